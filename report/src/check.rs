//! Regression check: compares a new run directory with a stored baseline of the same experiment.
//!
//! Two kinds of evidence: deterministic counters (rays, work per ray, tree statistics, hashes) must
//! match exactly per configuration; speedups against the reference series, pooled over seeds like
//! the figures' points, are compared with a percentile-bootstrap interval of `new / old`.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::Path;

use tracer::rng::SplitMix64;

use crate::error::Error;
use crate::markdown::num;
use crate::pool;
use crate::rows::{self, Rows, Run, SETTINGS};
use crate::spec::ReportSpec;
use crate::stats;
pub use crate::stats::Estimate;

/// Deterministic columns compared exactly (as text) between the first repetitions of a configuration.
pub const COUNTERS: [&str; 11] = [
    "rays",
    "nodes_per_ray",
    "box_tests_per_ray",
    "prim_tests_per_ray",
    "tree_nodes",
    "tree_leaves",
    "tree_depth",
    "tree_bytes",
    "sah_cost",
    "image_hash",
    "scene_fingerprint",
];

/// How strict the comparison is.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOptions {
    /// Metric column the speedups are computed from (a time: smaller is better).
    pub metric: String,
    /// Smallest relative change of a speedup that counts (0.10: 10%).
    pub min_effect: f64,
    /// Counter changes and configurations present on one side only do not fail the check.
    pub accept_counter_changes: bool,
    /// Only points whose series runs use this many threads gate the check.
    pub gate_threads: u32,
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions { metric: "trace_s".into(), min_effect: 0.10, accept_counter_changes: false, gate_threads: 1 }
    }
}

/// One deterministic column that differs between baseline and new run for one configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct CounterChange {
    /// The configuration id.
    pub config_id: String,
    /// The series label.
    pub series: String,
    /// Short description of the configuration's settings, e.g. `random-spheres objects 1000 seed 1`.
    pub settings: String,
    /// The column that changed.
    pub column: String,
    /// Baseline value.
    pub old: String,
    /// New value.
    pub new: String,
}

/// Outcome of one speedup comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpeedupVerdict {
    /// The speedup fell significantly and by more than the minimum effect.
    Regressed,
    /// The speedup rose significantly and by more than the minimum effect.
    Improved,
    /// Neither.
    Unchanged,
}

impl SpeedupVerdict {
    /// Lower-case word for the verdict.
    pub fn word(self) -> &'static str {
        match self {
            SpeedupVerdict::Regressed => "regressed",
            SpeedupVerdict::Improved => "improved",
            SpeedupVerdict::Unchanged => "unchanged",
        }
    }
}

/// The speedup of one series at one point, in baseline and new run.
#[derive(Clone, Debug, PartialEq)]
pub struct SpeedupComparison {
    /// The series label.
    pub series: String,
    /// The point, e.g. `objects 1000 (threads 1)`.
    pub point: String,
    /// Baseline speedup (reference median / series median) with its 95% interval.
    pub old: Estimate,
    /// New speedup with its 95% interval.
    pub new: Estimate,
    /// `new.value / old.value`.
    pub ratio: f64,
    /// Lower end of the ratio's 95% bootstrap interval.
    pub lo: f64,
    /// Upper end of the ratio's 95% bootstrap interval.
    pub hi: f64,
    /// Regressed, improved or unchanged.
    pub verdict: SpeedupVerdict,
    /// Whether this point can fail the check (its threads equal `gate_threads`).
    pub gating: bool,
}

/// Everything the check found.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOutcome {
    /// Counter differences, one per configuration and column.
    pub counter_changes: Vec<CounterChange>,
    /// Configurations present on one side only, described.
    pub missing: Vec<String>,
    /// Speedup comparisons, by series then point.
    pub speedups: Vec<SpeedupComparison>,
    /// Configurations present on both sides.
    pub common: usize,
    /// The gate: a gating regression, or counter changes / missing configurations not accepted.
    pub failed: bool,
}

/// Compares `run_dir/runs.csv` with `baseline_dir/runs.csv`.
pub fn compare(
    run_dir: &Path,
    baseline_dir: &Path,
    spec: &ReportSpec,
    options: &CheckOptions,
) -> Result<CheckOutcome, Error> {
    let (new_path, old_path) = (run_dir.join("runs.csv"), baseline_dir.join("runs.csv"));
    let new = rows::read(&new_path)?;
    let old = rows::read(&old_path)?;
    let mismatch = |message: String| Error::Mismatch { path: new_path.clone(), message };
    let (new_exp, old_exp) = (experiments(&new), experiments(&old));
    if new_exp != old_exp {
        return Err(mismatch(format!(
            "experiments do not match: run is {}, baseline is {} ({})",
            new_exp.into_iter().collect::<Vec<_>>().join("+"),
            old_exp.into_iter().collect::<Vec<_>>().join("+"),
            old_path.display()
        )));
    }
    if !new.is_numeric(&options.metric) || !old.is_numeric(&options.metric) {
        let path = if new.is_numeric(&options.metric) { old_path.clone() } else { new_path.clone() };
        return Err(Error::MissingColumn { path, column: options.metric.clone() });
    }

    let describe = Describer::new(spec, &new.runs, &old.runs);
    let (new_first, old_first) = (first_repetitions(&new.runs), first_repetitions(&old.runs));
    let mut counter_changes = Vec::new();
    let mut missing = Vec::new();
    let mut common = 0;
    for (id, run) in &old_first {
        if !new_first.contains_key(id) {
            missing.push(format!("only in baseline: {id} {}, {}", run.series(), describe.settings(run)));
        }
    }
    for (id, run) in &new_first {
        let Some(base) = old_first.get(id) else {
            missing.push(format!("only in run: {id} {}, {}", run.series(), describe.settings(run)));
            continue;
        };
        common += 1;
        for column in COUNTERS.iter().filter(|c| has_column(&new, c) && has_column(&old, c)) {
            let (o, n) = (base.text(column), run.text(column));
            if o != n {
                counter_changes.push(CounterChange {
                    config_id: id.to_string(),
                    series: run.series().into(),
                    settings: describe.settings(run),
                    column: column.to_string(),
                    old: o.into(),
                    new: n.into(),
                });
            }
        }
    }
    if common == 0 {
        return Err(mismatch(format!("no configuration in common with baseline {}", old_path.display())));
    }

    let speedups = match &spec.reference {
        Some(reference) => speedups(spec, reference, &new.runs, &old.runs, options),
        None => Vec::new(),
    };
    let regressed = speedups.iter().any(|s| s.gating && s.verdict == SpeedupVerdict::Regressed);
    let unaccepted = !options.accept_counter_changes && (!counter_changes.is_empty() || !missing.is_empty());
    Ok(CheckOutcome { counter_changes, missing, speedups, common, failed: regressed || unaccepted })
}

/// Distinct `experiment` values of a file (failed rows included).
fn experiments(rows: &Rows) -> BTreeSet<String> {
    rows.runs.iter().chain(&rows.failed).map(|r| r.text("experiment").to_string()).collect()
}

/// Whether the file has `column`.
fn has_column(rows: &Rows, column: &str) -> bool {
    rows.frame.schema().get(column).is_some()
}

/// Per configuration id, its run with the smallest repetition index.
fn first_repetitions(runs: &[Run]) -> BTreeMap<&str, &Run> {
    let mut first: BTreeMap<&str, &Run> = BTreeMap::new();
    for run in runs {
        let entry = first.entry(run.config_id()).or_insert(run);
        if run.num("repetition") < entry.num("repetition") {
            *entry = run;
        }
    }
    first
}

/// Describes a configuration by scene plus the settings that vary across both files.
struct Describer<'a> {
    spec: &'a ReportSpec,
    varying: Vec<&'static str>,
}

impl<'a> Describer<'a> {
    fn new(spec: &'a ReportSpec, new: &[Run], old: &[Run]) -> Self {
        let all: Vec<&Run> = new.iter().chain(old).collect();
        let varying = SETTINGS
            .iter()
            .copied()
            .filter(|c| *c != "scene")
            .filter(|c| all.iter().any(|r| r.text(c) != all[0].text(c)))
            .collect();
        Describer { spec, varying }
    }

    fn settings(&self, run: &Run) -> String {
        let fixed = self.spec.series_fixed.get(run.series());
        let mut parts = vec![run.text("scene").to_string()];
        for column in &self.varying {
            if !fixed.is_some_and(|f| f.iter().any(|c| c == column)) {
                parts.push(format!("{column} {}", run.text(column)));
            }
        }
        parts.join(" ")
    }
}

/// The key of a seed pool: series plus every setting except `seed`.
fn pool_key(run: &Run) -> Vec<String> {
    let mut key = vec![run.series().to_string()];
    key.extend(SETTINGS.iter().filter(|c| **c != "seed").map(|c| run.text(c).to_string()));
    key
}

/// Speedup comparisons of every non-reference series at every point present in both runs.
pub(crate) fn speedups(
    spec: &ReportSpec,
    reference: &str,
    new: &[Run],
    old: &[Run],
    options: &CheckOptions,
) -> Vec<SpeedupComparison> {
    let metric = options.metric.as_str();
    let old_pools: BTreeMap<Vec<String>, Vec<&Run>> =
        pool::seed_pools(old).into_iter().map(|group| (pool_key(group[0]), group)).collect();
    let mut series: Vec<String> = spec.series.clone();
    for run in new {
        if !series.iter().any(|s| s == run.series()) {
            series.push(run.series().to_string());
        }
    }
    let mut out = Vec::new();
    for label in series.iter().filter(|s| *s != reference) {
        for (fixed, groups) in pool::curves_of(new, label, "objects") {
            for (x, new_group) in groups {
                let Some(old_group) = old_pools.get(&pool_key(new_group[0])) else { continue };
                let side = |runs: &[Run], group: &[&Run]| {
                    let reference_runs = pool::counterparts(spec, runs, reference, group, &["seed"]);
                    (pool::samples(reference_runs, metric), pool::samples(group.iter().copied(), metric))
                };
                let (ref_new, ser_new) = side(new, &new_group);
                let (ref_old, ser_old) = side(old, old_group);
                if [&ref_new, &ser_new, &ref_old, &ser_old].iter().any(|s| s.is_empty()) {
                    continue;
                }
                let threads = new_group[0].text("threads");
                let point = if fixed.contains("threads") || threads.is_empty() {
                    format!("objects {x} ({fixed})")
                } else if fixed.is_empty() {
                    format!("objects {x} (threads {threads})")
                } else {
                    format!("objects {x} ({fixed}, threads {threads})")
                };
                let key = format!("check|{reference}/{label}|{}|{metric}", pool_key(new_group[0]).join("|"));
                let old_e = stats::ratio_ci(&ref_old, &ser_old, stats::seed_for(&format!("{key}|old")));
                let new_e = stats::ratio_ci(&ref_new, &ser_new, stats::seed_for(&format!("{key}|new")));
                let ratio = new_e.value / old_e.value;
                let (lo, hi) = ratio_of_ratios_ci([&ref_new, &ser_new, &ref_old, &ser_old], stats::seed_for(&key));
                let verdict = if hi < 1.0 && ratio < 1.0 - options.min_effect {
                    SpeedupVerdict::Regressed
                } else if lo > 1.0 && ratio > 1.0 + options.min_effect {
                    SpeedupVerdict::Improved
                } else {
                    SpeedupVerdict::Unchanged
                };
                let gating = new_group.iter().all(|r| r.num("threads") == options.gate_threads as f64);
                out.push(SpeedupComparison {
                    series: label.clone(),
                    point,
                    old: old_e,
                    new: new_e,
                    ratio,
                    lo,
                    hi,
                    verdict,
                    gating,
                });
            }
        }
    }
    out
}

/// 95% percentile-bootstrap interval of `(med(a)/med(b)) / (med(c)/med(d))`, all four resampled independently.
fn ratio_of_ratios_ci(sets: [&[f64]; 4], seed: u64) -> (f64, f64) {
    let sorted: Vec<Vec<f64>> = sets.iter().map(|s| stats::sorted(s)).collect();
    let mut rng = SplitMix64::new(seed);
    let mut scratch = Vec::new();
    let replicates = (0..stats::RESAMPLES)
        .map(|_| {
            let [a, b, c, d] = [0, 1, 2, 3].map(|i| stats::resampled_median(&sorted[i], &mut rng, &mut scratch));
            (a / b) / (c / d)
        })
        .collect();
    stats::percentile_interval(replicates)
}

impl CheckOutcome {
    /// A Markdown section for CI logs: overall result, counter table, speedup table (regressions first).
    pub fn markdown(&self) -> String {
        let mut md = String::from("## Regression check\n\n");
        let _ = writeln!(md, "**{}** — {}\n", if self.failed { "FAIL" } else { "PASS" }, self.reasons());
        if self.counter_changes.is_empty() {
            let _ = writeln!(md, "counters: all {} configurations identical\n", self.common);
        } else {
            md.push_str("| configuration | column | old → new |\n|---|---|---|\n");
            for c in &self.counter_changes {
                let _ = writeln!(
                    md,
                    "| `{}` {}, {} | {} | {} → {} |",
                    c.config_id,
                    cell(&c.series),
                    cell(&c.settings),
                    c.column,
                    cell(&c.old),
                    cell(&c.new)
                );
            }
            md.push('\n');
        }
        if !self.missing.is_empty() {
            md.push_str("Configurations on one side only:\n\n");
            for m in &self.missing {
                let _ = writeln!(md, "- {}", m);
            }
            md.push('\n');
        }
        if !self.speedups.is_empty() {
            md.push_str("| series | point | baseline speedup [95% CI] | new speedup [95% CI] | new/old [95% CI] | verdict | gates? |\n");
            md.push_str("|---|---|---|---|---|---|---|\n");
            let mut rows: Vec<&SpeedupComparison> = self.speedups.iter().collect();
            rows.sort_by_key(|s| match s.verdict {
                SpeedupVerdict::Regressed => 0,
                SpeedupVerdict::Improved => 1,
                SpeedupVerdict::Unchanged => 2,
            });
            for s in rows {
                let verdict = match s.verdict {
                    SpeedupVerdict::Regressed => "**regressed**",
                    v => v.word(),
                };
                let _ = writeln!(
                    md,
                    "| {} | {} | {} [{}, {}] | {} [{}, {}] | {} [{}, {}] | {} | {} |",
                    cell(&s.series),
                    cell(&s.point),
                    num(s.old.value),
                    num(s.old.lo),
                    num(s.old.hi),
                    num(s.new.value),
                    num(s.new.lo),
                    num(s.new.hi),
                    num(s.ratio),
                    num(s.lo),
                    num(s.hi),
                    verdict,
                    if s.gating { "yes" } else { "no" }
                );
            }
            md.push('\n');
        }
        md
    }

    /// Why the check passed or failed, in one line.
    fn reasons(&self) -> String {
        let regressions: Vec<String> = self
            .speedups
            .iter()
            .filter(|s| s.gating && s.verdict == SpeedupVerdict::Regressed)
            .map(|s| format!("{} at {}", s.series, s.point))
            .collect();
        let mut reasons = Vec::new();
        if !regressions.is_empty() {
            reasons.push(format!("{} gating regression(s): {}", regressions.len(), regressions.join("; ")));
        }
        // Without a gating regression, the check fails exactly when these were not accepted.
        let accepted = if !self.failed {
            " (accepted)"
        } else if regressions.is_empty() {
            " (not accepted)"
        } else {
            ""
        };
        if !self.counter_changes.is_empty() {
            reasons.push(format!("{} counter change(s){accepted}", self.counter_changes.len()));
        }
        if !self.missing.is_empty() {
            reasons.push(format!("{} configuration(s) on one side only{accepted}", self.missing.len()));
        }
        if reasons.is_empty() {
            format!("no gating regression among {} speedup comparison(s); counters identical", self.speedups.len())
        } else {
            reasons.join("; ")
        }
    }

    /// Every measure as a JSON document: speedups (value, lower, upper of old, new, ratio), counter changes, missing, failed.
    pub fn to_json(&self) -> String {
        let estimate = |e: &Estimate| {
            format!(
                "{{\"value\": {}, \"lower\": {}, \"upper\": {}}}",
                json_num(e.value),
                json_num(e.lo),
                json_num(e.hi)
            )
        };
        let speedups: Vec<String> = self
            .speedups
            .iter()
            .map(|s| {
                let ratio = Estimate { value: s.ratio, lo: s.lo, hi: s.hi };
                format!(
                    "    {{\"series\": {}, \"point\": {}, \"old\": {}, \"new\": {}, \"ratio\": {}, \"verdict\": {}, \"gating\": {}}}",
                    json_str(&s.series),
                    json_str(&s.point),
                    estimate(&s.old),
                    estimate(&s.new),
                    estimate(&ratio),
                    json_str(s.verdict.word()),
                    s.gating
                )
            })
            .collect();
        let changes: Vec<String> = self
            .counter_changes
            .iter()
            .map(|c| {
                format!(
                    "    {{\"config_id\": {}, \"series\": {}, \"settings\": {}, \"column\": {}, \"old\": {}, \"new\": {}}}",
                    json_str(&c.config_id),
                    json_str(&c.series),
                    json_str(&c.settings),
                    json_str(&c.column),
                    json_str(&c.old),
                    json_str(&c.new)
                )
            })
            .collect();
        let missing: Vec<String> = self.missing.iter().map(|m| format!("    {}", json_str(m))).collect();
        let list = |items: Vec<String>| {
            if items.is_empty() { "[]".to_string() } else { format!("[\n{}\n  ]", items.join(",\n")) }
        };
        format!(
            "{{\n  \"failed\": {},\n  \"common_configurations\": {},\n  \"speedups\": {},\n  \"counter_changes\": {},\n  \"missing\": {}\n}}\n",
            self.failed,
            self.common,
            list(speedups),
            list(changes),
            list(missing)
        )
    }
}

/// A Markdown table cell: pipes escaped, line breaks flattened.
fn cell(text: &str) -> String {
    text.replace('|', "\\|").replace(['\n', '\r'], " ")
}

/// A JSON number, `null` when not finite.
fn json_num(v: f64) -> String {
    if v.is_finite() { format!("{v}") } else { "null".into() }
}

/// A JSON string literal.
fn json_str(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}
