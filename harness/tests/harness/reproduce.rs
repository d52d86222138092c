//! `harness reproduce`: a small result set recorded here, re-run with today's code, judged; a tampered counter is a
//! difference; mixed commits, an unknown commit and uncommitted code are one line, exit 2, and write nothing.

use std::path::Path;

use tracer::accel::AccelKind;

use crate::common::{harness, stderr, temp};

/// Rewrites column `name` of every row of a runs.csv with `f(row index, old value)`.
fn rewrite(runs: &Path, name: &str, f: impl Fn(usize, &str) -> String) {
    let mut reader = csv::Reader::from_path(runs).unwrap();
    let header = reader.headers().unwrap().clone();
    let at = header.iter().position(|h| h == name).unwrap();
    let rows: Vec<csv::StringRecord> = reader.records().map(Result::unwrap).collect();
    let mut writer = csv::Writer::from_path(runs).unwrap();
    writer.write_record(&header).unwrap();
    for (i, row) in rows.iter().enumerate() {
        let cells: Vec<String> =
            row.iter().enumerate().map(|(j, c)| if j == at { f(i, c) } else { c.to_string() }).collect();
        writer.write_record(&cells).unwrap();
    }
    writer.flush().unwrap();
}

fn copy_set(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for file in ["runs.csv", "experiment.toml"] {
        std::fs::copy(from.join(file), to.join(file)).unwrap();
    }
}

#[test]
fn a_result_set_reproduces_at_head_and_a_changed_counter_does_not() {
    let dir = temp("head");
    let cfg = dir.join("small.toml");
    let (list, flat) = (AccelKind::List.name(), AccelKind::FlatBvh.name());
    std::fs::write(
        &cfg,
        format!(
            "name = \"small\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nreference = \"brute\"\nrepetitions = 6\n[sweep]\nobjects = [100, 300]\nwidth = 48\n\
             height = 32\nworkload = \"primary\"\n[[series]]\nlabel = \"brute\"\naccel = \"{list}\"\n[[series]]\n\
             label = \"tree\"\naccel = \"{flat}\"\n[[claim]]\ntext = \"the BVH beats the list\"\nkind = \"faster\"\n\
             series = \"tree\"\nthan = \"brute\"\nfactor = 1\n"
        ),
    )
    .unwrap();
    let set = dir.join("small");
    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", set.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let recorded = std::fs::read(set.join("runs.csv")).unwrap();

    // Two runs seconds apart are not a timing experiment: the times are judged (and printed) for information, so
    // that this test fails only on what must be exact.
    let o = harness()
        .args(["reproduce", set.to_str().unwrap(), "--at", "HEAD", "--timings-for-information"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{stdout}\n{}", stderr(&o));
    assert!(stdout.contains("deterministic columns: 4 configurations compared, 0 differences"), "{stdout}");
    // Its verdicts are timings (not asserted here); that the claim was judged on the points both ran is.
    assert!(stdout.contains("the BVH beats the list (then "), "{stdout}");
    assert_eq!(std::fs::read(set.join("runs.csv")).unwrap(), recorded, "the recorded rows are only read");
    let made: Vec<_> = std::fs::read_dir(set.join("reproductions")).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(made.len(), 1);
    assert!(made[0].file_name().unwrap().to_string_lossy().ends_with("-head"), "{made:?}");
    let md = std::fs::read_to_string(made[0].join("REPRODUCTION.md")).unwrap();
    assert!(md.contains("every compared column identical") && md.contains("## Claims"), "{md}");
    let report = std::fs::read_to_string(set.join("REPORT.md")).unwrap();
    assert!(report.contains("## Reproductions") && report.contains("/REPRODUCTION.md) |"), "{report}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(made[0].join("reproduction.json")).unwrap()).unwrap();
    assert_eq!(json["configurations_compared"], 4, "{json}");
    assert_eq!(json["differences"].as_array().map(Vec::len), Some(0), "{json}");
    assert_eq!(json["points"].as_array().map(Vec::len), Some(2), "tree against brute at 100 and 300: {json}");
    assert_ne!(json["claims"][0]["outcome"], "not-comparable", "{json}");

    // The same rows with one counter changed: listed, and the reproduction fails (exit 1).
    let tampered = dir.join("tampered");
    copy_set(&set, &tampered);
    rewrite(&tampered.join("runs.csv"), "tree_nodes", |_, old| {
        if old == "0" { old.to_string() } else { (old.parse::<u64>().unwrap() + 1).to_string() }
    });
    let o = harness()
        .args(["reproduce", tampered.to_str().unwrap(), "--at", "HEAD", "--timings-for-information"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(o.status.code(), Some(1), "{stdout}\n{}", stderr(&o));
    assert!(stdout.contains("differs: tree") && stdout.contains("tree_nodes"), "{stdout}");
}

#[test]
fn a_result_set_of_mixed_or_unknown_commits_is_refused_with_one_line() {
    let dir = temp("refused");
    let cfg = dir.join("tiny.toml");
    std::fs::write(
        &cfg,
        format!(
            "name = \"tiny\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nrepetitions = 2\n[sweep]\nobjects = 50\nwidth = 16\nheight = 16\nworkload = \"primary\"\n\
             [[series]]\nlabel = \"tree\"\naccel = \"{}\"\n",
            AccelKind::FlatBvh.name()
        ),
    )
    .unwrap();
    let set = dir.join("tiny");
    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", set.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let refused = |case: &str, edit: &dyn Fn(&Path), want: &str| {
        let copy = dir.join(case);
        copy_set(&set, &copy);
        edit(&copy.join("runs.csv"));
        let o = harness().args(["reproduce", copy.to_str().unwrap()]).output().unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{case}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{case}: one line: {err}");
        assert!(err.contains(want) && err.contains("runs.csv"), "{case}: {err}");
        assert!(!copy.join("reproductions").exists(), "{case}: nothing written");
    };
    let fake = "0123456789abcdef0123456789abcdef01234567";
    refused(
        "mixed",
        &|runs| rewrite(runs, "git_commit", |i, old| if i == 0 { fake.into() } else { old.into() }),
        "mix 2 commits",
    );
    refused(
        "unknown",
        &|runs| {
            rewrite(runs, "git_commit", |_, _| fake.into());
            rewrite(runs, "git_dirty", |_, _| "false".into());
        },
        "is not a commit of this repository",
    );
    refused("dirty", &|runs| rewrite(runs, "git_dirty", |_, _| "true".into()), "uncommitted changes");
    let o = harness().args(["reproduce", dir.to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a result set"), "{}", stderr(&o));
}
