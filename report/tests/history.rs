//! The speedup history: append runs, refuse duplicates, plot with regressions marked.

use std::collections::BTreeMap;
use std::path::Path;

use report::spec::ReportSpec;

fn spec() -> ReportSpec {
    let fixed: Vec<String> = schema::row::setting_names().into_iter().filter(|c| !["objects", "seed"].contains(c)).map(String::from).collect();
    ReportSpec {
        name: "golden".into(),
        reference: Some("serial·list".into()),
        series: vec!["serial·list".into(), "serial·bvh".into()],
        series_fixed: BTreeMap::from([("serial·list".to_string(), fixed.clone()), ("serial·bvh".to_string(), fixed)]),
        ..Default::default()
    }
}

#[test]
fn appended_runs_are_plotted_with_regressions_marked() {
    let golden = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/runs.csv")).unwrap();
    let base = std::env::temp_dir().join(format!("bvhlab-history-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let (a, b, history) = (base.join("a"), base.join("b"), base.join("history"));
    for d in [&a, &b] {
        std::fs::create_dir_all(d).unwrap();
    }
    std::fs::write(a.join("runs.csv"), &golden).unwrap();
    // Run b: a later commit whose BVH is four times slower (trace_s and total_s ×4).
    let mut lines = golden.lines();
    let header = lines.next().unwrap();
    let cols: Vec<&str> = header.split(',').collect();
    let at = |n: &str| cols.iter().position(|c| *c == n).unwrap();
    let mut slow = format!("{header}\n");
    for l in lines {
        let mut f: Vec<String> = report_fields(l);
        if f[at("series")] == "serial·bvh" {
            for c in ["trace_s", "total_s"] {
                f[at(c)] = (f[at(c)].parse::<f64>().unwrap() * 4.0).to_string();
            }
        }
        f[at("git_commit")] = "fedcba9876543210fedcba9876543210fedcba98".into();
        f[at("timestamp")] = "2026-01-01T00:00:00Z".into();
        slow.push_str(&f.iter().map(|v| if v.contains(',') { format!("\"{v}\"") } else { v.clone() }).collect::<Vec<_>>().join(","));
        slow.push('\n');
    }
    std::fs::write(b.join("runs.csv"), slow).unwrap();
    let options = Default::default();
    let n = report::history::append(&a, &spec(), &history, &options).unwrap();
    assert!(n > 0);
    assert!(report::history::append(&a, &spec(), &history, &options).is_err(), "the same run is not appended twice");
    assert_eq!(report::history::append(&b, &spec(), &history, &options).unwrap(), n);
    let text = std::fs::read_to_string(history.join("history.csv")).unwrap();
    assert_eq!(text.lines().count(), 1 + 2 * n);
    assert!(text.contains("fedcba987654"));
    let files = report::history::plot(&history).unwrap();
    assert_eq!(files.len(), 3);
    let svg = std::fs::read_to_string(history.join("golden.svg")).unwrap();
    assert!(svg.contains("regression"), "the 4x slowdown is marked");
    assert!(std::fs::read_to_string(history.join("HISTORY.md")).unwrap().contains("| 2 | fedcba987654 |"));
    std::fs::remove_dir_all(&base).unwrap();
}

/// Splits one CSV line (quoted fields may hold commas).
fn report_fields(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted) = (Vec::new(), String::new(), false);
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cur)),
            c => cur.push(c),
        }
    }
    out.push(cur);
    out
}
