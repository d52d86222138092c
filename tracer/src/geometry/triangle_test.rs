use serde::{Deserialize, Serialize};

/// Which ray–triangle test [`super::Triangle::intersect`] runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TriangleTest {
    /// Möller and Trumbore (1997): Cramer's rule on the edge vectors; each triangle rounds its own edges.
    MollerTrumbore,
    /// Woop, Benthin and Wald (2013): edge functions in a sheared ray space, exact on shared edges.
    Watertight,
}

impl TriangleTest {
    /// Every test, in the order tools list them.
    pub const ALL: [TriangleTest; 2] = [TriangleTest::MollerTrumbore, TriangleTest::Watertight];

    /// The kebab-case name used in configs and on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            TriangleTest::MollerTrumbore => "moller-trumbore",
            TriangleTest::Watertight => "watertight",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_the_serialized_names() {
        for test in TriangleTest::ALL {
            let json = serde_json::to_string(&test).unwrap();
            assert_eq!(json, format!("\"{}\"", test.name()));
        }
    }
}
