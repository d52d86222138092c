//! Recorded rows: one per timed repetition, appended to `runs.csv` and flushed as each run finishes.
//!
//! The column contract is `report/ROWS.md`. A sweep killed at any point leaves complete lines plus at most
//! one partial last line; [`RowLog::resume`] cuts that line off and reports which runs are done.

use std::collections::HashSet;
use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::Path;

pub use report::csv::{field as csv_field, split_line as split_csv_line};

/// Column names, in order (see `report/ROWS.md`).
pub const COLUMNS: &[&str] = &[
    "experiment", "config_id", "series", "repetition", "scene", "objects", "seed", "accel", "split", "leaf_size",
    "sah_bins", "traversal", "strategy", "threads", "width", "height", "max_depth", "workload", "obvhs_build",
    "embree_build", "embree_isa", "scene_s", "build_s",
    "trace_s", "encode_s", "total_s", "rays", "mrays_per_s", "nodes_per_ray", "box_tests_per_ray",
    "prim_tests_per_ray", "tree_nodes", "tree_leaves", "tree_depth", "tree_bytes", "sah_cost", "image_hash",
    "scene_fingerprint", "git_commit", "git_dirty", "rustc", "cpu_model", "logical_cores", "load_avg_1m", "timestamp",
    "harness_version", "validation", "validated_against", "mismatches", "peer_info",
];

/// The append-only row log of one run folder.
pub struct RowLog {
    file: File,
}

impl RowLog {
    /// Starts a new log at `path` (replacing any old one) with the header line.
    pub fn create(path: &Path) -> io::Result<Self> {
        let mut file = File::create(path)?;
        file.write_all(format!("{}\n", COLUMNS.join(",")).as_bytes())?;
        file.flush()?;
        Ok(Self { file })
    }

    /// Opens an existing log for appending: drops a partial last line, checks the header, and returns the
    /// `(config_id, repetition)` pairs already recorded.
    pub fn resume(path: &Path) -> io::Result<(Self, HashSet<(String, u32)>)> {
        let mut file = OpenOptions::new().read(true).write(true).open(path)?;
        let mut text = String::new();
        file.read_to_string(&mut text)?;
        let complete = text.rfind('\n').map_or(0, |i| i + 1);
        if complete < text.len() {
            file.set_len(complete as u64)?;
        }
        file.seek(SeekFrom::End(0))?;
        let mut lines = text[..complete].lines();
        let header = lines.next().unwrap_or_default();
        if header != COLUMNS.join(",") {
            return Err(io::Error::new(io::ErrorKind::InvalidData, "its header is not this harness's column list"));
        }
        let (id, rep) = (1, 3);
        let done = lines
            .map(split_csv_line)
            .filter_map(|f| Some((f.get(id)?.clone(), f.get(rep)?.parse().ok()?)))
            .collect();
        Ok((Self { file }, done))
    }

    /// Appends one row (values in [`COLUMNS`] order) as a single write, then flushes.
    pub fn append(&mut self, values: &[String]) -> io::Result<()> {
        debug_assert_eq!(values.len(), COLUMNS.len());
        let line: Vec<String> = values.iter().map(|v| csv_field(v)).collect();
        self.file.write_all(format!("{}\n", line.join(",")).as_bytes())?;
        self.file.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trips_quotes_and_commas() {
        let fields = ["plain", "a,b", "say \"hi\"", "serial·list", ""];
        let line: Vec<String> = fields.iter().map(|f| csv_field(f)).collect();
        assert_eq!(split_csv_line(&line.join(",")), fields);
    }

    #[test]
    fn resume_drops_a_partial_line_and_lists_done_runs() {
        let dir = std::env::temp_dir().join(format!("bvhlab-rows-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("runs.csv");
        let mut log = RowLog::create(&path).unwrap();
        let mut row: Vec<String> = COLUMNS.iter().map(|_| "0".to_string()).collect();
        row[1] = "abc".into();
        row[3] = "2".into();
        log.append(&row).unwrap();
        drop(log);
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(b"exp,def,series,0,random-sph").unwrap(); // killed mid-line
        drop(f);
        let (mut log, done) = RowLog::resume(&path).unwrap();
        assert_eq!(done, HashSet::from([("abc".to_string(), 2)]));
        row[1] = "def".into();
        log.append(&row).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 3);
        assert!(text.lines().all(|l| split_csv_line(l).len() == COLUMNS.len()));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
