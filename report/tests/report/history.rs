//! The speedup history: append runs, refuse duplicates, plot with regressions marked.

use crate::common;

use std::path::Path;

use report::spec::ReportSpec;

fn spec() -> ReportSpec {
    common::spec("golden", "serial·list", &["serial·list", "serial·bvh"])
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
        slow.push_str(
            &f.iter()
                .map(|v| if v.contains(',') { format!("\"{v}\"") } else { v.clone() })
                .collect::<Vec<_>>()
                .join(","),
        );
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

/// The texts of an SVG's `<text>` elements, with their opening tags.
fn svg_texts(svg: &str) -> Vec<(String, String)> {
    svg.split("<text")
        .skip(1)
        .map(|t| {
            let (tag, rest) = t.split_once('>').unwrap();
            (tag.to_string(), rest.split("</text>").next().unwrap().trim().to_string())
        })
        .collect()
}

#[test]
fn change_points_are_listed_and_marked_and_runs_are_ticked_by_commit() {
    // 16 runs of three tracked speedups (1% noise): `a` drops 20% at run 9, `b` stays flat, `c` holds an
    // outlier (3×) at run 3 and rises 10% at run 9.
    let mut rng = tracer::rng::SplitMix64::new(42);
    let commit = |i: usize| format!("{:012x}", 0x1f3a_5b7c_9d11u64.wrapping_mul(i as u64 + 1) & 0xffff_ffff_ffff);
    let mut csv = String::from("experiment,commit,dirty,timestamp,series,point,speedup,lower,upper,counters\n");
    for i in 0..16 {
        let levels = [
            ("a", if i < 8 { 50.0 } else { 40.0 }),
            ("b", 20.0),
            (
                "c",
                if i == 2 {
                    90.0
                } else if i < 8 {
                    30.0
                } else {
                    33.0
                },
            ),
        ];
        for (series, level) in levels {
            let v: f64 = level * (1.0 + 0.01 * rng.normal());
            csv.push_str(&format!(
                "ci,{},false,2026-12-{:02}T00:00:00Z,{series},objects 1000 (threads 1),{v},{},{},0123456789abcdef\n",
                commit(i),
                i + 1,
                v * 0.99,
                v * 1.01
            ));
        }
    }
    let dir = std::env::temp_dir().join(format!("bvhlab-history-changes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("history.csv"), csv).unwrap();
    report::history::plot(&dir).unwrap();

    let md = std::fs::read_to_string(dir.join("HISTORY.md")).unwrap();
    let rows: Vec<&str> = md.lines().filter(|l| l.contains(" → ") && l.starts_with("| 9 ")).collect();
    let ratio = |row: &str| row.split(" | ").nth(5).unwrap().parse::<f64>().unwrap();
    assert_eq!(rows.len(), 2, "{md}");
    assert!(rows[0].starts_with(&format!("| 9 | {} | a | objects 1000 (threads 1) | ", commit(8))), "{md}");
    assert!((ratio(rows[0]) - 0.8).abs() < 0.02, "{}", rows[0]);
    assert!(rows[1].starts_with(&format!("| 9 | {} | c | objects 1000 (threads 1) | ", commit(8))), "{md}");
    assert!((ratio(rows[1]) - 1.1).abs() < 0.03, "{}", rows[1]);

    let svg = std::fs::read_to_string(dir.join("ci.svg")).unwrap();
    let texts = svg_texts(&svg);
    assert!(texts.iter().any(|t| t.1.starts_with("change point")), "a legend entry for change points");
    assert!(texts.iter().any(|t| t.1.starts_with("regression")), "a legend entry for the 20% drop");
    // The x axis: ticks at whole runs only, labelled with their short commits (every other of the 16 runs).
    let size =
        texts.iter().find(|t| t.1 == commit(0)[..7]).map(|t| t.0.clone()).expect("run 1 is labelled with its commit");
    let x_labels: Vec<&str> = texts
        .iter()
        .filter(|t| t.0.contains("text-anchor=\"middle\"") && t.0.split("y=").nth(1) == size.split("y=").nth(1))
        .map(|t| t.1.as_str())
        .collect();
    let expected: Vec<String> = (0..16).step_by(2).map(|i| commit(i)[..7].to_string()).collect();
    assert_eq!(x_labels, expected);
    // Regression crosses are two-point strokes, never a line through several marks.
    let red: Vec<&str> = svg.lines().filter(|l| l.contains("<polyline") && l.contains("#C80000")).collect();
    assert_eq!(
        red.len(),
        3 * 2,
        "crosses at a's drop, at c's return from its outlier and in the legend, two strokes each: {red:?}"
    );
    assert!(
        red.iter()
            .all(|l| l.split("points=\"").nth(1).unwrap().split('"').next().unwrap().split_whitespace().count() == 2)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
