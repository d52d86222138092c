//! The per-commit history that `harness history backfill` records: one line per visited commit
//! (`commits.csv`: recorded, or why not) and one line per counted configuration of each recorded commit
//! (`instructions.csv`: callgrind instruction counts of the build and the trace, the answer hash and the tree's
//! shape, and trace and build times when asked for). Instruction counts do not wander from run to run, so the
//! tracks read from these files need no intervals: every change of level is the code's.

use std::collections::BTreeMap;
use std::fs;
use std::io::Write as _;
use std::path::Path;

use super::change_points::{self, ChangePoint};
use crate::error::Error;
use crate::stats::seed_for;

/// The file of visited commits, in a history folder.
pub const COMMITS_CSV: &str = "commits.csv";
/// The file of counted configurations, in a history folder.
pub const INSTRUCTIONS_CSV: &str = "instructions.csv";

/// A rise of an instruction count by more than this fraction from the previous recorded commit is a
/// regression (the threshold of `harness check`'s instruction gate).
pub const REGRESSION: f64 = 0.02;

/// One visited commit: a line of `commits.csv`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CommitEntry {
    /// The full commit hash.
    pub commit: String,
    /// Its place on the first-parent line of the branch backfilled (0: that line's first commit).
    pub position: u32,
    /// Committer date, ISO 8601.
    pub date: String,
    /// The first line of the commit message.
    pub subject: String,
    /// `recorded`, or `build failed` (visited once; backfill does not try it again).
    pub status: String,
    /// The compiler that built it (`rustc -V`).
    pub compiler: String,
    /// Configurations counted.
    pub counted: u32,
    /// Configurations of the suite this revision could not run, `series point: why`, separated by ` · `.
    pub skipped: String,
}

/// One counted configuration of one commit: a line of `instructions.csv`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CountedEntry {
    /// The full commit hash.
    pub commit: String,
    /// The suite (experiment name).
    pub experiment: String,
    pub series: String,
    /// The configuration's point, as the speedup history names it, e.g. `objects 1000 (threads 1)`.
    pub point: String,
    /// The configuration id in today's suite.
    pub config_id: String,
    pub build_instructions: u64,
    pub trace_instructions: u64,
    /// The answer hash the revision's worker reported (16 hex digits).
    pub output_hash: String,
    pub nodes: u64,
    pub leaves: u64,
    pub depth: u64,
    pub tree_bytes: u64,
    pub sah_cost: f64,
    /// Median trace seconds when times were taken (`--timings`), else empty.
    pub trace_s: Option<f64>,
    /// Median build seconds when times were taken, else empty.
    pub build_s: Option<f64>,
    /// The machine of the times (empty without them).
    pub machine_id: String,
}

fn read_csv<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Vec<T>, Error> {
    let Ok(text) = std::fs::read_to_string(path) else { return Ok(vec![]) };
    csv::Reader::from_reader(text.as_bytes())
        .deserialize()
        .collect::<Result<Vec<T>, _>>()
        .map_err(|e| Error::Mismatch { path: path.into(), message: format!("malformed history: {e}") })
}

/// The visited commits of `history_dir`, in first-parent order (empty when none was recorded).
pub fn read_commits(history_dir: &Path) -> Result<Vec<CommitEntry>, Error> {
    let mut commits: Vec<CommitEntry> = read_csv(&history_dir.join(COMMITS_CSV))?;
    commits.sort_by_key(|c| c.position);
    Ok(commits)
}

/// The counted configurations of `history_dir`.
pub fn read_counted(history_dir: &Path) -> Result<Vec<CountedEntry>, Error> {
    read_csv(&history_dir.join(INSTRUCTIONS_CSV))
}

/// Which phase's instruction count a track follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Phase {
    Build,
    Trace,
}

impl Phase {
    /// `build` or `trace`.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Build => "build",
            Phase::Trace => "trace",
        }
    }
}

/// One commit's count on a track.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackPoint {
    /// Index into the commits given to [`instruction_tracks`] (first-parent order).
    pub commit: usize,
    pub instructions: u64,
    /// More than [`REGRESSION`] above the previous point of the track.
    pub regression: bool,
    /// The answer hash differs from the previous point's.
    pub answers_changed: bool,
}

/// The instruction count of one phase of one configuration over the recorded commits.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    pub experiment: String,
    pub series: String,
    pub point: String,
    pub phase: Phase,
    pub points: Vec<TrackPoint>,
    /// Changes of level ([`change_points::detect`] with [`change_points::DEFAULT`]); `index` is into `points`.
    pub change_points: Vec<ChangePoint>,
}

/// Counted entries by (experiment, series, point), each with its commit's position in the commit list.
type ByConfig<'a> = BTreeMap<(&'a str, &'a str, &'a str), Vec<(usize, &'a CountedEntry)>>;

/// Every (configuration, phase) track of the counted entries over `commits` (as [`read_commits`] returns them),
/// sorted by experiment, series, point and phase; a commit not in `commits` is left out.
pub fn instruction_tracks(commits: &[CommitEntry], counted: &[CountedEntry]) -> Vec<Track> {
    let position: BTreeMap<&str, usize> = commits.iter().enumerate().map(|(i, c)| (c.commit.as_str(), i)).collect();
    let mut by_config: ByConfig = BTreeMap::new();
    for e in counted {
        if let Some(&i) = position.get(e.commit.as_str()) {
            by_config.entry((&e.experiment, &e.series, &e.point)).or_default().push((i, e));
        }
    }
    let mut tracks = Vec::new();
    for ((experiment, series, point), mut entries) in by_config {
        entries.sort_by_key(|(i, _)| *i);
        entries.dedup_by_key(|(i, _)| *i);
        for phase in [Phase::Build, Phase::Trace] {
            let count = |e: &CountedEntry| match phase {
                Phase::Build => e.build_instructions,
                Phase::Trace => e.trace_instructions,
            };
            let points: Vec<TrackPoint> = entries
                .iter()
                .enumerate()
                .map(|(k, (i, e))| {
                    let before = k.checked_sub(1).map(|k| entries[k].1);
                    TrackPoint {
                        commit: *i,
                        instructions: count(e),
                        regression: before.is_some_and(|b| count(e) as f64 > count(b) as f64 * (1.0 + REGRESSION)),
                        answers_changed: before.is_some_and(|b| b.output_hash != e.output_hash),
                    }
                })
                .collect();
            let values: Vec<f64> = points.iter().map(|p| p.instructions as f64).collect();
            let seed = seed_for(&format!("instruction history {experiment} {series} {point} {}", phase.name()));
            let change_points = change_points::detect(&values, &change_points::DEFAULT, seed);
            tracks.push(Track {
                experiment: experiment.to_string(),
                series: series.to_string(),
                point: point.to_string(),
                phase,
                points,
                change_points,
            });
        }
    }
    tracks
}

/// The Markdown section of `HISTORY.md` on the per-commit history of `history_dir`, or `None` when it has none:
/// the visited commits, and each track's changes of level and regressions.
pub fn markdown(history_dir: &Path) -> Result<Option<String>, Error> {
    let visited = read_commits(history_dir)?;
    if visited.is_empty() {
        return Ok(None);
    }
    let commits = &visited;
    let tracks = instruction_tracks(commits, &read_counted(history_dir)?);
    let short = &|i: usize| commits[i].commit.chars().take(12).collect::<String>();
    let recorded = commits.iter().filter(|c| c.status == "recorded").count();
    let mut md = format!(
        "## Instruction counts per commit\n\n`harness history backfill` visited {} commits of the first-parent line \
         ({} recorded, {} did not build) and counted the build and trace instructions of every single-thread \
         configuration of today's suite each revision can run, in that revision's own worker under callgrind \
         (`{COMMITS_CSV}`, `{INSTRUCTIONS_CSV}`). Counts are exact, so a change of level is the code's (or the \
         compiler's: see the compiler column). Regressions: a count more than {}% above the track's previous \
         commit.\n\n",
        commits.len(),
        recorded,
        commits.len() - recorded,
        REGRESSION * 100.0
    );
    let changes: Vec<String> = tracks
        .iter()
        .flat_map(|t| {
            t.change_points.iter().map(move |c| {
                let at = t.points[c.index].commit;
                format!(
                    "| {} | {} | {} | {} | {} | {:.0} → {:.0} | {:.3} |",
                    t.series,
                    t.point,
                    t.phase.name(),
                    short(at),
                    crate::markdown::cell(&commits[at].subject),
                    c.before,
                    c.after,
                    c.ratio()
                )
            })
        })
        .collect();
    if changes.is_empty() {
        md.push_str("Changes of level: none.\n\n");
    } else {
        md.push_str("Changes of level (first commit at the new level; levels are median counts):\n\n");
        md.push_str(
            "| series | point | phase | commit | subject | before → after | ratio |\n|---|---|---|---|---|---|---|\n",
        );
        md.push_str(&(changes.join("\n") + "\n\n"));
    }
    let regressions: Vec<String> = tracks
        .iter()
        .flat_map(|t| {
            t.points.iter().filter(|p| p.regression).map(move |p| {
                format!("{} {} {} at {} ({})", t.series, t.point, t.phase.name(), short(p.commit), p.instructions)
            })
        })
        .collect();
    md.push_str(&format!(
        "Regressions: {}.\n\n",
        if regressions.is_empty() { "none".to_string() } else { regressions.join("; ") }
    ));
    md.push_str("| position | commit | date | subject | status | compiler | counted | skipped |\n|---|---|---|---|---|---|---|---|\n");
    for c in commits {
        let skipped = if c.skipped.is_empty() { 0 } else { c.skipped.split(" · ").count() };
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} |\n",
            c.position,
            c.commit.chars().take(12).collect::<String>(),
            c.date,
            crate::markdown::cell(&c.subject),
            c.status,
            c.compiler,
            c.counted,
            skipped
        ));
    }
    md.push('\n');
    Ok(Some(md))
}

/// Writes one commit's lines: its counted configurations replace any it had in `instructions.csv` (left by a
/// backfill killed before the commit's line), then its line is appended to `commits.csv`.
pub fn record(dir: &Path, entry: &CommitEntry, counted: &[CountedEntry]) -> Result<(), Error> {
    fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    let path = dir.join(INSTRUCTIONS_CSV);
    let mut lines: Vec<CountedEntry> = read_counted(dir)?.into_iter().filter(|e| e.commit != entry.commit).collect();
    lines.extend(counted.iter().cloned());
    let mut writer = csv::Writer::from_writer(Vec::new());
    for line in &lines {
        writer.serialize(line).map_err(|e| Error::write(&path, e))?;
    }
    let bytes = writer.into_inner().map_err(|e| Error::write(&path, e.to_string()))?;
    let tmp = path.with_extension("csv.tmp");
    fs::write(&tmp, bytes).and_then(|()| fs::rename(&tmp, &path)).map_err(|e| Error::write(&path, e))?;

    let path = dir.join(COMMITS_CSV);
    let header = !path.is_file();
    let mut writer = csv::WriterBuilder::new().has_headers(header).from_writer(Vec::new());
    writer.serialize(entry).map_err(|e| Error::write(&path, e))?;
    let bytes = writer.into_inner().map_err(|e| Error::write(&path, e.to_string()))?;
    let mut file = fs::OpenOptions::new().create(true).append(true).open(&path).map_err(|e| Error::write(&path, e))?;
    file.write_all(&bytes).and_then(|()| file.sync_all()).map_err(|e| Error::write(&path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn commit(i: u32) -> CommitEntry {
        CommitEntry {
            commit: format!("{i:040x}"),
            position: i,
            date: format!("2026-11-{:02}T00:00:00Z", i + 1),
            subject: format!("commit {i}"),
            status: "recorded".into(),
            compiler: "rustc 1.95.0".into(),
            counted: 1,
            skipped: String::new(),
        }
    }

    fn counted(i: u32, trace: u64, hash: &str) -> CountedEntry {
        CountedEntry {
            commit: format!("{i:040x}"),
            experiment: "ci".into(),
            series: "flat-bvh".into(),
            point: "objects 1000 (threads 1)".into(),
            config_id: "0123456789abcdef".into(),
            build_instructions: 1000,
            trace_instructions: trace,
            output_hash: hash.into(),
            nodes: 7,
            leaves: 4,
            depth: 2,
            tree_bytes: 512,
            sah_cost: 3.5,
            trace_s: None,
            build_s: None,
            machine_id: String::new(),
        }
    }

    #[test]
    fn a_step_in_the_trace_count_is_a_regression_and_a_change_point() {
        let commits: Vec<CommitEntry> = (0..8).map(commit).collect();
        let counts = [100, 100, 100, 100, 150, 150, 150, 150];
        let entries: Vec<CountedEntry> =
            counts.iter().enumerate().map(|(i, &c)| counted(i as u32, c, if i < 6 { "a" } else { "b" })).collect();
        let tracks = instruction_tracks(&commits, &entries);
        assert_eq!(tracks.len(), 2, "build and trace");
        let trace = tracks.iter().find(|t| t.phase == Phase::Trace).unwrap();
        let regressions: Vec<usize> = trace.points.iter().filter(|p| p.regression).map(|p| p.commit).collect();
        assert_eq!(regressions, [4]);
        let changed: Vec<usize> = trace.points.iter().filter(|p| p.answers_changed).map(|p| p.commit).collect();
        assert_eq!(changed, [6]);
        assert_eq!(trace.change_points.iter().map(|c| c.index).collect::<Vec<_>>(), [4]);
        let build = tracks.iter().find(|t| t.phase == Phase::Build).unwrap();
        assert!(build.change_points.is_empty() && build.points.iter().all(|p| !p.regression));
    }

    #[test]
    fn a_commit_recorded_again_replaces_its_lines_and_keeps_the_others() {
        let dir = std::env::temp_dir().join(format!("bvhlab-history-record-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let mut timed = counted(0, 1, "a");
        (timed.trace_s, timed.machine_id) = (Some(0.25), "e1058ee6a3e6".into());
        let mut quoted = commit(1);
        quoted.subject = "a, \"quoted\" subject".into();
        record(&dir, &quoted, &[counted(1, 2, "a")]).unwrap();
        record(&dir, &commit(0), &[timed.clone()]).unwrap();
        // A backfill killed after writing commit 1's counts but before its line: they are replaced, not doubled.
        record(&dir, &quoted, &[counted(1, 3, "a")]).unwrap();
        let lines = read_counted(&dir).unwrap();
        assert_eq!(lines.iter().map(|e| e.trace_instructions).collect::<Vec<_>>(), [1, 3]);
        assert_eq!(lines[0], timed, "times and machine round trip");
        assert_eq!(lines[1].trace_s, None);
        assert_eq!(read_commits(&dir).unwrap()[..2], [commit(0), quoted], "sorted by position");
        fs::remove_dir_all(&dir).unwrap();
    }
}
