//! Rendering a [`Reproduction`]: its `REPRODUCTION.md`, and the section of the result set's REPORT.md on all its
//! reproductions.

use std::path::Path;

use super::{
    FOLDER, MARKDOWN, Origin, Outcome, PointOutcome, RESOLUTION_ALL_CORES, RESOLUTION_ONE_THREAD, Reproduction,
    read_all, short_commit,
};
use crate::error::Error;

/// REPRODUCTION.md: the verdict first, then the claims, the deterministic columns and the moved ratios. `how`
/// says what was run (command, commit, date).
pub fn markdown(r: &Reproduction, title: &str, how: &[String]) -> String {
    let origin = |o: &Origin| {
        format!(
            "commit {}, machine {}, {} rows{}",
            o.commits.iter().map(|c| format!("`{}`", short_commit(c))).collect::<Vec<_>>().join(", "),
            o.machines.join(", "),
            o.rows,
            if o.failed > 0 { format!(" ({} failed validation)", o.failed) } else { String::new() }
        )
    };
    let points = |outcome: Outcome| r.points.iter().filter(|p| p.outcome == outcome).count();
    let mut md = format!("# Reproduction of {title}\n\n");
    for line in how {
        md.push_str(&format!("- {line}\n"));
    }
    let verdict = r.headline();
    let (word, rest) = verdict.split_once(": ").unwrap_or((&verdict, ""));
    md.push_str(&format!(
        "- recorded: {}\n- reproduced: {}\n\n**{word}**: {rest}.\n\n",
        origin(&r.recorded_origin),
        origin(&r.reproduced_origin),
    ));
    md.push_str(&format!(
        "A time ratio (a series' time against the reference's, or a claim's, at one point) reproduced when it moved by \
         at most the harness's resolution (±{:.0}% at one thread, ±{:.0}% on more; `results/resolution`) or when its \
         recorded and reproduced 95% intervals overlap. Deterministic columns (tree statistics, counters per ray, \
         hashes, validation) must be identical where the SIMD kernel (our structures) or the ISA (peer libraries) is \
         the same. Absolute times of two machines are never compared.\n\n",
        RESOLUTION_ONE_THREAD * 100.0,
        RESOLUTION_ALL_CORES * 100.0
    ));
    if !r.claims.is_empty() {
        md.push_str("## Claims\n\n| claim | then | now | outcome | why |\n|---|---|---|---|---|\n");
        for c in &r.claims {
            md.push_str(&format!(
                "| {} | {} | {} | **{}** | {} |\n",
                c.text.replace('|', "\\|"),
                c.recorded,
                c.reproduced,
                c.outcome.word(),
                c.reason.replace('|', "\\|")
            ));
        }
        md.push('\n');
    }
    md.push_str(&format!(
        "## Deterministic columns\n\n{} configurations compared on {} columns ({}); {} recorded only, {} reproduced \
         only.\n\n",
        r.configurations_compared,
        r.deterministic_columns.len(),
        r.deterministic_columns.iter().map(|c| format!("`{c}`")).collect::<Vec<_>>().join(", "),
        r.only_recorded,
        r.only_reproduced
    ));
    for line in &r.not_comparable {
        md.push_str(&format!("- not comparable: {line}\n"));
    }
    if r.differences.is_empty() {
        md.push_str("- every compared column identical\n");
    }
    for line in &r.differences {
        md.push_str(&format!("- **differs**: {line}\n"));
    }
    if let Some(reference) = &r.reference {
        md.push_str(&format!(
            "\n## Times against {reference}\n\n{} of {} ratios reproduced; {} moved beyond the resolution without an \
             interval on one side to judge them by (not comparable). ",
            points(Outcome::Reproduced),
            r.points.len(),
            points(Outcome::NotComparable)
        ));
        let moved: Vec<&PointOutcome> = r.points.iter().filter(|p| p.outcome == Outcome::NotReproduced).collect();
        if moved.is_empty() {
            md.push_str("None moved beyond the resolution and its intervals.\n");
        } else {
            md.push_str("Those that moved:\n\n| series | point | then | now | resolution |\n|---|---|---|---|---|\n");
            for p in moved {
                let e = |v: [f64; 3]| format!("{:.3} [{:.3}, {:.3}]", v[0], v[1], v[2]);
                md.push_str(&format!(
                    "| {} | {} | {} | {} | ±{:.0}% |\n",
                    p.series,
                    p.point,
                    e(p.recorded),
                    e(p.reproduced),
                    p.resolution * 100.0
                ));
            }
        }
    }
    md
}

/// The heading of REPORT.md's section on the result set's reproductions.
pub(super) const SECTION: &str = "## Reproductions";

/// REPORT.md's section on the reproductions of the result set in `dir`: one line each, then every claim's outcome
/// in each (empty when there are none).
pub fn report_section(dir: &Path) -> Result<String, Error> {
    let all = read_all(dir)?;
    if all.is_empty() {
        return Ok(String::new());
    }
    let mut md = format!(
        "{SECTION}\n\nRe-runs of this result set by `harness reproduce` (docs/reproduction.md), each in \
         `{FOLDER}/<name>/` with its rows, report and `{MARKDOWN}`.\n\n| reproduction | code | machine | verdict | \
         claims reproduced / not / not comparable | deterministic differences | time ratios reproduced |\n\
         |---|---|---|---|---|---|---|\n"
    );
    for (name, r) in &all {
        let claims = |o: Outcome| r.claims.iter().filter(|c| c.outcome == o).count();
        let commits: Vec<&str> = r.reproduced_origin.commits.iter().map(|c| short_commit(c)).collect();
        md.push_str(&format!(
            "| [{name}]({FOLDER}/{name}/{MARKDOWN}) | {} | {} | **{}** | {} / {} / {} | {} of {} configurations | {} of {} |\n",
            commits.join(", "),
            r.reproduced_origin.machines.join(", "),
            r.outcome().word(),
            claims(Outcome::Reproduced),
            claims(Outcome::NotReproduced),
            claims(Outcome::NotComparable),
            r.differences.len(),
            r.configurations_compared,
            r.points.iter().filter(|p| p.outcome == Outcome::Reproduced).count(),
            r.points.len()
        ));
    }
    let texts: Vec<&str> = crate::distinct(all.iter().flat_map(|(_, r)| r.claims.iter().map(|c| c.text.as_str())));
    if !texts.is_empty() {
        md.push_str(&format!(
            "\n| claim | {} |\n|---|{}\n",
            all.iter().map(|(name, _)| name.as_str()).collect::<Vec<_>>().join(" | "),
            "---|".repeat(all.len())
        ));
        for text in texts {
            let cells: Vec<String> = all
                .iter()
                .map(|(_, r)| {
                    r.claims.iter().find(|c| c.text == text).map_or("—".into(), |c| {
                        format!("**{}** ({} then, {} now)", c.outcome.word(), c.recorded, c.reproduced)
                    })
                })
                .collect();
            md.push_str(&format!("| {} | {} |\n", text.replace('|', "\\|"), cells.join(" | ")));
        }
    }
    Ok(md)
}
