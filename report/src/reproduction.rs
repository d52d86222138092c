//! Whether a re-run of a recorded result set reproduces it: the deterministic columns of every configuration both
//! ran (identical where the kernel, or for a peer library the ISA, is the same), every series' time ratio to the
//! experiment's reference at every point, and every claim, judged within the harness's resolution.
//!
//! Times of two machines are never compared as such: only ratios of two series timed in the same rounds on one
//! machine, the recorded ratio against the reproduced one.

use std::collections::BTreeMap;
use std::path::Path;

use schema::row::{COLUMNS, Role};
use schema::{Axis, column};
use serde::{Deserialize, Serialize};

use crate::claims::{self, ClaimResult, PointResult};
use crate::error::Error;
use crate::rows::{self, Rows, Run};
use crate::spec::{ReportSpec, Verdict};
use crate::stats::Estimate;

/// The smallest change of a time ratio the harness resolves at one thread (`results/resolution`'s A/A
/// experiment): a ratio that moved by at most this much reproduced.
pub const RESOLUTION_ONE_THREAD: f64 = 0.02;
/// The same on all cores.
pub const RESOLUTION_ALL_CORES: f64 = 0.04;

/// The file a reproduction's verdict is written to, beside its rows (JSON; the site reads it).
pub const JSON: &str = "reproduction.json";
/// The same verdict for readers.
pub const MARKDOWN: &str = "REPRODUCTION.md";

/// A commit's first 12 digits (all of a shorter text, e.g. `unknown`).
pub fn short_commit(commit: &str) -> &str {
    &commit[..commit.len().min(12)]
}

/// The resolution at a point where at most `threads` worker threads ran.
pub fn resolution(threads: f64) -> f64 {
    if threads <= 1.0 { RESOLUTION_ONE_THREAD } else { RESOLUTION_ALL_CORES }
}

/// What a comparison found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Outcome {
    /// The same answer, within the resolution.
    Reproduced,
    /// A different answer.
    NotReproduced,
    /// Nothing to compare (a series or point missing here, another kernel or ISA).
    NotComparable,
}

impl Outcome {
    /// The outcome in words.
    pub fn word(self) -> &'static str {
        match self {
            Outcome::Reproduced => "reproduced",
            Outcome::NotReproduced => "not reproduced",
            Outcome::NotComparable => "not comparable",
        }
    }
}

/// Where a result set came from: its rows' commit and machine.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Origin {
    /// The commits of the rows (one for a result set that can be reproduced).
    pub commits: Vec<String>,
    /// The machines, as `cpu_model (machine_id)`.
    pub machines: Vec<String>,
    /// Rows timed, and rows that failed validation.
    pub rows: usize,
    /// Rows that failed validation.
    pub failed: usize,
}

impl Origin {
    fn of(rows: &Rows) -> Origin {
        let all = || rows.runs.iter().chain(&rows.failed);
        Origin {
            commits: crate::distinct(all().map(|r| r.text(column::git_commit).to_string())),
            machines: crate::distinct(all().map(Run::machine)),
            rows: rows.runs.len(),
            failed: rows.failed.len(),
        }
    }
}

/// A claim, recorded and reproduced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClaimOutcome {
    /// The claim in words.
    pub text: String,
    /// Its verdict then and now, over the points both ran (`holds`, `fails`, `inconclusive`).
    pub recorded: String,
    /// The same, reproduced.
    pub reproduced: String,
    /// The outcome.
    pub outcome: Outcome,
    /// Why, in one line.
    pub reason: String,
}

/// A series' time ratio to the reference at one point, recorded and reproduced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointOutcome {
    /// The series.
    pub series: String,
    /// The point, as claims name it.
    pub point: String,
    /// Recorded ratio `metric(reference) / metric(series)` and its 95% interval (null: none).
    #[serde(with = "nan_as_null")]
    pub recorded: [f64; 3],
    /// Reproduced ratio and interval.
    #[serde(with = "nan_as_null")]
    pub reproduced: [f64; 3],
    /// The resolution the point is judged with.
    pub resolution: f64,
    /// The outcome.
    pub outcome: Outcome,
}

/// JSON has no NaN: a ratio or interval end that is not a number (no interval below six runs) is written as null
/// and read back as NaN.
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(values: &[f64; 3], s: S) -> Result<S::Ok, S::Error> {
        values.map(|v| v.is_finite().then_some(v)).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
        Ok(<[Option<f64>; 3]>::deserialize(d)?.map(|v| v.unwrap_or(f64::NAN)))
    }
}

/// Everything a reproduction found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reproduction {
    /// The result set as recorded.
    pub recorded_origin: Origin,
    /// The reproduction.
    pub reproduced_origin: Origin,
    /// Every claim of the experiment.
    pub claims: Vec<ClaimOutcome>,
    /// The reference series the times are compared against (none: no time comparison).
    pub reference: Option<String>,
    /// Every series' ratio to the reference at every point both ran.
    pub points: Vec<PointOutcome>,
    /// The deterministic columns compared.
    pub deterministic_columns: Vec<String>,
    /// Configurations whose deterministic columns were compared.
    pub configurations_compared: usize,
    /// Configurations both ran but that are not comparable, one line per series and reason.
    pub not_comparable: Vec<String>,
    /// Configurations recorded but not run here, and run here but not recorded.
    pub only_recorded: usize,
    /// See `only_recorded`.
    pub only_reproduced: usize,
    /// Every deterministic difference, one line each.
    pub differences: Vec<String>,
}

impl Reproduction {
    /// The verdict: every deterministic column the same, no claim and no point not reproduced.
    pub fn outcome(&self) -> Outcome {
        let moved = self.claims.iter().any(|c| c.outcome == Outcome::NotReproduced)
            || self.points.iter().any(|p| p.outcome == Outcome::NotReproduced)
            || !self.differences.is_empty();
        let compared = self.configurations_compared > 0 || self.claims.iter().any(|c| c.outcome == Outcome::Reproduced);
        match (moved, compared) {
            (true, _) => Outcome::NotReproduced,
            (false, true) => Outcome::Reproduced,
            (false, false) => Outcome::NotComparable,
        }
    }

    /// Reads a reproduction's verdict from its folder.
    pub fn read(dir: &Path) -> Result<Reproduction, Error> {
        let path = dir.join(JSON);
        let text = std::fs::read_to_string(&path).map_err(|e| Error::read(&path, e))?;
        serde_json::from_str(&text).map_err(|e| Error::read(&path, e))
    }
}

/// Compares the rows of `reproduced` (a folder holding `runs.csv`) with those of `recorded`, the claims and ratios
/// as `spec` defines them.
pub fn compare(recorded: &Path, reproduced: &Path, spec: &ReportSpec) -> Result<Reproduction, Error> {
    let (old_csv, new_csv) = (recorded.join("runs.csv"), reproduced.join("runs.csv"));
    let (old, new) = (rows::read(&old_csv)?, rows::read(&new_csv)?);
    let shared = shared_columns(&old_csv, &new_csv)?;
    let deterministic: Vec<String> = COLUMNS
        .iter()
        .filter(|c| matches!(c.role, Role::Counter | Role::Validation) && shared.contains(c.name))
        .map(|c| c.name.to_string())
        .collect();
    let mut out = Reproduction {
        recorded_origin: Origin::of(&old),
        reproduced_origin: Origin::of(&new),
        claims: compare_claims(&claims::check_all(&old, spec), &claims::check_all(&new, spec)),
        reference: spec.reference.clone(),
        points: compare_points(spec, &old, &new),
        deterministic_columns: deterministic.clone(),
        configurations_compared: 0,
        not_comparable: Vec::new(),
        only_recorded: 0,
        only_reproduced: 0,
        differences: Vec::new(),
    };
    compare_deterministic(&old, &new, &shared, &deterministic, &mut out);
    Ok(out)
}

/// The header columns both files have (an older row format lacks the columns added since).
fn shared_columns(a: &Path, b: &Path) -> Result<std::collections::BTreeSet<String>, Error> {
    let header = |path: &Path| -> Result<std::collections::BTreeSet<String>, Error> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        Ok(text.lines().next().unwrap_or("").split(',').map(|c| c.trim().trim_matches('"').to_string()).collect())
    };
    let (a, b) = (header(a)?, header(b)?);
    Ok(a.intersection(&b).cloned().collect())
}

/// A configuration across machines and commits: its series and every setting both files record.
fn configuration_key(run: &Run, shared: &std::collections::BTreeSet<String>) -> Vec<String> {
    let mut key = vec![run.series().to_string()];
    key.extend(Axis::ALL.iter().filter(|a| shared.contains(a.key())).map(|a| run.text(a.key()).to_string()));
    key
}

/// Why rows of one configuration recorded and reproduced cannot be compared exactly: another SIMD kernel for the
/// tracer's structures, another ISA for a peer library (which dispatches on it).
fn incomparable(old: &Run, new: &Run) -> Option<String> {
    let peer = old.text(column::peer_info) != "-";
    let (what, then, now) = if peer {
        ("ISA", old.text(column::cpu_isa), new.text(column::cpu_isa))
    } else {
        ("kernel", old.text(column::simd_kernel_used), new.text(column::simd_kernel_used))
    };
    (then != now).then(|| format!("{what} `{then}` then, `{now}` here"))
}

fn compare_deterministic(
    old: &Rows,
    new: &Rows,
    shared: &std::collections::BTreeSet<String>,
    columns: &[String],
    out: &mut Reproduction,
) {
    let first_of = |rows: &Rows| {
        let mut map: BTreeMap<Vec<String>, Run> = BTreeMap::new();
        for run in rows.runs.iter().chain(&rows.failed) {
            map.entry(configuration_key(run, shared)).or_insert_with(|| run.clone());
        }
        map
    };
    let (old, new) = (first_of(old), first_of(new));
    let mut not_comparable: BTreeMap<String, usize> = BTreeMap::new();
    for (key, a) in &old {
        let Some(b) = new.get(key) else {
            out.only_recorded += 1;
            continue;
        };
        if let Some(why) = incomparable(a, b) {
            *not_comparable.entry(format!("{}: {why}", a.series())).or_default() += 1;
            continue;
        }
        out.configurations_compared += 1;
        let changed: Vec<String> = columns
            .iter()
            .filter(|c| a.text(c) != b.text(c))
            .map(|c| format!("{c} {} then, {} now", a.text(c), b.text(c)))
            .collect();
        if !changed.is_empty() {
            out.differences.push(format!("{} ({}): {}", a.series(), a.config_id(), changed.join("; ")));
        }
    }
    out.only_reproduced = new.keys().filter(|k| !old.contains_key(*k)).count();
    out.not_comparable =
        not_comparable.into_iter().map(|(what, n)| format!("{what} ({n} configuration{})", plural(n))).collect();
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Whether a ratio reproduced: it moved by at most `resolution`, or its two 95% intervals overlap. Moved further
/// where one side has no interval (fewer than [`crate::stats::MIN_SAMPLES_FOR_INTERVAL`] runs), noise and change
/// cannot be told apart: not comparable.
pub fn point_outcome(recorded: Estimate, reproduced: Estimate, resolution: f64) -> Outcome {
    if !recorded.value.is_finite() || !reproduced.value.is_finite() {
        return Outcome::NotComparable;
    }
    if (reproduced.value / recorded.value - 1.0).abs() <= resolution {
        return Outcome::Reproduced;
    }
    if [recorded.lo, recorded.hi, reproduced.lo, reproduced.hi].iter().any(|v| !v.is_finite()) {
        return Outcome::NotComparable;
    }
    let overlap = reproduced.lo <= recorded.hi && recorded.lo <= reproduced.hi;
    if overlap { Outcome::Reproduced } else { Outcome::NotReproduced }
}

fn compare_points(spec: &ReportSpec, old: &Rows, new: &Rows) -> Vec<PointOutcome> {
    let Some(reference) = spec.reference.as_deref() else { return Vec::new() };
    let mut out = Vec::new();
    for series in spec.series.iter().filter(|s| *s != reference) {
        let curves = |rows: &Rows| {
            let Some(first) = rows.runs.iter().find(|r| r.series() == series) else { return BTreeMap::new() };
            let metric = spec.speedup_metric_of(first.text(column::workload));
            let mut points = BTreeMap::new();
            for curve in crate::pool::ratio_curves(spec, &rows.runs, reference, series, column::objects, metric) {
                for p in curve.points {
                    let threads = p.threads.max(p.reference_threads);
                    points.insert(crate::pool::point_label(&curve.fixed, p.x), (p.estimate, threads));
                }
            }
            points
        };
        let (then, now) = (curves(old), curves(new));
        for (point, (a, threads)) in &then {
            let Some((b, _)) = now.get(point) else { continue };
            let resolution = resolution(*threads);
            out.push(PointOutcome {
                series: series.clone(),
                point: point.clone(),
                recorded: [a.value, a.lo, a.hi],
                reproduced: [b.value, b.lo, b.hi],
                resolution,
                outcome: point_outcome(*a, *b, resolution),
            });
        }
    }
    out
}

/// The verdict of a claim over some of its points: fails where one fails, holds where all hold.
fn verdict_over(points: &[&PointResult]) -> Verdict {
    if points.iter().any(|p| p.verdict == Verdict::Fails) {
        Verdict::Fails
    } else if !points.is_empty() && points.iter().all(|p| p.verdict == Verdict::Holds) {
        Verdict::Holds
    } else {
        Verdict::Inconclusive
    }
}

fn word(v: Verdict) -> &'static str {
    match v {
        Verdict::Holds => "holds",
        Verdict::Fails => "fails",
        Verdict::Inconclusive => "inconclusive",
    }
}

fn estimate(p: &PointResult) -> Estimate {
    Estimate { value: p.ratio, lo: p.lo, hi: p.hi }
}

/// Each recorded claim against the reproduced one of the same text, over the points both ran.
pub fn compare_claims(recorded: &[ClaimResult], reproduced: &[ClaimResult]) -> Vec<ClaimOutcome> {
    recorded
        .iter()
        .map(|old| {
            let new = reproduced.iter().find(|c| c.text == old.text);
            let outcome = |outcome, then: &str, now: &str, reason: String| ClaimOutcome {
                text: old.text.clone(),
                recorded: then.to_string(),
                reproduced: now.to_string(),
                outcome,
                reason,
            };
            let Some(new) = new.filter(|n| !n.points.is_empty()) else {
                let why = new.map_or("the claim is not in the config run here".to_string(), |n| n.detail.clone());
                return outcome(
                    Outcome::NotComparable,
                    word(old.verdict),
                    "-",
                    format!("nothing to compare here: {why}"),
                );
            };
            let pairs: Vec<(&PointResult, &PointResult)> = old
                .points
                .iter()
                .filter_map(|a| new.points.iter().find(|b| b.label == a.label).map(|b| (a, b)))
                .collect();
            if pairs.is_empty() {
                return outcome(
                    Outcome::NotComparable,
                    word(old.verdict),
                    word(new.verdict),
                    "no point of the claim ran both times".into(),
                );
            }
            let then = verdict_over(&pairs.iter().map(|(a, _)| *a).collect::<Vec<_>>());
            let now = verdict_over(&pairs.iter().map(|(_, b)| *b).collect::<Vec<_>>());
            let judged = |want: Outcome| {
                pairs
                    .iter()
                    .filter(move |(a, b)| point_outcome(estimate(a), estimate(b), resolution(a.threads)) == want)
            };
            let unjudged = judged(Outcome::NotComparable).count();
            let moved: Vec<String> = judged(Outcome::NotReproduced)
                .map(|(a, b)| {
                    format!(
                        "{} {:.3} [{:.3}, {:.3}] then, {:.3} [{:.3}, {:.3}] now",
                        a.label, a.ratio, a.lo, a.hi, b.ratio, b.lo, b.hi
                    )
                })
                .collect();
            let counted = if pairs.len() == old.points.len() {
                format!("{} points", pairs.len())
            } else {
                format!("{} of its {} points (the others did not run here)", pairs.len(), old.points.len())
            };
            let contradicts =
                matches!((then, now), (Verdict::Holds, Verdict::Fails) | (Verdict::Fails, Verdict::Holds));
            let (result, reason) = if contradicts {
                (Outcome::NotReproduced, format!("{} then, {} now over {counted}", word(then), word(now)))
            } else if !moved.is_empty() {
                (
                    Outcome::NotReproduced,
                    format!(
                        "{} of {counted} moved beyond the resolution and both intervals: {}",
                        moved.len(),
                        moved.join("; ")
                    ),
                )
            } else if unjudged > 0 {
                (
                    Outcome::NotComparable,
                    format!(
                        "{unjudged} of {counted} moved beyond the resolution without an interval to judge them by \
                         (fewer than {} runs on one side)",
                        crate::stats::MIN_SAMPLES_FOR_INTERVAL
                    ),
                )
            } else if then == now {
                (
                    Outcome::Reproduced,
                    format!(
                        "{} both times over {counted}, every ratio within the resolution or its interval",
                        word(now)
                    ),
                )
            } else {
                (
                    Outcome::Reproduced,
                    format!(
                        "{} then, {} now over {counted}: no ratio moved beyond the resolution or its interval",
                        word(then),
                        word(now)
                    ),
                )
            };
            outcome(result, word(then), word(now), reason)
        })
        .collect()
}

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
    let count = |outcome: Outcome| r.claims.iter().filter(|c| c.outcome == outcome).count();
    let points = |outcome: Outcome| r.points.iter().filter(|p| p.outcome == outcome).count();
    let mut md = format!("# Reproduction of {title}\n\n");
    for line in how {
        md.push_str(&format!("- {line}\n"));
    }
    md.push_str(&format!(
        "- recorded: {}\n- reproduced: {}\n\n**{}**: {} of {} claims reproduced, {} not reproduced, {} not comparable; \
         {} configurations' deterministic columns compared, {} differences; {} of {} time ratios reproduced.\n\n",
        origin(&r.recorded_origin),
        origin(&r.reproduced_origin),
        r.outcome().word(),
        count(Outcome::Reproduced),
        r.claims.len(),
        count(Outcome::NotReproduced),
        count(Outcome::NotComparable),
        r.configurations_compared,
        r.differences.len(),
        points(Outcome::Reproduced),
        r.points.len(),
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

/// The folder, under a result set, that holds its reproductions.
pub const FOLDER: &str = "reproductions";

/// The heading of REPORT.md's section on the result set's reproductions.
const SECTION: &str = "## Reproductions";

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

    fn e(value: f64, lo: f64, hi: f64) -> Estimate {
        Estimate { value, lo, hi }
    }

    fn point(label: &str, ratio: f64, lo: f64, hi: f64, verdict: Verdict) -> PointResult {
        PointResult { label: label.into(), ratio, lo, hi, threshold: 1.0, verdict, more: None, threads: 1.0 }
    }

    fn claim(points: Vec<PointResult>) -> ClaimResult {
        ClaimResult {
            text: "a is faster than b".into(),
            verdict: Verdict::Holds,
            ratio: f64::NAN,
            lo: f64::NAN,
            hi: f64::NAN,
            threshold: 1.0,
            detail: String::new(),
            points,
        }
    }

    #[test]
    fn a_ratio_reproduces_within_the_resolution_or_where_the_intervals_overlap() {
        assert_eq!(point_outcome(e(1.10, 1.09, 1.11), e(1.12, 1.119, 1.121), 0.02), Outcome::Reproduced);
        assert_eq!(point_outcome(e(1.10, 1.00, 1.20), e(1.30, 1.15, 1.40), 0.02), Outcome::Reproduced);
        assert_eq!(point_outcome(e(1.10, 1.08, 1.12), e(1.20, 1.18, 1.22), 0.04), Outcome::NotReproduced);
        assert_eq!(point_outcome(e(f64::NAN, 1.0, 1.0), e(1.0, 1.0, 1.0), 0.02), Outcome::NotComparable);
        // Without an interval on one side: within the resolution still reproduces, beyond it cannot be judged.
        let none = |v| e(v, f64::NAN, f64::NAN);
        assert_eq!(point_outcome(none(1.0), e(1.01, 1.0, 1.02), 0.02), Outcome::Reproduced);
        assert_eq!(point_outcome(none(1.0), e(1.5, 1.4, 1.6), 0.02), Outcome::NotComparable);
    }

    #[test]
    fn a_claim_is_judged_over_the_points_both_ran() {
        let old =
            claim(vec![point("1e3", 1.3, 1.2, 1.4, Verdict::Holds), point("1e4", 0.9, 0.85, 0.95, Verdict::Fails)]);
        // Only 1e3 ran again (a quick reproduction): the recorded verdict over it holds, and so does the new one.
        let new = claim(vec![point("1e3", 1.31, 1.25, 1.36, Verdict::Holds)]);
        let c = &compare_claims(std::slice::from_ref(&old), std::slice::from_ref(&new))[0];
        assert_eq!((c.outcome, c.recorded.as_str(), c.reproduced.as_str()), (Outcome::Reproduced, "holds", "holds"));
        assert!(c.reason.contains("1 of its 2 points"), "{}", c.reason);

        let flipped = claim(vec![point("1e3", 0.9, 0.85, 0.95, Verdict::Fails)]);
        let c = &compare_claims(std::slice::from_ref(&old), &[flipped])[0];
        assert_eq!(c.outcome, Outcome::NotReproduced);
        assert!(c.reason.starts_with("holds then, fails now"), "{}", c.reason);

        // Still holding, but far outside the recorded interval and the resolution.
        let moved = claim(vec![point("1e3", 1.9, 1.8, 2.0, Verdict::Holds)]);
        let c = &compare_claims(std::slice::from_ref(&old), &[moved])[0];
        assert_eq!(c.outcome, Outcome::NotReproduced);
        assert!(c.reason.contains("moved beyond the resolution"), "{}", c.reason);

        let c = &compare_claims(std::slice::from_ref(&old), &[claim(vec![])])[0];
        assert_eq!(c.outcome, Outcome::NotComparable);
        let other = ClaimResult { text: "another claim".into(), ..new.clone() };
        assert_eq!(compare_claims(&[old], &[other])[0].outcome, Outcome::NotComparable);
    }

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
