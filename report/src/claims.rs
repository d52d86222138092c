//! Checking `[[claim]]`s: ratio `metric(than) / metric(series)` per object count, pooled over seeds.

use crate::pool::{self, Point};
use crate::rows::Rows;
use crate::spec::{ClaimKind, ClaimSpec, ReportSpec, Verdict};
use crate::stats::{self, Estimate};
use schema::column;

/// What would settle an inconclusive point: more runs of each series, or, where its interval resamples the
/// processes that timed it (`processes` in the config), more processes of each configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum More {
    /// About this many more runs of each series.
    Runs(usize),
    /// About this many more worker processes of each configuration, each timing as many rounds as before.
    Processes(usize),
}

impl More {
    /// How many more.
    pub fn count(self) -> usize {
        match self {
            More::Runs(n) | More::Processes(n) => n,
        }
    }

    /// What is counted, in the plural (`runs`, `processes`).
    pub fn unit(self) -> &'static str {
        match self {
            More::Runs(_) => "runs",
            More::Processes(_) => "processes",
        }
    }

    /// What would settle a point whose estimate rests on `provenance`: processes where the interval resampled
    /// them (at least [`stats::MIN_SAMPLES_FOR_INTERVAL`]), else runs; `None` as [`runs_to_settle`].
    pub fn to_settle(e: Estimate, kind: &ClaimKind, threshold: f64, provenance: &pool::Provenance) -> Option<More> {
        if provenance.processes >= stats::MIN_SAMPLES_FOR_INTERVAL {
            runs_to_settle(e, kind, threshold, provenance.processes).map(More::Processes)
        } else {
            runs_to_settle(e, kind, threshold, provenance.n).map(More::Runs)
        }
    }
}

impl std::fmt::Display for More {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "~{} more {}", self.count(), self.unit())
    }
}

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
    /// Every point compared, in the order of the rows.
    pub points: Vec<PointResult>,
}

/// One point of a claim: its settings, ratio and own verdict.
#[derive(Clone, Debug, PartialEq)]
pub struct PointResult {
    /// The settings that name the point (e.g. `mesh bunny, view street, workload diffuse`).
    pub label: String,
    /// Ratio `metric(than) / metric(series)` there.
    pub ratio: f64,
    /// Lower end of its 95% interval.
    pub lo: f64,
    /// Upper end of its 95% interval.
    pub hi: f64,
    /// The factor the ratio must reach there, or the tolerance.
    pub threshold: f64,
    /// Holds, fails or inconclusive at this point.
    pub verdict: Verdict,
    /// Inconclusive points: about how many more runs, or processes, would settle it (see [`runs_to_settle`]).
    pub more: Option<More>,
    /// The most worker threads either side used there (1: a one-thread point).
    pub threads: f64,
}

/// Checks every claim of `spec` against the rows.
pub fn check_all(rows: &Rows, spec: &ReportSpec) -> Vec<ClaimResult> {
    spec.claims.iter().map(|claim| check(rows, spec, claim)).collect()
}

/// The claims of `now` that held in `recorded` (matched by their text) and fail at every point of `now`: an answer
/// that the code no longer gives.
pub fn lost<'a>(recorded: &[ClaimResult], now: &'a [ClaimResult]) -> Vec<&'a ClaimResult> {
    let held = |text: &str| recorded.iter().any(|r| r.text == text && r.verdict == Verdict::Holds);
    let fails_everywhere =
        |c: &ClaimResult| !c.points.is_empty() && c.points.iter().all(|p| p.verdict == Verdict::Fails);
    now.iter().filter(|c| fails_everywhere(c) && held(&c.text)).collect()
}

/// Checks one claim.
pub fn check(rows: &Rows, spec: &ReportSpec, claim: &ClaimSpec) -> ClaimResult {
    let (series, than) = match &claim.kind {
        ClaimKind::Faster { series, than, .. } | ClaimKind::Within { series, than, .. } => (series, than),
    };
    let (points, labels) = collect_points(rows, spec, claim, series, than);
    if points.is_empty() {
        return no_points(claim, series, than);
    }
    let judged: Vec<Judged> = points.iter().map(|p| judge(&claim.kind, p)).collect();
    let more: Vec<Option<More>> = points
        .iter()
        .zip(&judged)
        .map(|(p, j)| {
            (j.verdict == Verdict::Inconclusive)
                .then(|| More::to_settle(p.estimate, &claim.kind, j.threshold, &p.provenance))
                .flatten()
        })
        .collect();
    let worst = least_favourable(&judged);
    let estimate = points[worst].estimate;
    ClaimResult {
        text: claim.text.clone(),
        verdict: overall(&judged),
        ratio: estimate.value,
        lo: estimate.lo,
        hi: estimate.hi,
        threshold: judged[worst].threshold,
        detail: describe(&judged, &more, &labels[worst]),
        points: points
            .iter()
            .zip(&judged)
            .zip(labels)
            .zip(more)
            .map(|(((p, j), label), more)| PointResult {
                label,
                ratio: p.estimate.value,
                lo: p.estimate.lo,
                hi: p.estimate.hi,
                threshold: j.threshold,
                verdict: j.verdict,
                more,
                threads: p.threads.max(p.reference_threads),
            })
            .collect(),
    }
}

/// One point judged against its claim.
struct Judged {
    /// The factor the ratio must reach (`Faster`) or the tolerance (`Within`).
    threshold: f64,
    /// How far the point is from failing: larger is safer, compared holds-side end first.
    safety: (f64, f64),
    /// The point's own verdict.
    verdict: Verdict,
}

/// Every in-range point of every curve (one per thread count etc. varying in the series), with its label.
fn collect_points(
    rows: &Rows,
    spec: &ReportSpec,
    claim: &ClaimSpec,
    series: &str,
    than: &str,
) -> (Vec<Point>, Vec<String>) {
    let in_range = |p: &Point| {
        claim.min_objects.is_none_or(|min| p.x >= min as f64) && claim.max_objects.is_none_or(|max| p.x <= max as f64)
    };
    let mut points: Vec<Point> = Vec::new();
    let mut labels: Vec<String> = Vec::new();
    let runs: Vec<crate::rows::Run> = rows.runs.iter().filter(|r| r.passes(&claim.filter)).cloned().collect();
    if rows.is_numeric(&claim.metric) {
        for curve in pool::ratio_curves(spec, &runs, than, series, column::objects, &claim.metric) {
            for point in curve.points.into_iter().filter(in_range) {
                labels.push(pool::point_label(&curve.fixed, point.x));
                points.push(point);
            }
        }
    }
    (points, labels)
}

/// The inconclusive result of a claim no point matched, saying why.
fn no_points(claim: &ClaimSpec, series: &str, than: &str) -> ClaimResult {
    ClaimResult {
        text: claim.text.clone(),
        verdict: Verdict::Inconclusive,
        ratio: f64::NAN,
        lo: f64::NAN,
        hi: f64::NAN,
        threshold: match claim.kind {
            ClaimKind::Faster { factor, .. } => factor,
            ClaimKind::Within { tolerance, .. } => tolerance,
        },
        detail: format!(
            "no points: no `{}` rows of {series} with matching {than} rows{}",
            claim.metric,
            objects_range(claim)
        ),
        points: Vec::new(),
    }
}

/// Judges one point against the claim kind.
fn judge(kind: &ClaimKind, point: &Point) -> Judged {
    match *kind {
        ClaimKind::Faster { factor, per_thread, .. } => {
            judge_faster(point.estimate, if per_thread { factor * thread_ratio(point) } else { factor })
        }
        ClaimKind::Within { tolerance, .. } => judge_within(point.estimate, tolerance),
    }
}

/// How many times more threads the series used than the side it is compared with (its own count when the
/// other side's is unknown).
fn thread_ratio(point: &Point) -> f64 {
    if point.reference_threads.is_finite() && point.reference_threads > 0.0 {
        point.threads / point.reference_threads
    } else {
        point.threads
    }
}

/// `Faster`: holds when the interval lies at or above `threshold`, fails when entirely below it.
fn judge_faster(e: Estimate, threshold: f64) -> Judged {
    let verdict = if e.lo >= threshold {
        Verdict::Holds
    } else if e.hi < threshold {
        Verdict::Fails
    } else {
        Verdict::Inconclusive
    };
    Judged { threshold, safety: (e.lo / threshold, e.hi / threshold), verdict }
}

/// `Within`: holds when the interval lies inside `1 ± tolerance`, fails when entirely outside it.
fn judge_within(e: Estimate, tolerance: f64) -> Judged {
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
    let near = if e.lo <= 1.0 && 1.0 <= e.hi { 0.0 } else { (e.lo - 1.0).abs().min((e.hi - 1.0).abs()) };
    Judged { threshold: tolerance, safety: (-near, -far), verdict }
}

/// About how many more of the `runs` independent draws behind a point's interval (runs of each series, or the
/// processes its interval resampled) would settle a point whose interval straddles a bound of its claim (the
/// threshold, or `1 ± tolerance`), if its ratio and its draws' spread stay as they are: an interval narrows as
/// 1/√draws, so it must shrink by the distance from the ratio to the bound. `None` when no bound is straddled or the
/// ratio sits on one (no number of runs settles that). A point without an interval (fewer runs than
/// [`stats::MIN_SAMPLES_FOR_INTERVAL`]) needs at least the runs that give it one.
pub fn runs_to_settle(e: Estimate, kind: &ClaimKind, threshold: f64, runs: usize) -> Option<usize> {
    if e.lo.is_nan() || e.hi.is_nan() {
        return (runs < stats::MIN_SAMPLES_FOR_INTERVAL).then(|| stats::MIN_SAMPLES_FOR_INTERVAL - runs);
    }
    let bounds = match kind {
        ClaimKind::Faster { .. } => vec![threshold],
        ClaimKind::Within { .. } => vec![1.0 - threshold, 1.0 + threshold],
    };
    let mut shrink: f64 = 1.0;
    for bound in bounds.into_iter().filter(|&b| e.lo < b && b <= e.hi) {
        let (half, gap) =
            if e.value >= bound { (e.value - e.lo, e.value - bound) } else { (e.hi - e.value, bound - e.value) };
        if gap <= 0.0 || !half.is_finite() {
            return None;
        }
        shrink = shrink.max(half / gap);
    }
    let needed = (runs.max(1) as f64 * shrink * shrink - 1e-9).ceil(); // not one more for a rounding error
    (shrink > 1.0 && needed.is_finite()).then(|| needed as usize - runs.max(1))
}

/// The claim's verdict: fails if any point fails, holds if every point holds, inconclusive otherwise.
fn overall(judged: &[Judged]) -> Verdict {
    if judged.iter().any(|j| j.verdict == Verdict::Fails) {
        Verdict::Fails
    } else if judged.iter().all(|j| j.verdict == Verdict::Holds) {
        Verdict::Holds
    } else {
        Verdict::Inconclusive
    }
}

/// Index of the least safe point (the first of equals); `judged` must not be empty.
fn least_favourable(judged: &[Judged]) -> usize {
    // A failing point before an inconclusive one before one that holds: the point named is the one that decided
    // the claim's verdict. Among equals, the least safe.
    let rank = |v: Verdict| match v {
        Verdict::Fails => 0,
        Verdict::Inconclusive => 1,
        Verdict::Holds => 2,
    };
    (0..judged.len())
        .min_by(|&a, &b| {
            let (ka, kb) = (judged[a].safety, judged[b].safety);
            rank(judged[a].verdict)
                .cmp(&rank(judged[b].verdict))
                .then(ka.0.total_cmp(&kb.0))
                .then(ka.1.total_cmp(&kb.1))
        })
        .expect("points is not empty")
}

/// More runs than this to settle a point: it sits on its threshold, for any practical purpose.
pub const SETTLE_LIMIT: usize = 1000;

/// How many points were compared, how they came out, what would settle the inconclusive ones, and where the least
/// favourable one is.
fn describe(judged: &[Judged], more: &[Option<More>], worst_label: &str) -> String {
    let counts = |v: Verdict| judged.iter().filter(|j| j.verdict == v).count();
    let inconclusive = counts(Verdict::Inconclusive);
    let mut settle = String::new();
    let mut settled = 0;
    for (unit, of_each) in [("runs", "series"), ("processes", "configuration")] {
        let near: Vec<usize> = more
            .iter()
            .flatten()
            .filter(|m| m.unit() == unit)
            .map(|m| m.count())
            .filter(|&n| n <= SETTLE_LIMIT)
            .collect();
        if let (Some(least), Some(most)) = (near.iter().min(), near.iter().max()) {
            let n = if least == most { format!("{least}") } else { format!("{least}–{most}") };
            settle.push_str(&format!("; {} would settle with about {n} more {unit} of each {of_each}", near.len()));
        }
        settled += near.len();
    }
    if inconclusive > settled {
        settle.push_str(&format!("; {} sit on the threshold", inconclusive - settled));
    }
    format!(
        "{} point{} ({} hold, {} fail, {inconclusive} inconclusive{settle}); least favourable at {}",
        judged.len(),
        if judged.len() == 1 { "" } else { "s" },
        counts(Verdict::Holds),
        counts(Verdict::Fails),
        worst_label
    )
}

/// The claim's object range in words (` with at least 1000 objects`), empty without one.
fn objects_range(claim: &ClaimSpec) -> String {
    match (claim.min_objects, claim.max_objects) {
        (None, None) => String::new(),
        (Some(min), None) => format!(" with at least {min} objects"),
        (None, Some(max)) => format!(" with at most {max} objects"),
        (Some(min), Some(max)) => format!(" with {min} to {max} objects"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(lo: f64, hi: f64, threads: f64, reference_threads: f64) -> Point {
        Point {
            x: 1.0,
            estimate: Estimate { value: (lo + hi) / 2.0, lo, hi },
            threads,
            reference_threads,
            provenance: Default::default(),
        }
    }

    #[test]
    fn per_thread_thresholds_use_the_ratio_of_both_sides_thread_counts() {
        let kind = ClaimKind::Faster { series: "a".into(), than: "b".into(), factor: 0.5, per_thread: true };
        // 8 threads against 4: the speedup must reach 0.5 × 2 = 1, not 0.5 × 8 = 4.
        assert_eq!(judge(&kind, &point(1.1, 1.3, 8.0, 4.0)).verdict, Verdict::Holds);
        assert_eq!(judge(&kind, &point(0.7, 0.9, 8.0, 4.0)).verdict, Verdict::Fails);
        assert_eq!(judge(&kind, &point(1.1, 1.3, 8.0, 1.0)).verdict, Verdict::Fails, "against one thread: 4");
        assert_eq!(
            judge(&kind, &point(1.1, 1.3, 2.0, f64::NAN)).verdict,
            Verdict::Holds,
            "other side unknown: 0.5 × 2"
        );
    }

    #[test]
    fn an_inconclusive_point_says_how_many_more_runs_would_settle_it() {
        let faster = ClaimKind::Faster { series: "a".into(), than: "b".into(), factor: 1.0, per_thread: false };
        let within = ClaimKind::Within { series: "a".into(), than: "b".into(), tolerance: 0.02 };
        let e = |value, lo, hi| Estimate { value, lo, hi };
        // 1.05 [0.95, 1.10] against 1: the low side must halve (0.10 -> below 0.05): 4x the runs, 30 more.
        assert_eq!(runs_to_settle(e(1.05, 0.95, 1.10), &faster, 1.0, 10), Some(30));
        // Leaning to fail: 0.98 [0.96, 1.01]: the high side 0.03 must shrink below 0.02: 2.25x, 23 of 10 -> 13.
        assert_eq!(runs_to_settle(e(0.98, 0.96, 1.01), &faster, 1.0, 10), Some(13));
        assert_eq!(runs_to_settle(e(1.0, 0.9, 1.1), &faster, 1.0, 10), None, "on the threshold");
        assert_eq!(runs_to_settle(e(1.2, 1.1, 1.3), &faster, 1.0, 10), None, "settled already");
        // Within 2%: 1.01 [0.99, 1.03] straddles 1.02 only: 0.02 / 0.01 -> 4x.
        assert_eq!(runs_to_settle(e(1.01, 0.99, 1.03), &within, 0.02, 20), Some(60));
        // Both bounds straddled: the worse side decides.
        assert_eq!(runs_to_settle(e(1.0, 0.97, 1.04), &within, 0.02, 10), Some(30));
        // Four runs have no interval: two more give one.
        assert_eq!(runs_to_settle(e(9.0, f64::NAN, f64::NAN), &faster, 1.0, 4), Some(2));
    }

    #[test]
    fn the_least_favourable_point_is_the_one_that_decided_the_verdict() {
        // Within 10%: one point sits just off 1 with a tight interval (holds), another straddles 1.1 (inconclusive):
        // the claim is inconclusive, and the point it names is the inconclusive one, not the one off 1.
        let judged: Vec<Judged> = [(1.003, 1.016), (0.95, 1.17), (0.97, 1.02)]
            .iter()
            .map(|&(lo, hi)| judge_within(Estimate { value: (lo + hi) / 2.0, lo, hi }, 0.1))
            .collect();
        assert_eq!(overall(&judged), Verdict::Inconclusive);
        assert_eq!(least_favourable(&judged), 1);
        // Faster than 1: a failing point is named before an inconclusive one whose interval reaches lower.
        let judged: Vec<Judged> = [(0.5, 1.5), (0.9, 0.95), (1.1, 1.2)]
            .iter()
            .map(|&(lo, hi)| judge_faster(Estimate { value: (lo + hi) / 2.0, lo, hi }, 1.0))
            .collect();
        assert_eq!(least_favourable(&judged), 1);
    }

    #[test]
    fn a_point_whose_interval_resampled_processes_asks_for_more_processes() {
        let within = ClaimKind::Within { series: "a".into(), than: "b".into(), tolerance: 0.02 };
        let e = Estimate { value: 1.01, lo: 0.99, hi: 1.03 };
        let provenance = |n, processes| pool::Provenance { n, processes, ..Default::default() };
        // 40 rounds over 8 processes: the interval is the processes', so 4x the processes, not 4x the rounds.
        assert_eq!(More::to_settle(e, &within, 0.02, &provenance(40, 8)), Some(More::Processes(24)));
        // In one process (or rows without `process_id`), the rounds.
        assert_eq!(More::to_settle(e, &within, 0.02, &provenance(40, 1)), Some(More::Runs(120)));
        assert_eq!(More::to_settle(e, &within, 0.02, &provenance(40, 0)), Some(More::Runs(120)));
        assert_eq!(More::Processes(24).to_string(), "~24 more processes");
    }

    #[test]
    fn a_claim_is_lost_only_when_it_held_and_now_fails_at_every_point() {
        let point = |verdict| PointResult {
            label: String::new(),
            ratio: 1.0,
            lo: 1.0,
            hi: 1.0,
            threshold: 1.0,
            verdict,
            more: None,
            threads: 1.0,
        };
        let claim = |text: &str, verdict, points: &[Verdict]| ClaimResult {
            text: text.into(),
            verdict,
            ratio: 1.0,
            lo: 1.0,
            hi: 1.0,
            threshold: 1.0,
            detail: String::new(),
            points: points.iter().map(|&v| point(v)).collect(),
        };
        use Verdict::{Fails, Holds, Inconclusive};
        let then = [claim("a", Holds, &[Holds]), claim("b", Holds, &[Holds]), claim("c", Fails, &[Fails])];
        let now = [
            claim("a", Fails, &[Fails, Fails]),
            claim("b", Fails, &[Fails, Inconclusive]),
            claim("c", Fails, &[Fails]),
            claim("d", Fails, &[Fails]),
        ];
        let lost: Vec<&str> = lost(&then, &now).iter().map(|c| c.text.as_str()).collect();
        assert_eq!(lost, ["a"], "b is not failing everywhere, c never held, d is new");
        assert!(super::lost(&then, &[claim("a", Fails, &[])]).is_empty(), "no points: nothing measured");
    }
}
