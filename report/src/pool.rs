//! Pooling samples: which runs stand for the same point, and which runs of another series they
//! are compared with (the matching rule shared by speedups, speedup figures and claims).

use std::sync::LazyLock;

use crate::rows::{POINT, Run};
use crate::spec::ReportSpec;
use crate::stats::{self, Estimate};
use schema::column;

/// One point of a series: an x value with the pooled estimate of a metric or a ratio.
#[derive(Clone, Debug)]
pub struct Point {
    /// The x value.
    pub x: f64,
    /// Median (or ratio of medians) with its 95% interval.
    pub estimate: Estimate,
    /// Largest `threads` among the point's runs of the series itself.
    pub threads: f64,
    /// Largest `threads` among the runs the series is compared with (ratio curves; NaN for metric curves).
    pub reference_threads: f64,
    /// The series' runs behind the point: how many, and their commits and machines.
    pub provenance: Provenance,
}

/// How many runs stand behind a point, and which commits and machines recorded them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Provenance {
    /// Number of runs (repetitions and seeds pooled).
    pub n: usize,
    /// Distinct `git_commit` values, in order of appearance.
    pub commits: Vec<String>,
    /// Distinct machines as `cpu_model (machine_id)`, in order of appearance.
    pub machines: Vec<String>,
    /// Distinct worker processes that timed them (`process_id`; 0, rows recorded before the column, not counted).
    pub processes: usize,
}

impl Provenance {
    /// The provenance of `group`.
    pub fn of(group: &[&Run]) -> Provenance {
        Provenance {
            n: group.len(),
            commits: crate::distinct(group.iter().map(|r| r.text(column::git_commit).to_string())),
            machines: crate::distinct(group.iter().map(|r| r.machine())),
            processes: processes(group.iter().copied()),
        }
    }
}

/// How many distinct worker processes timed `runs` (`process_id`; 0, rows recorded before the column, not counted).
pub fn processes<'a>(runs: impl IntoIterator<Item = &'a Run>) -> usize {
    runs.into_iter().map(|r| r.row.process_id).filter(|&id| id != 0).collect::<std::collections::HashSet<_>>().len()
}

/// Whether `other` is `run`'s counterpart: equal on every setting column and the machine, except the
/// settings the two runs' series fix (`spec.series_fixed`) and those in `ignore`.
pub fn matches(spec: &ReportSpec, run: &Run, other: &Run, ignore: &[&str]) -> bool {
    // Each point column with its index, looked up once: this runs for every pair of runs a ratio compares (a
    // column the schema does not declare reads "" in every run, so it always matches).
    static POINT_AT: LazyLock<Vec<(&str, usize)>> =
        LazyLock::new(|| POINT.iter().filter_map(|&c| crate::rows::index_of(c).map(|at| (c, at))).collect());
    let fixed = |series: &str, column: &str| {
        spec.series_fixed.get(series).is_some_and(|columns| columns.iter().any(|c| c == column))
    };
    POINT_AT.iter().all(|&(column, at)| {
        run.text_at(at) == other.text_at(at)
            || ignore.contains(&column)
            || fixed(run.series(), column)
            || fixed(other.series(), column)
    })
}

/// The finite values of `metric` over `runs`.
pub fn samples<'a>(runs: impl IntoIterator<Item = &'a Run>, metric: &str) -> Vec<f64> {
    runs.into_iter().map(|run| run.num(metric)).filter(|v| v.is_finite()).collect()
}

/// The runs of series `other` that match at least one of `group` (see [`matches`]).
pub fn counterparts<'a>(
    spec: &ReportSpec,
    runs: &'a [Run],
    other: &str,
    group: &[&Run],
    ignore: &[&str],
) -> Vec<&'a Run> {
    runs.iter()
        .filter(|candidate| candidate.series() == other)
        .filter(|candidate| group.iter().any(|run| matches(spec, run, candidate, ignore)))
        .collect()
}

/// The runs of `group` paired with their counterparts in series `other` from the same rounds: equal on every setting
/// but those the series fix (seeds included, whatever `ratio_against` ignores) and on `repetition`. A run whose
/// round `other` did not reach (adaptive repetitions stopped one side first: `other` has runs of that setting, not of
/// that round) is left out, as are `other`'s rounds the group did not reach. `None` when a run has no counterpart at
/// all, or two, or shares one with another run, when a side lacks `metric`, or when fewer than two rounds pair.
/// The third list names each round's pair of processes (`process_id` of both sides).
fn rounds(
    spec: &ReportSpec,
    runs: &[Run],
    other: &str,
    group: &[&Run],
    metric: &str,
) -> Option<(Vec<f64>, Vec<f64>, Vec<u64>)> {
    let mut taken = std::collections::HashSet::new();
    let mut pairs = (Vec::new(), Vec::new(), Vec::new());
    for run in group {
        let counterpart = |candidate: &&Run| candidate.series() == other && matches(spec, run, candidate, &[]);
        let mut partners = runs
            .iter()
            .enumerate()
            .filter(|(_, candidate)| candidate.row.repetition == run.row.repetition && counterpart(candidate));
        let Some((index, partner)) = partners.next() else {
            if runs.iter().any(|candidate| counterpart(&candidate)) {
                continue; // `other` stopped before this round
            }
            return None;
        };
        let (a, b) = (partner.num(metric), run.num(metric));
        if partners.next().is_some() || !taken.insert(index) || !a.is_finite() || !b.is_finite() {
            return None;
        }
        pairs.0.push(a);
        pairs.1.push(b);
        pairs.2.push(u64::from(partner.row.process_id) << 32 | u64::from(run.row.process_id));
    }
    (pairs.0.len() >= 2).then_some(pairs)
}

/// The per-round ratios of two series timed in the same rounds, each with the pair of processes that timed it.
#[derive(Clone, Debug)]
pub struct RoundRatios {
    /// `metric(other) / metric(group)`, one per round.
    pub ratios: Vec<f64>,
    /// The processes of each round (both sides' `process_id`): rounds of one pair share their offsets.
    pub processes: Vec<u64>,
}

impl RoundRatios {
    /// Their median with its 95% interval: resampling processes ([`stats::clustered_ratio_ci`]) where the rounds
    /// ran in at least [`stats::MIN_SAMPLES_FOR_INTERVAL`] pairs of processes (`processes` in the config), else
    /// the rounds' distribution-free interval ([`stats::median_ci`], which does not carry an offset of the one
    /// or few processes they ran in; docs/statistics.md, "Processes"). `key` seeds the bootstrap.
    pub fn estimate(&self, key: &str) -> Estimate {
        let over_processes = stats::clustered_ratio_ci(&self.ratios, &self.processes, stats::seed_for(key));
        if over_processes.lo.is_nan() { stats::median_ci(&self.ratios) } else { over_processes }
    }
}

/// The per-round ratios `metric(other) / metric(group)` over the rounds both series ran (see [`rounds`]; at least
/// two), else `None`.
pub fn round_ratios(spec: &ReportSpec, runs: &[Run], other: &str, group: &[&Run], metric: &str) -> Option<RoundRatios> {
    let (num, den, processes) = rounds(spec, runs, other, group, metric)?;
    Some(RoundRatios { ratios: num.iter().zip(&den).map(|(n, d)| n / d).collect(), processes })
}

/// `metric(other) / metric(group)` at one point, with its interval; `None` when there is no counterpart or no
/// sample. Where the two series ran in the same rounds (every run of the group has one counterpart of the same
/// repetition, or its setting's counterparts stopped earlier; see [`rounds`]) it is the median of the per-round
/// ratios over the rounds both ran, with its interval ([`RoundRatios::estimate`]: processes resampled where the
/// rounds ran in several); otherwise the ratio of the two medians, each side resampled on its own
/// ([`stats::ratio_ci`]). `key` seeds the bootstrap.
pub fn ratio_against(
    spec: &ReportSpec,
    runs: &[Run],
    other: &str,
    group: &[&Run],
    metric: &str,
    ignore: &[&str],
    key: &str,
) -> Option<Estimate> {
    let numerator = samples(counterparts(spec, runs, other, group, ignore), metric);
    let denominator = samples(group.iter().copied(), metric);
    if numerator.is_empty() || denominator.is_empty() {
        return None;
    }
    if let Some(ratios) = round_ratios(spec, runs, other, group, metric) {
        return Some(ratios.estimate(key));
    }
    Some(stats::ratio_ci(&numerator, &denominator, stats::seed_for(key)))
}

/// One line of a figure or one claim's set of points: a series, with any setting other than
/// seed and x that varies within the series held fixed (so that, say, thread counts are never pooled).
#[derive(Clone, Debug)]
pub struct Curve {
    /// The settings held fixed, e.g. `threads 4` (empty when only seeds and x vary).
    pub fixed: String,
    /// Points in ascending x.
    pub points: Vec<Point>,
}

/// One curve's runs: the settings held fixed (as [`Curve::fixed`]) and its runs grouped by x value.
pub(crate) type CurveRuns<'a> = (String, Vec<(f64, Vec<&'a Run>)>);

/// The values of a text x column (e.g. `workload`) in order of first appearance in `runs`: a category axis that
/// places them at 1, 2, …; `None` for a numeric column.
pub fn categories(runs: &[Run], x: &str) -> Option<Vec<String>> {
    if runs.iter().any(|r| r.num(x).is_finite()) {
        return None;
    }
    let values = crate::distinct(runs.iter().map(|r| r.text(x)).filter(|t| !t.is_empty()).map(String::from));
    (!values.is_empty()).then_some(values)
}

/// True when setting `c` only renames a numeric x value: one value of `c` at each x, a different one at each x
/// (the data set on a `primitives` axis): it makes no curves of its own.
fn names_x(runs: &[&Run], c: &str, x_of: impl Fn(&Run) -> f64) -> bool {
    let mut pairs: Vec<(u64, &str)> = runs.iter().map(|r| (x_of(r).to_bits(), r.text(c))).collect();
    pairs.sort_unstable();
    pairs.dedup();
    let xs = crate::distinct(pairs.iter().map(|p| p.0)).len();
    let cs = crate::distinct(pairs.iter().map(|p| p.1)).len();
    pairs.len() == xs && xs == cs
}

/// The runs of `series` split into curves (see [`Curve`]), each grouped by x value (ascending). A text x column
/// is a category axis ([`categories`] of all `runs`). Runs without an x value are left out.
pub(crate) fn curves_of<'a>(runs: &'a [Run], series: &str, x: &str) -> Vec<CurveRuns<'a>> {
    let categories = categories(runs, x);
    let x_of = |r: &Run| match &categories {
        None => r.num(x),
        Some(values) => values.iter().position(|v| v == r.text(x)).map_or(f64::NAN, |i| (i + 1) as f64),
    };
    let own: Vec<&Run> = runs.iter().filter(|r| r.series() == series && x_of(r).is_finite()).collect();
    let varying: Vec<&str> = POINT
        .iter()
        .copied()
        .filter(|c| *c != column::seed && *c != x)
        .filter(|c| own.iter().any(|r| r.text(c) != own[0].text(c)))
        .filter(|c| categories.is_some() || !names_x(&own, c, x_of))
        .collect();
    let mut curves: Vec<CurveRuns> = Vec::new();
    for run in own {
        let fixed = varying.iter().map(|c| format!("{c} {}", run.text(c))).collect::<Vec<_>>().join(", ");
        let index = match curves.iter().position(|(f, _)| *f == fixed) {
            Some(index) => index,
            None => {
                curves.push((fixed, Vec::new()));
                curves.len() - 1
            }
        };
        let groups = &mut curves[index].1;
        let value = x_of(run);
        match groups.iter_mut().find(|(v, _)| *v == value) {
            Some((_, group)) => group.push(run),
            None => groups.push((value, vec![run])),
        }
    }
    for (_, groups) in &mut curves {
        groups.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    curves
}

fn max_threads(group: &[&Run]) -> f64 {
    group.iter().map(|run| run.num(column::threads)).fold(f64::NAN, f64::max)
}

/// The curves of `series` against `x`, each point estimated by `estimate(fixed, x value, runs there)`, which
/// also gives the reference side's largest thread count.
fn curves_with(
    runs: &[Run],
    series: &str,
    x: &str,
    estimate: impl Fn(&str, f64, &[&Run]) -> Option<(stats::Estimate, f64)>,
) -> Vec<Curve> {
    curves_of(runs, series, x)
        .into_iter()
        .map(|(fixed, groups)| {
            let points = groups
                .into_iter()
                .filter_map(|(xv, group)| {
                    let (estimate, reference_threads) = estimate(&fixed, xv, &group)?;
                    Some(Point {
                        x: xv,
                        estimate,
                        threads: max_threads(&group),
                        reference_threads,
                        provenance: Provenance::of(&group),
                    })
                })
                .collect();
            Curve { fixed, points }
        })
        .collect()
}

/// Curves of `metric` against `x` for one series, each point pooled over seeds.
pub fn metric_curves(runs: &[Run], series: &str, x: &str, metric: &str) -> Vec<Curve> {
    curves_with(runs, series, x, |_, _, group| {
        let values = samples(group.iter().copied(), metric);
        (!values.is_empty()).then(|| (stats::median_ci(&values), f64::NAN))
    })
}

/// One point per setting combination of `series` (seeds pooled): the median of metric `x` against the median and
/// 95% interval of metric `y` (the trade-off of two metrics, e.g. build time against trace time).
pub fn trade_off_curves(runs: &[Run], series: &str, x: &str, y: &str) -> Vec<Curve> {
    curves_of(runs, series, column::seed)
        .into_iter()
        .filter_map(|(fixed, groups)| {
            let group: Vec<&Run> = groups.into_iter().flat_map(|(_, g)| g).collect();
            let (xs, ys) = (samples(group.iter().copied(), x), samples(group.iter().copied(), y));
            if xs.is_empty() || ys.is_empty() {
                return None;
            }
            let x_median = stats::median(&xs);
            let estimate = stats::median_ci(&ys);
            let point = Point {
                x: x_median,
                estimate,
                threads: max_threads(&group),
                reference_threads: f64::NAN,
                provenance: Provenance::of(&group),
            };
            Some(Curve { fixed, points: vec![point] })
        })
        .collect()
}

/// Curves of `metric(other) / metric(series)` against `x`, each point pooled over seeds; `other`'s
/// samples at a point are the counterparts (see [`matches`]) of the series' runs there, seeds ignored.
pub fn ratio_curves(spec: &ReportSpec, runs: &[Run], other: &str, series: &str, x: &str, metric: &str) -> Vec<Curve> {
    curves_with(runs, series, x, |fixed, xv, group| {
        let key = format!("{other}/{series}|{fixed}|{x}={xv}|{metric}");
        let estimate = ratio_against(spec, runs, other, group, metric, &[column::seed], &key)?;
        Some((estimate, max_threads(&counterparts(spec, runs, other, group, &[column::seed]))))
    })
}

/// How claims and the site's ratio matrix name a point of a curve: its settings (`fixed`) where it has no object
/// count (a mesh), else its object count with them.
pub fn point_label(fixed: &str, x: f64) -> String {
    match (fixed.is_empty(), x == 0.0) {
        (true, true) => "its only point (the claim's `where`)".to_string(),
        (false, true) => fixed.to_string(),
        (false, false) => format!("{x} objects ({fixed})"),
        (true, _) => format!("{x} objects"),
    }
}

/// The key of a run's seed pool: series plus every setting except `seed` (see `schema::row::pool_key`).
pub fn pool_key(run: &Run) -> Vec<String> {
    schema::row::pool_key(run.series(), |column| run.text(column).to_string())
}

/// Runs grouped by configuration with seeds pooled (see [`pool_key`]), in order of first appearance.
pub fn seed_pools(runs: &[Run]) -> Vec<Vec<&Run>> {
    let key = pool_key;
    let mut pools: Vec<(Vec<String>, Vec<&Run>)> = Vec::new();
    for run in runs {
        let k = key(run);
        match pools.iter_mut().find(|(existing, _)| *existing == k) {
            Some((_, group)) => group.push(run),
            None => pools.push((k, vec![run])),
        }
    }
    pools.into_iter().map(|(_, group)| group).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The golden rows (two series, 10 and 100 objects, two seeds, three repetitions each).
    fn golden() -> Vec<Run> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/runs.csv");
        crate::rows::read(&path).unwrap().runs
    }

    #[test]
    fn trade_off_points_are_the_medians_of_both_metrics_per_setting() {
        let runs = golden();
        let series = runs[0].series().to_string();
        let curves = trade_off_curves(&runs, &series, column::trace_s, column::total_s);
        let by_objects = |metric| metric_curves(&runs, &series, column::objects, metric).remove(0).points;
        let (trace, total) = (by_objects(column::trace_s), by_objects(column::total_s));
        assert_eq!(curves.len(), trace.len(), "one point per object count, seeds pooled");
        for (curve, (t, s)) in curves.iter().zip(trace.iter().zip(&total)) {
            assert_eq!(curve.fixed, format!("objects {}", t.x));
            let [p] = curve.points.as_slice() else { panic!("one point per curve: {curve:?}") };
            assert_eq!((p.x, p.estimate.value), (t.estimate.value, s.estimate.value));
            assert!(p.estimate.lo <= p.estimate.value && p.estimate.value <= p.estimate.hi);
        }
        assert!(trade_off_curves(&runs, "no such series", column::trace_s, column::total_s).is_empty());
    }

    #[test]
    fn rounds_pair_over_the_rounds_both_series_ran() {
        let runs = golden();
        let (a, b) = (
            runs[0].series().to_string(),
            runs.iter().map(Run::series).find(|s| *s != runs[0].series()).unwrap().to_string(),
        );
        // Each series fixes its structure (the `[[series]]` tables of the golden config).
        let fixed: Vec<String> =
            ["accel", "split", "leaf_size", "sah_bins", "traversal", "sah_traversal_cost", "sah_intersection_cost"]
                .map(String::from)
                .into();
        let spec = ReportSpec {
            series_fixed: [(a.clone(), fixed.clone()), (b.clone(), fixed)].into_iter().collect(),
            ..ReportSpec::default()
        };
        let point = |runs: &[Run], series: &str| -> Vec<Run> {
            runs.iter()
                .filter(|r| r.series() == series && r.num(column::objects) == 10.0 && r.num(column::seed) == 1.0)
                .cloned()
                .collect()
        };
        let all = point(&runs, &a);
        let group: Vec<&Run> = all.iter().collect();
        let full = round_ratios(&spec, &runs, &b, &group, column::trace_s).expect("same rounds pair");
        assert_eq!(full.ratios.len(), 3);
        // `b` stopped a round early (adaptive repetitions): the two rounds both ran pair, the third is left out.
        let fewer: Vec<Run> = runs.iter().filter(|r| !(r.series() == b && r.row.repetition == 2)).cloned().collect();
        let shorter = round_ratios(&spec, &fewer, &b, &group, column::trace_s).expect("common rounds pair");
        assert_eq!(shorter.ratios, full.ratios[..2]);
        // The group stopped early: `b`'s extra round is left out.
        let first_two: Vec<&Run> = group.iter().copied().filter(|r| r.row.repetition < 2).collect();
        assert_eq!(round_ratios(&spec, &runs, &b, &first_two, column::trace_s).unwrap().ratios, full.ratios[..2]);
        // A setting `b` never ran (its seed left out) does not pair, whatever the rounds.
        let no_seed: Vec<Run> =
            runs.iter().filter(|r| !(r.series() == b && r.num(column::seed) == 1.0)).cloned().collect();
        assert!(round_ratios(&spec, &no_seed, &b, &group, column::trace_s).is_none());
        // One round in common is not a pair of rounds.
        let one: Vec<Run> = runs.iter().filter(|r| !(r.series() == b && r.row.repetition > 0)).cloned().collect();
        assert!(round_ratios(&spec, &one, &b, &group, column::trace_s).is_none());
    }
}
