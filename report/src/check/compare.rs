//! Computing a [`CheckOutcome`]: the timing mode, counters compared exactly per configuration, instruction counts
//! (module `instructions`), every configuration's phase times and the speedups compared with bootstrap intervals
//! of `new / old`; and the second measurement of flagged times ([`CheckOutcome::confirm`]).

use schema::column;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use tracer::rng::SplitMix64;

use super::{
    CheckOptions, CheckOutcome, CounterChange, SpeedupComparison, TIMED_PHASES, TimeComparison, TimeRatio, TimingMode,
    Verdict, instructions,
};
use crate::error::Error;
use crate::pool;
use crate::rows::{self, Rows, Run, SETTINGS};
use crate::spec::ReportSpec;
use crate::stats;

/// Compares `run_dir/runs.csv` with `baseline_dir/runs.csv`, and their `instructions.csv` where both have one.
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

    let describe = Describer::new(&new.runs, &old.runs);
    let Counters { changes: counter_changes, missing, common } = compare_counters(&describe, &new, &old);
    if common == 0 {
        return Err(mismatch(format!("no configuration in common with baseline {}", old_path.display())));
    }
    let mode = timing_mode(&new, &old, options.timings_for_information, options.max_extra_load);
    let times = times(&describe, &new.runs, &old.runs, &mode, options);
    let speedups = match &spec.reference {
        Some(reference) => speedups(spec, reference, &new.runs, &old.runs, options),
        None => Vec::new(),
    };
    let mut instructions = instructions::check(run_dir, baseline_dir, options.instruction_threshold)?;
    if let Some(stale) = counted_elsewhere(run_dir, &new)? {
        instructions.note.push_str(&format!(" (note: {stale})"));
    }
    Ok(CheckOutcome {
        mode,
        counter_changes,
        missing,
        instructions,
        times,
        speedups,
        common,
        accept_counter_changes: options.accept_counter_changes,
    })
}

impl CheckOutcome {
    /// Adds the second measurement of every flagged time ([`CheckOutcome::to_confirm`]) from `confirm_csv` (rows
    /// of those configurations measured again, in the format of `runs.csv`), compared with `baseline_dir`'s rows
    /// by the same rule. A flagged time without rows in `confirm_csv` keeps failing.
    pub fn confirm(&mut self, confirm_csv: &Path, baseline_dir: &Path, options: &CheckOptions) -> Result<(), Error> {
        let again = rows::read(confirm_csv)?;
        let old = rows::read(&baseline_dir.join("runs.csv"))?;
        let (again, old) = (by_config(&again.runs), by_config(&old.runs));
        for t in self.times.iter_mut().filter(|t| t.flagged()) {
            let (Some(new), Some(base)) = (again.get(t.config_id.as_str()), old.get(t.config_id.as_str())) else {
                continue;
            };
            let key = format!("check|time|{}|{}|confirm", t.config_id, t.metric);
            t.confirmation = time_ratio(
                &pool::samples(new.iter().copied(), t.metric),
                &pool::samples(base.iter().copied(), t.metric),
                &key,
                options.time_effect(t.metric),
            );
        }
        Ok(())
    }
}

/// Whether the run folder's instruction counts were made at another commit than its rows (counted before a
/// rebuild, or copied): says which, for the note.
fn counted_elsewhere(run_dir: &Path, rows: &Rows) -> Result<Option<String>, Error> {
    let path = run_dir.join(instructions::FILE);
    if !path.is_file() {
        return Ok(None);
    }
    let counted: BTreeSet<String> = instructions::read(&path)?.into_iter().map(|c| c.git_commit).collect();
    let timed: BTreeSet<String> = rows.runs.iter().map(|r| r.row.git_commit.clone()).collect();
    let short =
        |s: &BTreeSet<String>| s.iter().map(|c| c.chars().take(12).collect::<String>()).collect::<Vec<_>>().join("+");
    Ok((counted != timed)
        .then(|| format!("the run's counts were made at commit {}, its rows at {}", short(&counted), short(&timed))))
}

/// Same machine when every row of both files (failed ones included) has one and the same non-empty
/// `machine_id` and one and the same non-empty `boot_id`, and the run's median `load_avg_1m` exceeds the baseline's
/// by at most `max_extra_load`; else, or when `forced`, information only, saying why.
///
/// The boot is part of it because virtual machines of one kind share every fact `machine_id` hashes: a CI run on
/// another VM with this machine's `machine_id` built trees 1.3-1.8x slower than its baseline at equal trace times.
fn timing_mode(new: &Rows, old: &Rows, forced: bool, max_extra_load: f64) -> TimingMode {
    let ids = |rows: &Rows, column: fn(&schema::Row) -> &String| -> BTreeSet<String> {
        rows.runs.iter().chain(&rows.failed).map(|r| column(&r.row).clone()).collect()
    };
    let (n, o) = (ids(new, |r| &r.machine_id), ids(old, |r| &r.machine_id));
    let name = |ids: &BTreeSet<String>| -> String {
        let named: Vec<String> =
            ids.iter().map(|id| if id.is_empty() { "an unrecorded machine".to_string() } else { id.clone() }).collect();
        match named.len() {
            1 => format!("machine {}", named[0]),
            _ => format!("{} machines ({})", named.len(), named.join(", ")),
        }
    };
    if forced {
        return TimingMode::Information { reason: "forced by --timings-for-information".into() };
    }
    let machine_id = match (n.iter().next(), n.len(), o.len()) {
        (Some(id), 1, 1) if !id.is_empty() && n == o => id.clone(),
        _ => return TimingMode::Information { reason: format!("run on {}, baseline on {}", name(&n), name(&o)) },
    };
    let (nb, ob) = (ids(new, |r| &r.boot_id), ids(old, |r| &r.boot_id));
    let boot = |ids: &BTreeSet<String>| -> String {
        match (ids.len(), ids.iter().next()) {
            (1, Some(id)) if id.is_empty() => "no recorded boot".to_string(),
            (1, Some(id)) => format!("boot {}", short_boot(id)),
            _ => format!("{} boots", ids.len()),
        }
    };
    let boot_id = match (nb.iter().next(), nb.len(), ob.len()) {
        (Some(id), 1, 1) if !id.is_empty() && nb == ob => id.clone(),
        _ => {
            return TimingMode::Information {
                reason: format!(
                    "same hardware facts (machine_id {machine_id}) but the run is from {}, the baseline from {}: \
                     virtual machines of one kind share every fact machine_id hashes, so times gate only within one \
                     boot",
                    boot(&nb),
                    boot(&ob)
                ),
            };
        }
    };
    let load = |rows: &Rows| {
        stats::median(&rows.runs.iter().map(|r| r.row.load_avg_1m).filter(|l| l.is_finite()).collect::<Vec<_>>())
    };
    let (new_load, old_load) = (load(new), load(old));
    if new_load > old_load + max_extra_load {
        return TimingMode::Information {
            reason: format!(
                "same machine ({machine_id}), but the run was measured at a median 1-minute load of {new_load:.2}, more \
                 than {max_extra_load} above the baseline's {old_load:.2}"
            ),
        };
    }
    TimingMode::SameMachine { machine_id, boot_id }
}

/// The first 8 characters of a boot id.
pub(crate) fn short_boot(id: &str) -> &str {
    &id[..id.len().min(8)]
}

/// Runs by configuration id.
fn by_config(runs: &[Run]) -> BTreeMap<&str, Vec<&Run>> {
    let mut map: BTreeMap<&str, Vec<&Run>> = BTreeMap::new();
    for run in runs {
        map.entry(run.config_id()).or_default().push(run);
    }
    map
}

/// Every phase of [`TIMED_PHASES`] of every configuration timed on both sides, in the run's order.
fn times(
    describe: &Describer,
    new: &[Run],
    old: &[Run],
    mode: &TimingMode,
    options: &CheckOptions,
) -> Vec<TimeComparison> {
    let (new_by, old_by) = (by_config(new), by_config(old));
    let mut seen = BTreeSet::new();
    let mut out = Vec::new();
    for run in new {
        let id = run.config_id();
        if !seen.insert(id) {
            continue;
        }
        let Some(base) = old_by.get(id) else { continue };
        for metric in TIMED_PHASES {
            let (n, o) =
                (pool::samples(new_by[id].iter().copied(), metric), pool::samples(base.iter().copied(), metric));
            let key = format!("check|time|{id}|{metric}");
            let Some(first) = time_ratio(&n, &o, &key, options.time_effect(metric)) else { continue };
            out.push(TimeComparison {
                config_id: id.to_string(),
                series: run.series().to_string(),
                settings: describe.settings(run),
                threads: match run.num(column::threads) {
                    used if used.is_finite() => format!("{used}"),
                    _ => run.text(column::threads).to_string(),
                },
                metric,
                gating: mode.gates_times() && first.old.value >= options.min_time_s,
                first,
                confirmation: None,
            });
        }
    }
    out
}

/// Medians of `new` and `old` with intervals and their ratio new/old; slower (regressed) when the ratio's
/// interval lies above `1 + min_effect` (faster, improved, when it lies below `1 - min_effect`). `None` without
/// samples on either side.
fn time_ratio(new: &[f64], old: &[f64], key: &str, min_effect: f64) -> Option<TimeRatio> {
    if new.is_empty() || old.is_empty() {
        return None;
    }
    let ratio = stats::ratio_ci(new, old, stats::seed_for(key));
    let verdict = if ratio.lo > 1.0 + min_effect {
        Verdict::Regressed
    } else if ratio.hi < 1.0 - min_effect {
        Verdict::Improved
    } else {
        Verdict::Unchanged
    };
    Some(TimeRatio { old: stats::median_ci(old), new: stats::median_ci(new), ratio, verdict })
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
fn compare_counters(describe: &Describer, new: &Rows, old: &Rows) -> Counters {
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
    rows.runs.iter().chain(&rows.failed).map(|r| r.text(column::experiment).to_string()).collect()
}

/// Whether the file's header has `column` (a counter added since an older file was recorded is not compared).
fn has_column(rows: &Rows, column: &str) -> bool {
    rows.recorded.contains(column)
}

/// Per configuration id, its run with the smallest repetition index.
fn first_repetitions(runs: &[Run]) -> BTreeMap<&str, &Run> {
    let mut first: BTreeMap<&str, &Run> = BTreeMap::new();
    for run in runs {
        let entry = first.entry(run.config_id()).or_insert(run);
        if run.num(column::repetition) < entry.num(column::repetition) {
            *entry = run;
        }
    }
    first
}

/// Describes a configuration by its scene plus the settings that vary among its series' rows in both files.
struct Describer {
    varying: BTreeMap<String, Vec<&'static str>>,
}

impl Describer {
    fn new(new: &[Run], old: &[Run]) -> Self {
        let mut by_series: BTreeMap<&str, Vec<&Run>> = BTreeMap::new();
        for run in new.iter().chain(old) {
            by_series.entry(run.series()).or_default().push(run);
        }
        let varying = by_series
            .into_iter()
            .map(|(series, runs)| {
                let columns = SETTINGS
                    .iter()
                    .copied()
                    .filter(|c| *c != column::scene)
                    .filter(|c| runs.iter().any(|r| r.text(c) != runs[0].text(c)))
                    .collect();
                (series.to_string(), columns)
            })
            .collect();
        Describer { varying }
    }

    fn settings(&self, run: &Run) -> String {
        let mut parts = vec![run.text(column::scene).to_string()];
        for column in self.varying.get(run.series()).into_iter().flatten() {
            parts.push(format!("{column} {}", run.text(column)));
        }
        parts.join(" ")
    }
}

/// Speedup comparisons of every non-reference series at every point present in both runs (for information).
pub(crate) fn speedups(
    spec: &ReportSpec,
    reference: &str,
    new: &[Run],
    old: &[Run],
    options: &CheckOptions,
) -> Vec<SpeedupComparison> {
    let metric = options.metric.as_str();
    // Points are matched across the two files whatever machines recorded them (`pool_key` holds `machine_id`).
    let point_key = |run: &Run| {
        schema::row::pool_key(run.series(), |c| {
            if c == column::machine_id { String::new() } else { run.text(c).to_string() }
        })
    };
    let old_pools: BTreeMap<Vec<String>, Vec<&Run>> =
        pool::seed_pools(old).into_iter().map(|group| (point_key(group[0]), group)).collect();
    let mut series: Vec<String> = spec.series.clone();
    for run in new {
        if !series.iter().any(|s| s == run.series()) {
            series.push(run.series().to_string());
        }
    }
    let mut out = Vec::new();
    for label in series.iter().filter(|s| *s != reference) {
        for (fixed, groups) in pool::curves_of(new, label, column::objects) {
            for (x, new_group) in groups {
                let Some(old_group) = old_pools.get(&point_key(new_group[0])) else { continue };
                let side = |runs: &[Run], group: &[&Run]| {
                    let reference_runs = pool::counterparts(spec, runs, reference, group, &[column::seed]);
                    (pool::samples(reference_runs, metric), pool::samples(group.iter().copied(), metric))
                };
                let (ref_new, ser_new) = side(new, &new_group);
                let (ref_old, ser_old) = side(old, old_group);
                if [&ref_new, &ser_new, &ref_old, &ser_old].iter().any(|s| s.is_empty()) {
                    continue;
                }
                let threads = new_group[0].text(column::threads);
                let point = if fixed.contains(column::threads) || threads.is_empty() {
                    format!("objects {x} ({fixed})")
                } else if fixed.is_empty() {
                    format!("objects {x} (threads {threads})")
                } else {
                    format!("objects {x} ({fixed}, threads {threads})")
                };
                let key = format!("check|{reference}/{label}|{}|{metric}", point_key(new_group[0]).join("|"));
                // Where each run's series and reference ran in the same rounds, each speedup is the median of its
                // per-round ratios (as in reports and `ab`), and the change resamples those; else medians' ratios.
                let paired = (
                    pool::round_ratios(spec, new, reference, &new_group, metric),
                    pool::round_ratios(spec, old, reference, old_group, metric),
                );
                let (old_e, new_e, ratio, lo, hi) = if let (Some(r_new), Some(r_old)) = paired {
                    let old_e = r_old.estimate(&format!("{key}|old"));
                    let new_e = r_new.estimate(&format!("{key}|new"));
                    let change = stats::ratio_ci(&r_new.ratios, &r_old.ratios, stats::seed_for(&key));
                    (old_e, new_e, change.value, change.lo, change.hi)
                } else {
                    let old_e = stats::ratio_ci(&ref_old, &ser_old, stats::seed_for(&format!("{key}|old")));
                    let new_e = stats::ratio_ci(&ref_new, &ser_new, stats::seed_for(&format!("{key}|new")));
                    let sets = [&ref_new[..], &ser_new[..], &ref_old[..], &ser_old[..]];
                    let (lo, hi) = ratio_of_ratios_ci(sets, stats::seed_for(&key));
                    (old_e, new_e, new_e.value / old_e.value, lo, hi)
                };
                let verdict = verdict(ratio, lo, hi, options.min_effect);
                out.push(SpeedupComparison {
                    series: label.clone(),
                    point,
                    old: old_e,
                    new: new_e,
                    ratio,
                    lo,
                    hi,
                    verdict,
                });
            }
        }
    }
    out
}

/// A speedup regressed (fell) or improved when the ratio's interval excludes 1 and the ratio moved by more than
/// `min_effect`.
fn verdict(ratio: f64, lo: f64, hi: f64, min_effect: f64) -> Verdict {
    if hi < 1.0 && ratio < 1.0 - min_effect {
        Verdict::Regressed
    } else if lo > 1.0 && ratio > 1.0 + min_effect {
        Verdict::Improved
    } else {
        Verdict::Unchanged
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
