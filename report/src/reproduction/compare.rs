//! Computing a [`Reproduction`]: the deterministic columns of every configuration both folders ran, every
//! series' time ratio to the reference at every point both ran ([`point_outcome`]), and every claim over the points
//! both ran ([`compare_claims`]).

use std::collections::BTreeMap;
use std::path::Path;

use schema::row::{COLUMNS, Role};
use schema::{Axis, column};

use super::{ClaimOutcome, Origin, Outcome, PointOutcome, Reproduction, resolution};
use crate::claims::{self, ClaimResult, PointResult};
use crate::error::Error;
use crate::rows::{self, Rows, Run};
use crate::spec::{ReportSpec, Verdict};
use crate::stats::Estimate;

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

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    fn e(value: f64, lo: f64, hi: f64) -> Estimate {
        Estimate { value, lo, hi }
    }

    pub(in crate::reproduction) fn point(label: &str, ratio: f64, lo: f64, hi: f64, verdict: Verdict) -> PointResult {
        PointResult { label: label.into(), ratio, lo, hi, threshold: 1.0, verdict, more: None, threads: 1.0 }
    }

    pub(in crate::reproduction) fn claim(points: Vec<PointResult>) -> ClaimResult {
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
}
