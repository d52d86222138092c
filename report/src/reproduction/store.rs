//! Storing reproductions: each one's `reproduction.json` and `REPRODUCTION.md` in its folder under the result set's
//! `reproductions/`, reading them back, and REPORT.md's section on them.

use std::path::Path;

use super::markdown::SECTION;
use super::{Reproduction, markdown, report_section};
use crate::error::Error;

/// The file a reproduction's verdict is written to, beside its rows (JSON; the site reads it).
pub const JSON: &str = "reproduction.json";
/// The same verdict for readers.
pub const MARKDOWN: &str = "REPRODUCTION.md";

/// The folder, under a result set, that holds its reproductions.
pub const FOLDER: &str = "reproductions";

impl Reproduction {
    /// Reads a reproduction's verdict from its folder.
    pub fn read(dir: &Path) -> Result<Reproduction, Error> {
        let path = dir.join(JSON);
        let text = std::fs::read_to_string(&path).map_err(|e| Error::read(&path, e))?;
        serde_json::from_str(&text).map_err(|e| Error::read(&path, e))
    }
}

/// The reproductions of the result set in `dir` (`reproductions/<name>/reproduction.json`), by folder name; a folder
/// without a verdict (still running, or stopped) is left out.
pub fn read_all(dir: &Path) -> Result<Vec<(String, Reproduction)>, Error> {
    let Ok(entries) = std::fs::read_dir(dir.join(FOLDER)) else { return Ok(Vec::new()) };
    let mut found: Vec<std::path::PathBuf> =
        entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.join(JSON).is_file()).collect();
    found.sort();
    found
        .iter()
        .map(|p| Ok((p.file_name().unwrap_or_default().to_string_lossy().into_owned(), Reproduction::read(p)?)))
        .collect()
}

/// Replaces REPORT.md's reproductions section in `dir` (or adds it at the end), leaving the rest of the report as
/// it is: what `harness reproduce` does to the result set it re-ran, whose rows it only reads.
pub fn update_report(dir: &Path) -> Result<(), Error> {
    let path = dir.join("REPORT.md");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::read(&path, e))?;
    let section = report_section(dir)?;
    let (before, after) = match text.find(&format!("\n{SECTION}\n")) {
        Some(start) => {
            let rest = &text[start + 1..];
            let end = rest[SECTION.len()..].find("\n## ").map_or(text.len(), |i| start + 1 + SECTION.len() + i + 1);
            (&text[..start + 1], &text[end..])
        }
        None => (text.as_str(), ""),
    };
    let mut out = before.to_string();
    if !section.is_empty() {
        if !out.ends_with("\n\n") {
            out.push('\n');
        }
        out.push_str(&section);
        if !after.is_empty() {
            out.push('\n');
        }
    }
    out.push_str(after);
    std::fs::write(&path, out).map_err(|e| Error::write(&path, e))
}

/// Writes `reproduction.json` and `REPRODUCTION.md` into `dir`.
pub fn write(dir: &Path, r: &Reproduction, title: &str, how: &[String]) -> Result<(), Error> {
    let json = dir.join(JSON);
    let text = serde_json::to_string_pretty(r).map_err(|e| Error::write(&json, e))?;
    std::fs::write(&json, text + "\n").map_err(|e| Error::write(&json, e))?;
    let md = dir.join(MARKDOWN);
    std::fs::write(&md, markdown(r, title, how)).map_err(|e| Error::write(&md, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reproduction::compare::tests::{claim, point};
    use crate::reproduction::{Origin, Outcome, PointOutcome, compare_claims};
    use crate::spec::Verdict;

    #[test]
    fn the_report_section_is_replaced_in_place_and_the_rest_of_the_report_kept() {
        let dir = std::env::temp_dir().join(format!("bvhlab-reproduction-section-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let at = dir.join(FOLDER).join("2026-12-04-abc");
        std::fs::create_dir_all(&at).unwrap();
        let old = claim(vec![point("1e3", 1.3, 1.2, 1.4, Verdict::Holds)]);
        let r = Reproduction {
            recorded_origin: Origin::default(),
            reproduced_origin: Origin { commits: vec!["0123456789abcdef".into()], ..Origin::default() },
            claims: compare_claims(std::slice::from_ref(&old), std::slice::from_ref(&old)),
            reference: None,
            points: vec![],
            deterministic_columns: vec![],
            configurations_compared: 3,
            not_comparable: vec![],
            only_recorded: 0,
            only_reproduced: 0,
            differences: vec![],
        };
        let nan = f64::NAN;
        let point = PointOutcome {
            series: "a".into(),
            point: "1e3".into(),
            recorded: [1.0, nan, nan],
            reproduced: [1.5, 1.4, 1.6],
            resolution: 0.02,
            outcome: Outcome::NotComparable,
        };
        let r = Reproduction { points: vec![point], ..r };
        write(&at, &r, "results/x", &[]).unwrap();
        let back = Reproduction::read(&at).unwrap();
        assert!(back.points[0].recorded[1].is_nan() && back.points[0].reproduced == [1.5, 1.4, 1.6], "{back:?}");
        let report = dir.join("REPORT.md");
        std::fs::write(&report, "# x\n\n## Claims\n\nA\n\n## Summary\n\nB\n").unwrap();
        update_report(&dir).unwrap();
        let once = std::fs::read_to_string(&report).unwrap();
        assert!(once.starts_with("# x\n\n## Claims\n\nA\n\n## Summary\n\nB\n\n## Reproductions\n"), "{once}");
        assert!(once.contains("| [2026-12-04-abc](reproductions/2026-12-04-abc/REPRODUCTION.md) | 0123456789ab |"));
        assert!(once.contains("| a is faster than b | **reproduced** (holds then, holds now) |"), "{once}");
        update_report(&dir).unwrap();
        assert_eq!(std::fs::read_to_string(&report).unwrap(), once, "updating twice changes nothing");
        // A section in the middle is replaced where it stands.
        let middle = once.replace("## Summary\n\nB\n\n", "") + "\n## Summary\n\nB\n";
        std::fs::write(&report, &middle).unwrap();
        update_report(&dir).unwrap();
        assert_eq!(std::fs::read_to_string(&report).unwrap(), middle);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
