//! Pooling samples: which runs stand for the same point, and which runs of another series they
//! are compared with (the matching rule shared by speedups, speedup figures and claims).

use crate::rows::{Run, SETTINGS};
use crate::spec::ReportSpec;
use crate::stats::{self, Estimate};

/// One point of a series: an x value with the pooled estimate of a metric or a ratio.
#[derive(Clone, Debug)]
pub struct Point {
    /// The x value.
    pub x: f64,
    /// Median (or ratio of medians) with its 95% bootstrap interval.
    pub estimate: Estimate,
    /// Largest `threads` among the point's runs of the series itself.
    pub threads: f64,
}

/// Whether `other` is `run`'s counterpart: equal on every setting column except those the two
/// runs' series fix (`spec.series_fixed`) and those in `ignore`.
pub fn matches(spec: &ReportSpec, run: &Run, other: &Run, ignore: &[&str]) -> bool {
    let fixed = |series: &str, column: &str| {
        spec.series_fixed.get(series).is_some_and(|columns| columns.iter().any(|c| c == column))
    };
    SETTINGS
        .iter()
        .filter(|column| !ignore.contains(column))
        .filter(|column| !fixed(run.series(), column) && !fixed(other.series(), column))
        .all(|column| run.text(column) == other.text(column))
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

/// `median(metric over other's counterparts) / median(metric over group)`, with its interval;
/// `None` when there is no counterpart or no sample. `key` seeds the bootstrap.
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
    Some(stats::ratio_ci(&numerator, &denominator, stats::seed_for(key)))
}

/// The runs of `series`, grouped by the value of column `x` (ascending); runs with no numeric x are left out.
pub fn by_x<'a>(runs: &'a [Run], series: &str, x: &str) -> Vec<(f64, Vec<&'a Run>)> {
    let mut groups: Vec<(f64, Vec<&Run>)> = Vec::new();
    for run in runs.iter().filter(|run| run.series() == series) {
        let value = run.num(x);
        if !value.is_finite() {
            continue;
        }
        match groups.iter_mut().find(|(v, _)| *v == value) {
            Some((_, group)) => group.push(run),
            None => groups.push((value, vec![run])),
        }
    }
    groups.sort_by(|a, b| a.0.total_cmp(&b.0));
    groups
}

fn max_threads(group: &[&Run]) -> f64 {
    group.iter().map(|run| run.num("threads")).fold(f64::NAN, f64::max)
}

/// Points of `metric` against `x` for one series, pooled over every other setting.
pub fn metric_points(runs: &[Run], series: &str, x: &str, metric: &str) -> Vec<Point> {
    by_x(runs, series, x)
        .into_iter()
        .filter_map(|(xv, group)| {
            let values = samples(group.iter().copied(), metric);
            if values.is_empty() {
                return None;
            }
            let key = format!("{series}|{x}={xv}|{metric}");
            let estimate = stats::median_ci(&values, stats::seed_for(&key));
            Some(Point { x: xv, estimate, threads: max_threads(&group) })
        })
        .collect()
}

/// Points of `metric(other) / metric(series)` against `x`, each pooled over seeds and every other
/// setting; `other`'s samples at a point are the counterparts of the series' runs there, seeds ignored.
pub fn ratio_points(
    spec: &ReportSpec,
    runs: &[Run],
    other: &str,
    series: &str,
    x: &str,
    metric: &str,
) -> Vec<Point> {
    by_x(runs, series, x)
        .into_iter()
        .filter_map(|(xv, group)| {
            let key = format!("{other}/{series}|{x}={xv}|{metric}");
            let estimate = ratio_against(spec, runs, other, &group, metric, &["seed"], &key)?;
            Some(Point { x: xv, estimate, threads: max_threads(&group) })
        })
        .collect()
}

/// Runs grouped by configuration with seeds pooled: series plus every setting except `seed`,
/// in order of first appearance.
pub fn seed_pools(runs: &[Run]) -> Vec<Vec<&Run>> {
    let key = |run: &Run| {
        let mut parts = vec![run.series().to_string()];
        parts.extend(SETTINGS.iter().filter(|c| **c != "seed").map(|c| run.text(c).to_string()));
        parts
    };
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
