//! A speedup history: one line per tracked speedup of each appended run (`history.csv`), and a figure per
//! experiment of every speedup over the appended commits, regressions and change points marked.

pub mod change_points;
pub mod commits;

use schema::column;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use tracer::fingerprint::Fnv64;

use crate::check::{CheckOptions, counters, speedups};
use crate::error::Error;
use crate::figures::chart::{self, Chart, ChartPoint, Line, Mark, Marks, Overlay};
use crate::markdown::{cell, num};
use crate::rows;
use crate::spec::ReportSpec;
use crate::stats::seed_for;

/// A drop of the speedup by more than this fraction from the previous entry is marked as a regression.
pub const REGRESSION: f64 = 0.10;

/// One line of `history.csv` (the header names these fields).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Entry {
    pub experiment: String,
    pub commit: String,
    pub dirty: String,
    pub timestamp: String,
    pub series: String,
    pub point: String,
    pub speedup: f64,
    pub lower: f64,
    pub upper: f64,
    pub counters: String,
}

/// Whether `after` is a regression from `before`: a drop of more than [`REGRESSION`], beyond both intervals.
fn dropped(before: &Entry, after: &Entry) -> bool {
    after.speedup < before.speedup * (1.0 - REGRESSION) && after.upper < before.lower
}

/// One appended run of an experiment: its commit, time, dirty flag and counters' fingerprint.
pub(crate) struct AppendedRun {
    pub commit: String,
    pub timestamp: String,
    pub dirty: String,
    pub counters: String,
}

/// One tracked speedup (series and point) over an experiment's appended runs.
pub(crate) struct SpeedupTrack<'a> {
    pub series: String,
    pub point: String,
    /// The track's entries in order, each with its run's number (1-based, into [`SpeedupHistory::runs`]).
    pub entries: Vec<(usize, &'a Entry)>,
    /// Indices into `entries` of regressions: drops from the previous entry (see [`REGRESSION`]).
    pub regressions: Vec<usize>,
    /// Changes of level found by [`change_points::detect`] with [`change_points::DEFAULT`] (indices into `entries`).
    pub change_points: Vec<change_points::ChangePoint>,
}

/// One experiment's speedup history: its appended runs in order and every tracked speedup over them.
pub(crate) struct SpeedupHistory<'a> {
    pub experiment: String,
    pub runs: Vec<AppendedRun>,
    pub tracks: Vec<SpeedupTrack<'a>>,
}

/// The speedup history of each experiment of `entries` (lines of `history.csv`), in order of appearance.
pub(crate) fn speedup_histories(entries: &[Entry]) -> Vec<SpeedupHistory<'_>> {
    let experiments = crate::distinct(entries.iter().map(|e| e.experiment.as_str()));
    experiments
        .into_iter()
        .map(|experiment| {
            let own: Vec<&Entry> = entries.iter().filter(|e| e.experiment == experiment).collect();
            let keys = crate::distinct(own.iter().map(|e| (e.commit.as_str(), e.timestamp.as_str())));
            let run_of =
                |e: &Entry| 1 + keys.iter().position(|k| *k == (e.commit.as_str(), e.timestamp.as_str())).unwrap();
            let runs = keys
                .iter()
                .map(|&(commit, timestamp)| {
                    let first = own.iter().find(|e| e.commit == commit && e.timestamp == timestamp).unwrap();
                    AppendedRun {
                        commit: commit.into(),
                        timestamp: timestamp.into(),
                        dirty: first.dirty.clone(),
                        counters: first.counters.clone(),
                    }
                })
                .collect();
            let tracks = crate::distinct(own.iter().map(|e| (e.series.as_str(), e.point.as_str())))
                .into_iter()
                .map(|(series, point)| {
                    let entries: Vec<(usize, &Entry)> = own
                        .iter()
                        .filter(|e| e.series == series && e.point == point)
                        .map(|e| (run_of(e), *e))
                        .collect();
                    let regressions = (1..entries.len()).filter(|&i| dropped(entries[i - 1].1, entries[i].1)).collect();
                    let speedups: Vec<f64> = entries.iter().map(|(_, e)| e.speedup).collect();
                    let seed = seed_for(&format!("history change points {experiment} {series} {point}"));
                    let change_points = change_points::detect(&speedups, &change_points::DEFAULT, seed);
                    SpeedupTrack { series: series.into(), point: point.into(), entries, regressions, change_points }
                })
                .collect();
            SpeedupHistory { experiment: experiment.into(), runs, tracks }
        })
        .collect()
}

/// The lines of a `history.csv` (none when the file is missing).
pub(crate) fn read(path: &Path) -> Result<Vec<Entry>, Error> {
    let Ok(text) = std::fs::read_to_string(path) else { return Ok(vec![]) };
    csv::Reader::from_reader(text.as_bytes())
        .deserialize()
        .collect::<Result<Vec<Entry>, _>>()
        .map_err(|e| Error::Mismatch { path: path.into(), message: format!("malformed history: {e}") })
}

/// Appends every speedup of `run_dir` (against `spec.reference`, same run) to `history_dir/history.csv`;
/// returns how many lines were added. The same run (experiment, commit, time) is never appended twice.
pub fn append(run_dir: &Path, spec: &ReportSpec, history_dir: &Path, options: &CheckOptions) -> Result<usize, Error> {
    let runs_csv = run_dir.join("runs.csv");
    let rows = rows::read(&runs_csv)?;
    let Some(reference) = spec.reference.as_deref() else {
        return Err(Error::Mismatch {
            path: runs_csv,
            message: "the experiment names no reference series, so it has no speedups to track".into(),
        });
    };
    let first = &rows.runs[0];
    let timestamp = rows.runs.iter().map(|r| r.text(column::timestamp)).max().unwrap_or_default().to_string();
    let mut by_config: BTreeMap<&str, &rows::Run> = BTreeMap::new();
    for r in &rows.runs {
        by_config.entry(r.config_id()).or_insert(r);
    }
    let mut h = Fnv64::default();
    for (id, r) in &by_config {
        h.bytes(id.as_bytes());
        for c in counters() {
            h.bytes(r.text(c).as_bytes()).bytes(b"|");
        }
    }
    let counters = format!("{:016x}", h.finish());
    let path = history_dir.join("history.csv");
    let existing = read(&path)?;
    let experiment = first.text(column::experiment).to_string();
    let commit = first.text(column::git_commit).chars().take(12).collect::<String>();
    if existing.iter().any(|e| e.experiment == experiment && e.commit == commit && e.timestamp == timestamp) {
        return Err(Error::Mismatch { path, message: format!("{} is already in the history", run_dir.display()) });
    }
    let points = speedups(spec, reference, &rows.runs, &rows.runs, options);
    let mut writer = csv::WriterBuilder::new().has_headers(existing.is_empty()).from_writer(Vec::new());
    for p in &points {
        let entry = Entry {
            experiment: experiment.clone(),
            commit: commit.clone(),
            dirty: first.text(column::git_dirty).to_string(),
            timestamp: timestamp.clone(),
            series: p.series.clone(),
            point: p.point.clone(),
            speedup: p.new.value,
            lower: p.new.lo,
            upper: p.new.hi,
            counters: counters.clone(),
        };
        writer.serialize(entry).map_err(|e| Error::write(&path, e))?;
    }
    let text = writer.into_inner().map_err(|e| Error::write(&path, e.to_string()))?;
    std::fs::create_dir_all(history_dir).map_err(|e| Error::write(history_dir, e))?;
    use std::io::Write as _;
    let mut file =
        std::fs::OpenOptions::new().create(true).append(true).open(&path).map_err(|e| Error::write(&path, e))?;
    file.write_all(&text).map_err(|e| Error::write(&path, e))?;
    Ok(points.len())
}

/// A change of level of one tracked speedup.
struct Change {
    series: String,
    point: String,
    /// The first run (1-based) at the new level.
    run: usize,
    /// The speedup at that run.
    speedup: f64,
    found: change_points::ChangePoint,
}

/// Draws `history_dir/<experiment>.svg|png` for every experiment in the history (x: appended runs in
/// order, labelled with short commit hashes; red crosses: a drop of more than [`REGRESSION`] from the
/// previous entry, beyond both intervals; rings and dashed rules: change points found by
/// [`change_points::detect`] with [`change_points::DEFAULT`]), and `HISTORY.md` listing the change points and
/// each run's commit and time. Returns the files written.
pub fn plot(history_dir: &Path) -> Result<Vec<PathBuf>, Error> {
    let path = history_dir.join("history.csv");
    let entries = read(&path)?;
    let per_commit = commits::markdown(history_dir)?;
    if entries.is_empty() && per_commit.is_none() {
        return Err(Error::NoRows { path });
    }
    let p = change_points::DEFAULT;
    let mut files = Vec::new();
    let mut md = String::from(
        "# Speedup history\n\nEach figure plots every tracked speedup (95% interval) against the appended runs, in order ",
    );
    md.push_str(
        "(x: the run's commit); red crosses mark drops of more than 10% from the previous run beyond both intervals. ",
    );
    md.push_str(&format!(
        "Black rings mark change points, the first run of a series at a new level, and a dashed line separates the two \
         levels. Each series' speedups over the runs are searched with a permutation CUSUM test on ranks in the manner of \
         Taylor's change-point analysis: the standardized maximum of the CUSUM of rank deviations from their mean is \
         compared with {} seeded reshuffles; at confidence ≥ {}% the series splits where the absolute deviations from \
         the two levels' medians are smallest, and both sides are searched again. Only levels of at least {} runs whose \
         medians differ by more than {}% are kept (`report/src/history/change_points.rs`). A 10% shift in 1% noise is found \
         once 4 runs lie on each side of it, or 3 on one side and 10 on the other.\n\n",
        p.reshuffles,
        p.confidence * 100.0,
        p.min_segment,
        p.min_effect * 100.0
    ));
    for history in speedup_histories(&entries) {
        let (experiment, runs) = (&history.experiment, &history.runs);
        let mut lines: Vec<Line> = Vec::new();
        let mut regressions: Vec<(f64, f64)> = Vec::new();
        let mut changes: Vec<Change> = Vec::new();
        for (i, track) in history.tracks.iter().enumerate() {
            let at = |k: usize| (track.entries[k].0, track.entries[k].1.speedup);
            let points: Vec<ChartPoint> = track
                .entries
                .iter()
                .map(|(run, e)| ChartPoint { x: *run as f64, y: e.speedup, lo: e.lower, hi: e.upper })
                .collect();
            regressions.extend(track.regressions.iter().map(|&k| (at(k).0 as f64, at(k).1)));
            for found in &track.change_points {
                let (run, speedup) = at(found.index);
                let (series, point) = (track.series.clone(), track.point.clone());
                changes.push(Change { series, point, run, speedup, found: *found });
            }
            lines.push(Line {
                label: format!("{} {}", track.series, track.point),
                style: i,
                colour: None,
                front: false,
                points,
            });
        }
        changes.sort_by_key(|c| c.run);
        let mut rules: Vec<f64> = changes.iter().map(|c| c.run as f64 - 0.5).collect();
        rules.dedup();
        let overlay = Overlay {
            x_ticks: runs
                .iter()
                .enumerate()
                .map(|(i, r)| ((i + 1) as f64, r.commit.chars().take(7).collect()))
                .collect(),
            marks: vec![
                Marks { label: "regression (drop > 10%)".into(), mark: Mark::Cross, points: regressions },
                Marks {
                    label: "change point (new level from here)".into(),
                    mark: Mark::Ring,
                    points: changes.iter().map(|c| (c.run as f64, c.speedup)).collect(),
                },
            ],
            rules,
            categorical: false,
        };
        let chart = Chart {
            title: format!("{experiment}: speedups over the appended runs"),
            x_label: "commit of each appended run, in order".into(),
            y_label: "speedup vs reference (×)".into(),
            log_x: false,
            log_y: true,
            lines,
            guide: None,
        };
        let (svg, png) = (history_dir.join(format!("{experiment}.svg")), history_dir.join(format!("{experiment}.png")));
        chart::render_with(&chart, &overlay, &svg, &png).map_err(|(p, e)| Error::write(&p, e))?;
        md.push_str(&format!("## {experiment}\n\n![{experiment}]({experiment}.svg)\n\n"));
        if changes.is_empty() {
            let plural = if runs.len() == 1 { "" } else { "s" };
            md.push_str(&format!("Change points: none in {} run{plural}.\n\n", runs.len()));
        } else {
            md.push_str("Change points (level: the median speedup between neighbouring change points):\n\n");
            md.push_str("| run | commit | series | point | level before → after | ratio | confidence |\n|---|---|---|---|---|---|---|\n");
            for c in &changes {
                md.push_str(&format!(
                    "| {} | {} | {} | {} | {} → {} | {:.3} | {:.1}% |\n",
                    c.run,
                    runs[c.run - 1].commit,
                    cell(&c.series),
                    cell(&c.point),
                    num(c.found.before),
                    num(c.found.after),
                    c.found.ratio(),
                    c.found.confidence * 100.0
                ));
            }
            md.push('\n');
        }
        md.push_str("| run | commit | dirty | time | counters |\n|---|---|---|---|---|\n");
        for (i, r) in runs.iter().enumerate() {
            md.push_str(&format!("| {} | {} | {} | {} | {} |\n", i + 1, r.commit, r.dirty, r.timestamp, r.counters));
        }
        md.push('\n');
        files.extend([svg, png]);
    }
    md.push_str(&per_commit.unwrap_or_default());
    let md_path = history_dir.join("HISTORY.md");
    std::fs::write(&md_path, md).map_err(|e| Error::write(&md_path, e))?;
    files.push(md_path);
    Ok(files)
}
