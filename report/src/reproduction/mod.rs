//! Whether a re-run of a recorded result set reproduces it: the deterministic columns of every configuration both
//! ran (identical where the kernel, or for a peer library the ISA, is the same), every series' time ratio to the
//! experiment's reference at every point, and every claim, judged within the harness's resolution.
//!
//! Times of two machines are never compared as such: only ratios of two series timed in the same rounds on one
//! machine, the recorded ratio against the reproduced one.
//!
//! [`compare()`] computes a [`Reproduction`] from the two folders' rows (module `compare`, with [`compare_claims`] and
//! [`point_outcome`]); [`markdown()`] renders it as `REPRODUCTION.md` and [`report_section`] the result set's
//! REPORT.md section on its reproductions (module `markdown`); [`write`], [`Reproduction::read`], [`read_all`] and
//! [`update_report`] store and read them (module `store`).

mod compare;
mod markdown;
mod store;

use schema::column;
use serde::{Deserialize, Serialize};

use crate::rows::{Rows, Run};

pub use compare::{compare, compare_claims, point_outcome};
pub use markdown::{markdown, report_section};
pub use store::{FOLDER, JSON, MARKDOWN, read_all, update_report, write};

/// The smallest change of a time ratio the harness resolves at one thread (`results/resolution`'s A/A
/// experiment): a ratio that moved by at most this much reproduced.
pub const RESOLUTION_ONE_THREAD: f64 = 0.02;
/// The same on all cores.
pub const RESOLUTION_ALL_CORES: f64 = 0.04;

/// A commit's first 12 digits (all of a shorter text, e.g. `unknown`).
pub fn short_commit(commit: &str) -> &str {
    &commit[..commit.len().min(12)]
}

/// The resolution at a point where at most `threads` worker threads ran.
pub fn resolution(threads: f64) -> f64 {
    if threads <= 1.0 { RESOLUTION_ONE_THREAD } else { RESOLUTION_ALL_CORES }
}

/// What a comparison found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Outcome {
    /// The same answer, within the resolution.
    Reproduced,
    /// A different answer.
    NotReproduced,
    /// Nothing to compare (a series or point missing here, another kernel or ISA).
    NotComparable,
}

impl Outcome {
    /// The outcome in words.
    pub fn word(self) -> &'static str {
        match self {
            Outcome::Reproduced => "reproduced",
            Outcome::NotReproduced => "not reproduced",
            Outcome::NotComparable => "not comparable",
        }
    }
}

/// Where a result set came from: its rows' commit and machine.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Origin {
    /// The commits of the rows (one for a result set that can be reproduced).
    pub commits: Vec<String>,
    /// The machines, as `cpu_model (machine_id)`.
    pub machines: Vec<String>,
    /// Rows timed, and rows that failed validation.
    pub rows: usize,
    /// Rows that failed validation.
    pub failed: usize,
}

impl Origin {
    fn of(rows: &Rows) -> Origin {
        let all = || rows.runs.iter().chain(&rows.failed);
        Origin {
            commits: crate::distinct(all().map(|r| r.text(column::git_commit).to_string())),
            machines: crate::distinct(all().map(Run::machine)),
            rows: rows.runs.len(),
            failed: rows.failed.len(),
        }
    }
}

/// A claim, recorded and reproduced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClaimOutcome {
    /// The claim in words.
    pub text: String,
    /// Its verdict then and now, over the points both ran (`holds`, `fails`, `inconclusive`).
    pub recorded: String,
    /// The same, reproduced.
    pub reproduced: String,
    /// The outcome.
    pub outcome: Outcome,
    /// Why, in one line.
    pub reason: String,
}

/// A series' time ratio to the reference at one point, recorded and reproduced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointOutcome {
    /// The series.
    pub series: String,
    /// The point, as claims name it.
    pub point: String,
    /// Recorded ratio `metric(reference) / metric(series)` and its 95% interval (null: none).
    #[serde(with = "nan_as_null")]
    pub recorded: [f64; 3],
    /// Reproduced ratio and interval.
    #[serde(with = "nan_as_null")]
    pub reproduced: [f64; 3],
    /// The resolution the point is judged with.
    pub resolution: f64,
    /// The outcome.
    pub outcome: Outcome,
}

/// JSON has no NaN: a ratio or interval end that is not a number (no interval below six runs) is written as null
/// and read back as NaN.
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(values: &[f64; 3], s: S) -> Result<S::Ok, S::Error> {
        values.map(|v| v.is_finite().then_some(v)).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
        Ok(<[Option<f64>; 3]>::deserialize(d)?.map(|v| v.unwrap_or(f64::NAN)))
    }
}

/// Everything a reproduction found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reproduction {
    /// The result set as recorded.
    pub recorded_origin: Origin,
    /// The reproduction.
    pub reproduced_origin: Origin,
    /// Every claim of the experiment.
    pub claims: Vec<ClaimOutcome>,
    /// The reference series the times are compared against (none: no time comparison).
    pub reference: Option<String>,
    /// Every series' ratio to the reference at every point both ran.
    pub points: Vec<PointOutcome>,
    /// The deterministic columns compared.
    pub deterministic_columns: Vec<String>,
    /// Configurations whose deterministic columns were compared.
    pub configurations_compared: usize,
    /// Configurations both ran but that are not comparable, one line per series and reason.
    pub not_comparable: Vec<String>,
    /// Configurations recorded but not run here, and run here but not recorded.
    pub only_recorded: usize,
    /// See `only_recorded`.
    pub only_reproduced: usize,
    /// Every deterministic difference, one line each.
    pub differences: Vec<String>,
}

impl Reproduction {
    /// The verdict: every deterministic column the same, no claim and no point not reproduced.
    pub fn outcome(&self) -> Outcome {
        let moved = self.claims.iter().any(|c| c.outcome == Outcome::NotReproduced)
            || self.points.iter().any(|p| p.outcome == Outcome::NotReproduced)
            || !self.differences.is_empty();
        // With claims, it reproduced only when every claim did; without, when something was compared.
        let reproduced = if self.claims.is_empty() {
            self.configurations_compared > 0 || self.points.iter().any(|p| p.outcome == Outcome::Reproduced)
        } else {
            self.claims.iter().all(|c| c.outcome == Outcome::Reproduced)
        };
        match (moved, reproduced) {
            (true, _) => Outcome::NotReproduced,
            (false, true) => Outcome::Reproduced,
            (false, false) => Outcome::NotComparable,
        }
    }

    /// The verdict with each part named: claims, deterministic columns and time ratios, e.g. "not comparable: claims
    /// 1 of 4 reproduced, 3 not comparable; deterministic columns not compared; time ratios 4 of 20 reproduced, 16
    /// not comparable".
    pub fn headline(&self) -> String {
        let tally = |what: &str, outcomes: Vec<Outcome>| {
            let n = |o: Outcome| outcomes.iter().filter(|&&x| x == o).count();
            let mut parts = vec![format!("{} of {} reproduced", n(Outcome::Reproduced), outcomes.len())];
            for (o, word) in [(Outcome::NotReproduced, "not reproduced"), (Outcome::NotComparable, "not comparable")] {
                if n(o) > 0 {
                    parts.push(format!("{} {word}", n(o)));
                }
            }
            if outcomes.is_empty() { format!("no {what}") } else { format!("{what} {}", parts.join(", ")) }
        };
        let claims = tally("claims", self.claims.iter().map(|c| c.outcome).collect());
        let deterministic = match (self.configurations_compared, self.differences.len()) {
            (0, _) => "deterministic columns not compared (no configuration ran both times alike)".to_string(),
            (n, 0) => format!("deterministic columns reproduced ({n} configurations)"),
            (n, d) => format!("deterministic columns differ in {d} of {n} configurations"),
        };
        let times = tally("time ratios", self.points.iter().map(|p| p.outcome).collect());
        format!("{}: {claims}; {deterministic}; {times}", self.outcome().word())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn claim(outcome: Outcome) -> ClaimOutcome {
        ClaimOutcome { text: "c".into(), recorded: "-".into(), reproduced: "-".into(), outcome, reason: String::new() }
    }

    fn point(outcome: Outcome) -> PointOutcome {
        PointOutcome {
            series: "s".into(),
            point: "p".into(),
            recorded: [1.0; 3],
            reproduced: [1.0; 3],
            resolution: 0.02,
            outcome,
        }
    }

    fn reproduction(claims: Vec<ClaimOutcome>, points: Vec<PointOutcome>, compared: usize) -> Reproduction {
        Reproduction {
            recorded_origin: Origin::default(),
            reproduced_origin: Origin::default(),
            claims,
            reference: None,
            points,
            deterministic_columns: Vec::new(),
            configurations_compared: compared,
            not_comparable: Vec::new(),
            only_recorded: 0,
            only_reproduced: 0,
            differences: Vec::new(),
        }
    }

    #[test]
    fn reproduced_only_when_every_claim_is_and_the_headline_names_each_part() {
        use Outcome::{NotComparable, NotReproduced, Reproduced};
        // A quick run: one claim reproduced, three not comparable, nothing deterministic compared.
        let quick = reproduction(
            vec![claim(Reproduced), claim(NotComparable), claim(NotComparable), claim(NotComparable)],
            vec![point(Reproduced), point(NotComparable)],
            0,
        );
        assert_eq!(quick.outcome(), NotComparable);
        assert_eq!(
            quick.headline(),
            "not comparable: claims 1 of 4 reproduced, 3 not comparable; deterministic columns not compared (no \
             configuration ran both times alike); time ratios 1 of 2 reproduced, 1 not comparable"
        );
        let full = reproduction(vec![claim(Reproduced); 4], vec![point(Reproduced); 55], 162);
        assert_eq!(full.outcome(), Reproduced);
        assert!(
            full.headline().contains("deterministic columns reproduced (162 configurations)"),
            "{}",
            full.headline()
        );
        let moved = reproduction(vec![claim(Reproduced)], vec![point(NotReproduced)], 3);
        assert_eq!(moved.outcome(), NotReproduced);
        let no_claims = reproduction(Vec::new(), Vec::new(), 21);
        assert_eq!(no_claims.outcome(), Reproduced, "without claims, the deterministic columns decide");
    }
}
