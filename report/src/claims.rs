//! Checking `[[claim]]`s: ratio `metric(than) / metric(series)` per object count, pooled over seeds.

use crate::pool::{self, Point};
use crate::rows::Rows;
use crate::spec::{ClaimKind, ClaimSpec, ReportSpec, Verdict};

/// A checked claim.
#[derive(Clone, Debug, PartialEq)]
pub struct ClaimResult {
    /// The claim in words.
    pub text: String,
    /// Holds, fails or inconclusive.
    pub verdict: Verdict,
    /// Ratio `metric(than) / metric(series)` at the least favourable point (NaN without points).
    pub ratio: f64,
    /// Lower end of that point's 95% interval.
    pub lo: f64,
    /// Upper end of that point's 95% interval.
    pub hi: f64,
    /// `Faster`: the factor the ratio must reach there; `Within`: the tolerance.
    pub threshold: f64,
    /// How many points were compared and which was least favourable.
    pub detail: String,
}

/// Checks every claim of `spec` against the rows.
pub fn check_all(rows: &Rows, spec: &ReportSpec) -> Vec<ClaimResult> {
    spec.claims.iter().map(|claim| check(rows, spec, claim)).collect()
}

/// Checks one claim.
pub fn check(rows: &Rows, spec: &ReportSpec, claim: &ClaimSpec) -> ClaimResult {
    let (series, than) = match &claim.kind {
        ClaimKind::Faster { series, than, .. } | ClaimKind::Within { series, than, .. } => (series, than),
    };
    // Every point of every curve (a curve per thread count etc. when those vary within the series).
    let in_range = |p: &Point| {
        claim.min_objects.is_none_or(|min| p.x >= min as f64) && claim.max_objects.is_none_or(|max| p.x <= max as f64)
    };
    let mut points: Vec<Point> = Vec::new();
    let mut labels: Vec<String> = Vec::new();
    let runs: Vec<crate::rows::Run> = rows.runs.iter().filter(|r| r.passes(&claim.filter)).cloned().collect();
    if rows.is_numeric(&claim.metric) {
        for curve in pool::ratio_curves(spec, &runs, than, series, "objects", &claim.metric) {
            for point in curve.points.into_iter().filter(in_range) {
                let fixed = if curve.fixed.is_empty() { String::new() } else { format!(" ({})", curve.fixed) };
                labels.push(format!("{} objects{fixed}", point.x));
                points.push(point);
            }
        }
    }
    let mut result = ClaimResult {
        text: claim.text.clone(),
        verdict: Verdict::Inconclusive,
        ratio: f64::NAN,
        lo: f64::NAN,
        hi: f64::NAN,
        threshold: f64::NAN,
        detail: String::new(),
    };
    if points.is_empty() {
        result.threshold = match claim.kind {
            ClaimKind::Faster { factor, .. } => factor,
            ClaimKind::Within { tolerance, .. } => tolerance,
        };
        result.detail = format!(
            "no points: no `{}` rows of {series} with matching {than} rows{}",
            claim.metric,
            objects_range(claim)
        );
        return result;
    }

    // Each point's (threshold, how far it is from failing: larger is safer, holds-side first).
    let judged: Vec<(f64, (f64, f64), Verdict)> = points
        .iter()
        .map(|p| {
            let e = p.estimate;
            match claim.kind {
                ClaimKind::Faster { factor, per_thread, .. } => {
                    let threshold = if per_thread { factor * p.threads } else { factor };
                    let verdict = if e.lo >= threshold {
                        Verdict::Holds
                    } else if e.hi < threshold {
                        Verdict::Fails
                    } else {
                        Verdict::Inconclusive
                    };
                    (threshold, (e.lo / threshold, e.hi / threshold), verdict)
                }
                ClaimKind::Within { tolerance, .. } => {
                    let (low, high) = (1.0 - tolerance, 1.0 + tolerance);
                    let verdict = if e.lo >= low && e.hi <= high {
                        Verdict::Holds
                    } else if e.hi < low || e.lo > high {
                        Verdict::Fails
                    } else {
                        Verdict::Inconclusive
                    };
                    // Distance of the interval's far and near ends from 1, negated: nearer is safer.
                    let far = (e.lo - 1.0).abs().max((e.hi - 1.0).abs());
                    let near =
                        if e.lo <= 1.0 && 1.0 <= e.hi { 0.0 } else { (e.lo - 1.0).abs().min((e.hi - 1.0).abs()) };
                    (tolerance, (-near, -far), verdict)
                }
            }
        })
        .collect();

    result.verdict = if judged.iter().any(|j| j.2 == Verdict::Fails) {
        Verdict::Fails
    } else if judged.iter().all(|j| j.2 == Verdict::Holds) {
        Verdict::Holds
    } else {
        Verdict::Inconclusive
    };
    let worst = (0..points.len())
        .min_by(|&a, &b| {
            let (ka, kb) = (judged[a].1, judged[b].1);
            ka.0.total_cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
        })
        .expect("points is not empty");
    let point = &points[worst];
    result.ratio = point.estimate.value;
    result.lo = point.estimate.lo;
    result.hi = point.estimate.hi;
    result.threshold = judged[worst].0;
    let counts = |v: Verdict| judged.iter().filter(|j| j.2 == v).count();
    result.detail = format!(
        "{} point{} ({} hold, {} fail, {} inconclusive); least favourable at {}",
        points.len(),
        if points.len() == 1 { "" } else { "s" },
        counts(Verdict::Holds),
        counts(Verdict::Fails),
        counts(Verdict::Inconclusive),
        labels[worst]
    );
    result
}

fn objects_range(claim: &ClaimSpec) -> String {
    match (claim.min_objects, claim.max_objects) {
        (None, None) => String::new(),
        (Some(min), None) => format!(" with at least {min} objects"),
        (None, Some(max)) => format!(" with at most {max} objects"),
        (Some(min), Some(max)) => format!(" with {min} to {max} objects"),
    }
}
