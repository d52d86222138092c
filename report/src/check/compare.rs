//! Computing a [`CheckOutcome`]: counters compared exactly per configuration, speedups compared with a
//! bootstrap interval of `new / old`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use tracer::rng::SplitMix64;

use super::{CheckOptions, CheckOutcome, CounterChange, SpeedupComparison, SpeedupVerdict};
use crate::error::Error;
use crate::pool::{self, pool_key};
use crate::rows::{self, Rows, Run, SETTINGS};
use crate::spec::ReportSpec;
use crate::stats;

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

    let Counters { changes: counter_changes, missing, common } = compare_counters(spec, &new, &old);
    if common == 0 {
        return Err(mismatch(format!("no configuration in common with baseline {}", old_path.display())));
    }

    let speedups = match &spec.reference {
        Some(reference) => speedups(spec, reference, &new.runs, &old.runs, options),
        None => Vec::new(),
    };
    let regressed = speedups.iter().any(|s| s.gating && s.verdict == SpeedupVerdict::Regressed);
    let unaccepted = !options.accept_counter_changes && (!counter_changes.is_empty() || !missing.is_empty());
    let timings_for_information = options.timings_for_information;
    Ok(CheckOutcome { counter_changes, missing, speedups, common, failed: regressed || unaccepted, timings_for_information })
}

/// What the counter comparison found.
struct Counters {
    /// Counter differences, one per configuration and column.
    changes: Vec<CounterChange>,
    /// Configurations present on one side only, described.
    missing: Vec<String>,
    /// Configurations present on both sides.
    common: usize,
}

/// Compares the [`super::counters`] of the first repetition of every configuration present in both files.
fn compare_counters(spec: &ReportSpec, new: &Rows, old: &Rows) -> Counters {
    let describe = Describer::new(spec, &new.runs, &old.runs);
    let (new_first, old_first) = (first_repetitions(&new.runs), first_repetitions(&old.runs));
    let mut changes = Vec::new();
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
        for column in super::counters().into_iter().filter(|c| has_column(new, c) && has_column(old, c)) {
            let (o, n) = (base.text(column), run.text(column));
            if o != n {
                changes.push(CounterChange {
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
    Counters { changes, missing, common }
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
                let verdict = verdict(ratio, lo, hi, options.min_effect);
                let gating = !options.timings_for_information
                    && new_group.iter().all(|r| r.num("threads") == options.gate_threads as f64);
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

/// Regressed or improved when the ratio's interval excludes 1 and the ratio moved by more than `min_effect`.
fn verdict(ratio: f64, lo: f64, hi: f64, min_effect: f64) -> SpeedupVerdict {
    if hi < 1.0 && ratio < 1.0 - min_effect {
        SpeedupVerdict::Regressed
    } else if lo > 1.0 && ratio > 1.0 + min_effect {
        SpeedupVerdict::Improved
    } else {
        SpeedupVerdict::Unchanged
    }
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
