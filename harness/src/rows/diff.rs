//! `harness rows-diff A B`: whether two row logs hold the same rows, in any order (e.g. a merged sharded sweep and
//! the same sweep unsharded).

use schema::column;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use schema::Role;
use schema::row::COLUMNS;

use crate::error::Error;
use crate::rows::read_log;
use crate::run::RUNS_CSV;

/// Provenance that differs from run to run of one build on one machine; ignored with the timings.
pub const PER_RUN: [&str; 6] =
    [column::load_avg_1m, column::timestamp, column::shard, column::slurm_job_id, column::node, column::process_id];

/// The columns compared: all, or all but the timings and [`PER_RUN`].
pub fn compared(ignore_timing: bool) -> Vec<&'static str> {
    COLUMNS
        .iter()
        .filter(|c| !ignore_timing || (c.role != Role::Metric && !PER_RUN.contains(&c.name)))
        .map(|c| c.name)
        .collect()
}

fn runs_csv(p: &Path) -> PathBuf {
    if p.is_dir() { p.join(RUNS_CSV) } else { p.to_path_buf() }
}

/// Rows keyed by `(config_id, repetition)`, each the text of the compared columns.
type Keyed = BTreeMap<(String, u32), Vec<Vec<String>>>;

fn keyed(path: &Path, columns: &[&str]) -> Result<(Keyed, usize), Error> {
    let rows = read_log(path)?;
    let mut out = Keyed::new();
    for r in &rows {
        let cells = columns.iter().map(|c| r.cell(c).map(|v| v.to_string()).unwrap_or_default()).collect();
        out.entry((r.config_id.clone(), r.repetition)).or_default().push(cells);
    }
    for v in out.values_mut() {
        v.sort();
    }
    Ok((out, rows.len()))
}

/// The differences between the rows of `a` and `b` over `columns`, one line each (empty: equal as multisets).
pub fn differences(a: &Path, b: &Path, columns: &[&str]) -> Result<(usize, usize, Vec<String>), Error> {
    let ((ka, na), (kb, nb)) = (keyed(a, columns)?, keyed(b, columns)?);
    let mut lines = Vec::new();
    for key in ka.keys().chain(kb.keys()).collect::<std::collections::BTreeSet<_>>() {
        let (ra, rb) = (ka.get(key).map_or(&[][..], |v| &v[..]), kb.get(key).map_or(&[][..], |v| &v[..]));
        let what = format!("configuration {} repetition {}", key.0, key.1);
        if ra.len() != rb.len() {
            lines.push(format!("{what}: {} rows in A, {} in B", ra.len(), rb.len()));
            continue;
        }
        for (x, y) in ra.iter().zip(rb) {
            let differing: Vec<String> = columns
                .iter()
                .enumerate()
                .filter(|(i, _)| x[*i] != y[*i])
                .map(|(i, c)| format!("{c} {:?} vs {:?}", x[i], y[i]))
                .collect();
            if !differing.is_empty() {
                lines.push(format!("{what}: {}", differing.join(", ")));
            }
        }
    }
    Ok((na, nb, lines))
}

/// `harness rows-diff`: prints whether the rows agree; exit 1 when they do not.
pub fn run(a: &Path, b: &Path, ignore_timing: bool) -> Result<(), Error> {
    let columns = compared(ignore_timing);
    let (a, b) = (runs_csv(a), runs_csv(b));
    let (na, nb, lines) = differences(&a, &b, &columns)?;
    let ignored = COLUMNS.len() - columns.len();
    if lines.is_empty() {
        say!("rows-diff: equal: {na} rows each, {} columns compared ({ignored} ignored), order ignored", columns.len());
        return Ok(());
    }
    for line in lines.iter().take(20) {
        say!("{line}");
    }
    if lines.len() > 20 {
        say!("... and {} more", lines.len() - 20);
    }
    Err(Error::Run(format!(
        "rows-diff: {} and {} differ ({na} vs {nb} rows; {} differences over {} columns)",
        a.display(),
        b.display(),
        lines.len(),
        columns.len()
    )))
}
