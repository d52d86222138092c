//! `report/ROWS.md`, the row contract, generated from the declaration (a test keeps the file in step).

use crate::columns::{Axis, COLUMNS, REPLACED};
use crate::row::{Kind, Role};

/// The whole text of ROWS.md.
pub fn text() -> String {
    let mut md = String::from(
        "# The row contract: `runs.csv`\n\n\
         Generated from `schema/src/columns.rs` (the one declaration of every setting and column); \
         `cargo test -p schema` fails when this file is out of step, and \
         `BVHLAB_WRITE_ROWS_MD=1 cargo test -p schema` rewrites it.\n\n\
         `harness run` appends one row per timed repetition to `<run dir>/runs.csv` (RFC 4180 CSV, header first, \
         `\\n` line ends, fields quoted only when they contain `,` `\"` or a line break), written and read through \
         one serde struct, `schema::Row`. Columns are read by name; a column recorded before a setting existed \
         takes that setting's default. Warm-up runs are not recorded.\n\n\
         | column | type | role | unit | meaning |\n|---|---|---|---|---|\n",
    );
    for c in COLUMNS {
        let kind = match c.kind {
            Kind::Text => "str",
            Kind::Int => "int",
            Kind::Float => "float",
            Kind::Bool => "bool",
        };
        let role = match c.role {
            Role::Identity => "identity",
            Role::Setting => "setting",
            Role::Metric => "metric",
            Role::Counter => "counter",
            Role::Provenance => "provenance",
            Role::Validation => "validation",
        };
        let mut meaning = c.doc.trim().to_string();
        if let Some(axis) = Axis::from_key(c.name) {
            meaning.push_str(&format!(" Allowed: {}.", axis.allowed()));
            if let Some(na) = axis.not_applicable() {
                meaning.push_str(&format!(" `{na}` where it does not apply."));
            }
        }
        md.push_str(&format!("| {} | {kind} | {role} | {} | {} |\n", c.name, c.unit, meaning.replace('|', "\\|")));
    }
    md.push_str(
        "\nRoles: *settings* are the axes of a sweep (a configuration is a series plus its settings); *metrics* vary \
         between repetitions; *counters* are deterministic — equal in every repetition and on every machine — and \
         are compared exactly by `harness check`; *provenance* says where and how the row was recorded.\n",
    );
    md.push_str("\nColumns of earlier row formats, read into the settings that replaced them:\n\n");
    for r in REPLACED {
        let by: Vec<String> = r.by.iter().map(|a| format!("`{}`", a.key())).collect();
        md.push_str(&format!("- `{}`: {}.\n", r.key, by.join(" and ")));
    }
    md
}

#[cfg(test)]
mod tests {
    #[test]
    fn report_rows_md_is_the_generated_contract() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../report/ROWS.md");
        let want = super::text();
        if std::env::var_os("BVHLAB_WRITE_ROWS_MD").is_some() {
            std::fs::write(&path, &want).unwrap();
        }
        let have = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            have == want,
            "{} is out of step with schema/src/columns.rs: run `BVHLAB_WRITE_ROWS_MD=1 cargo test -p schema`",
            path.display()
        );
    }
}
