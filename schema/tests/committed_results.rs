//! Every committed `runs.csv` reads into typed rows, and every row's configuration id is recomputed from
//! its typed settings: the declaration reproduces the ids the results were recorded with.

use std::path::{Path, PathBuf};

fn committed_runs() -> Vec<PathBuf> {
    let results = Path::new(env!("CARGO_MANIFEST_DIR")).join("../results");
    let mut found = Vec::new();
    let mut stack = vec![results];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.file_name().is_some_and(|n| n == "runs.csv") {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

#[test]
fn committed_rows_parse_and_keep_their_configuration_ids() {
    let files = committed_runs();
    assert!(files.len() >= 6, "found {files:?}");
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let rows = schema::row::read_rows(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(rows.len(), text.lines().count() - 1, "{}", path.display());
        for row in &rows {
            let id = schema::row::config_id(&row.series, &row.settings());
            assert_eq!(id, row.config_id, "{}: {} {:?}", path.display(), row.series, row.settings());
        }
    }
}

#[test]
fn rows_round_trip_through_csv() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../results/baselines/ci/runs.csv");
    let text = std::fs::read_to_string(path).unwrap();
    let rows = schema::row::read_rows(&text).unwrap();
    let mut written = format!("{}\n", schema::row::header());
    for row in &rows {
        written.push_str(&schema::row::csv_line(row).unwrap());
    }
    assert_eq!(schema::row::read_rows(&written).unwrap(), rows);
}
