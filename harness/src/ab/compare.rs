//! The comparison proper: times the configurations with both builds, interleaved, each run in a fresh
//! `harness worker` process; measures flagged single-thread slowdowns again; reports how much faster the new build
//! is (old time / new time, above 1 = faster: the one direction of every ratio) with its interval and verdict, and
//! whether the builds' answers agree.

use std::path::Path;

use report::RoundRatios;
use report::stats::Estimate;

use super::AbRequest;
use crate::config::Experiment;
use crate::error::Error;
use crate::plan::{Configuration, Plan};
use crate::revision::Revision;
use crate::run::{self, worker};

/// The speed verdict of one configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Speed {
    Regressed,
    SlowerNotGating,
    Improved,
    Unchanged,
}

impl Speed {
    /// `e` is old / new (how much faster the new build is); single-thread configurations gate. `min_effect` is a
    /// change of the new build's time: slower means it takes more than `1 + min_effect` times the old time.
    fn of(e: &Estimate, min_effect: f64, gating: bool) -> Speed {
        let slower = e.hi < 1.0 && e.value < 1.0 / (1.0 + min_effect);
        let faster = e.lo > 1.0 && e.value > 1.0 / (1.0 - min_effect);
        match (slower, faster) {
            (true, _) if gating => Speed::Regressed,
            (true, _) => Speed::SlowerNotGating,
            (_, true) => Speed::Improved,
            _ => Speed::Unchanged,
        }
    }

    fn label(self) -> &'static str {
        match self {
            Speed::Regressed => "**regressed**",
            Speed::SlowerNotGating => "slower (not gating: threads > 1)",
            Speed::Improved => "improved",
            Speed::Unchanged => "unchanged",
        }
    }
}

/// How one configuration's answers (output hashes, one per run) compare between the builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Answers {
    Same,
    Differ,
    /// A build's answers changed from run to run: (old, new).
    Unstable(bool, bool),
}

impl Answers {
    fn of(old: &[u64], new: &[u64]) -> Answers {
        let unstable = |h: &[u64]| h.windows(2).any(|w| w[0] != w[1]);
        match (unstable(old), unstable(new)) {
            (false, false) if old.first() == new.first() => Answers::Same,
            (false, false) => Answers::Differ,
            (o, n) => Answers::Unstable(o, n),
        }
    }

    fn label(self) -> &'static str {
        match self {
            Answers::Same => "same",
            Answers::Differ => "differs",
            Answers::Unstable(true, true) => "unstable (both builds)",
            Answers::Unstable(true, false) => "unstable (old build)",
            Answers::Unstable(..) => "unstable (new build)",
        }
    }
}

/// Why the comparison fails, in one line, or `None`: answers that change between runs of a build always fail,
/// answers that differ between the builds fail unless allowed, and so do significant single-thread slowdowns.
fn failure(results: &[(String, Speed, Answers)], allow_different_answers: bool) -> Option<String> {
    let names = |keep: &dyn Fn(Speed, Answers) -> bool| {
        results.iter().filter(|(_, s, a)| keep(*s, *a)).map(|(n, ..)| n.as_str()).collect::<Vec<_>>().join(", ")
    };
    let reasons: Vec<String> = [
        (names(&|_, a| matches!(a, Answers::Unstable(..))), "answers change from run to run of the same build in", ""),
        (
            names(&|_, a| a == Answers::Differ && !allow_different_answers),
            "the builds' answers differ in",
            " (--allow-different-answers to compare them anyway)",
        ),
        (names(&|s, _| s == Speed::Regressed), "significantly slower than the base revision (single thread):", ""),
    ]
    .into_iter()
    .filter(|(names, ..)| !names.is_empty())
    .map(|(names, what, hint)| format!("{what} {names}{hint}"))
    .collect();
    (!reasons.is_empty()).then(|| reasons.join("; "))
}

/// A configuration as the table and the messages name it.
fn describe(c: &Configuration) -> String {
    let s = &c.settings;
    let scene = match (&s.mesh, s.view) {
        (Some(mesh), Some(view)) => format!("mesh {mesh} {}", schema::Named::name(view)),
        _ => format!("{} objects {}", schema::Named::name(s.scene), s.objects),
    };
    format!("{} | {scene} {} {}", c.series, schema::Named::name(s.workload), s.strategy())
}

/// A configuration's samples and answers from both builds.
#[derive(Default)]
struct Pair {
    old: Vec<f64>,
    new: Vec<f64>,
    old_answers: Vec<u64>,
    new_answers: Vec<u64>,
}

impl Pair {
    /// The per-round ratios old/new (above 1: the new build is faster), each round a pair of processes of its own.
    fn ratios(&self) -> RoundRatios {
        RoundRatios {
            ratios: self.new.iter().zip(&self.old).map(|(n, o)| o / n).collect(),
            processes: (0..self.new.len() as u64).collect(),
        }
    }
}

/// The verdict that counts: a regression of the first measurement stands only if the second one (when taken)
/// finds it too; otherwise the configuration is unchanged.
fn confirmed(first: Speed, second: Option<Speed>) -> Speed {
    match (first, second) {
        (Speed::Regressed, Some(Speed::Regressed)) | (Speed::Regressed, None) => Speed::Regressed,
        (Speed::Regressed, Some(_)) => Speed::Unchanged,
        (first, _) => first,
    }
}

/// Times `configurations` with both builds, interleaved (old then new, new then old, round after round), each run
/// in a fresh `harness worker` process: one [`Pair`] per configuration.
fn measure(
    plan: &Plan,
    configurations: &[&Configuration],
    rounds: (u32, u32),
    bins: (&Path, &Path),
    root: &Path,
    what: &str,
) -> Result<Vec<Pair>, Error> {
    let (warmups, repetitions) = rounds;
    let (old_bin, new_bin) = bins;
    let mut pairs: Vec<Pair> = configurations.iter().map(|_| Pair::default()).collect();
    for round in 0..warmups + repetitions {
        for (c, pair) in configurations.iter().zip(&mut pairs) {
            let old_first = round % 2 == 0;
            let (first, second) = if old_first { (old_bin, new_bin) } else { (new_bin, old_bin) };
            let job = run::worker_request(plan, c);
            let a = worker::time(first, Some(root), &job)?;
            let b = worker::time(second, Some(root), &job)?;
            let (old, new) = if old_first { (a, b) } else { (b, a) };
            pair.old_answers.push(old.output_hash);
            pair.new_answers.push(new.output_hash);
            if round >= warmups {
                pair.old.push(old.trace_s);
                pair.new.push(new.trace_s);
            }
        }
        note!("ab: {what} round {}/{} done", round + 1, warmups + repetitions);
    }
    Ok(pairs)
}

/// The configurations of `plan` that revision `rev` (built as `base`) can run, and why each other one is skipped:
/// a setting newer than the revision ([`Revision::cannot_run`]), or its worker refusing the request (asked once).
fn runnable_at<'a>(rev: &str, plan: &'a Plan, root: &Path, base: &Path) -> (Vec<&'a Configuration>, Vec<String>) {
    let revision = Revision::read(root, rev);
    let (mut runnable, mut skipped) = (Vec::new(), Vec::new());
    for c in plan.runnable() {
        let why = revision
            .cannot_run(&c.settings)
            .or_else(|| worker::time(base, Some(root), &run::worker_request(plan, c)).err().map(|e| e.to_string()));
        match why {
            Some(why) => skipped.push(format!("{}: {why}", describe(c))),
            None => runnable.push(c),
        }
    }
    (runnable, skipped)
}

/// Runs the comparison; fails (exit 1) on answers that differ or change, or on a significant single-thread
/// regression beyond `min_effect` that a second measurement of the configuration (fresh, interleaved) confirms.
pub(super) fn run(
    request: &AbRequest<'_>,
    exp: &Experiment,
    plan: &Plan,
    root: &Path,
    rev: &str,
    bins: (&Path, &Path),
) -> Result<(), Error> {
    let (old_bin, _) = bins;
    let rounds = (exp.warmups, exp.repetitions.max());
    let (all, skipped) = runnable_at(rev, plan, root, old_bin);
    for why in &skipped {
        note!("ab: skipped, {why}");
    }
    if all.is_empty() {
        return Err(Error::Run(format!("{}: no configuration runs at {}", exp.path.display(), &rev[..12])));
    }
    let mut pairs = measure(plan, &all, rounds, bins, root, "")?;
    let speed = |c: &Configuration, pair: &Pair| {
        // Old and new ran in the same rounds (one after the other), each round in a pair of processes of its own.
        let e: Estimate = pair.ratios().estimate(&c.id);
        (Speed::of(&e, request.min_effect, c.settings.strategy().threads == 1), e)
    };
    let flagged: Vec<usize> =
        (0..all.len()).filter(|&i| !request.no_confirm && speed(all[i], &pairs[i]).0 == Speed::Regressed).collect();
    let mut again: Vec<Option<Pair>> = all.iter().map(|_| None).collect();
    if !flagged.is_empty() {
        note!("ab: {} configuration(s) flagged as slower: measuring them again", flagged.len());
        let configurations: Vec<&Configuration> = flagged.iter().map(|&i| all[i]).collect();
        let second = measure(plan, &configurations, rounds, bins, root, "confirmation")?;
        for (&i, pair) in flagged.iter().zip(second) {
            pairs[i].old_answers.extend(&pair.old_answers);
            pairs[i].new_answers.extend(&pair.new_answers);
            again[i] = Some(pair);
        }
    }
    say!("## A/B: {} (new, this build) against {} (old, {})\n", exp.name, &rev[..12], request.base);
    say!(
        "How much faster the new build is per configuration: old trace time / new (above 1: faster), the median of per-round ratios with its 95% interval; {} rounds, interleaved. \
         A single-thread configuration flagged as slower is measured again the same way and fails only if that \
         agrees.\n",
        exp.repetitions.max()
    );
    say!(
        "| series | settings | old median (s) | new median (s) | old / new [95% CI] | verdict | measured again: old / new \
         [95% CI], verdict | output |"
    );
    say!("|---|---|---|---|---|---|---|---|");
    let mut results = vec![];
    for (i, c) in all.iter().enumerate() {
        let (first, e) = speed(c, &pairs[i]);
        let second = again[i].as_ref().map(|pair| speed(c, pair));
        let verdict = confirmed(first, second.as_ref().map(|(s, _)| *s));
        let confirmation = second.map_or("—".to_string(), |(s, e2)| {
            format!("{:.3} [{:.3}, {:.3}], {}", e2.value, e2.lo, e2.hi, s.label())
        });
        let answers = Answers::of(&pairs[i].old_answers, &pairs[i].new_answers);
        say!(
            "| {} | {:.6} | {:.6} | {:.3} [{:.3}, {:.3}] | {} | {} | {} |",
            describe(c),
            report::stats::median(&pairs[i].old),
            report::stats::median(&pairs[i].new),
            e.value,
            e.lo,
            e.hi,
            first.label(),
            confirmation,
            answers.label()
        );
        results.push((describe(c).replace(" | ", ": "), verdict, answers));
    }
    if !skipped.is_empty() {
        say!("\nSkipped: {} configuration(s) the base revision cannot run:\n", skipped.len());
        for why in &skipped {
            say!("- {why}");
        }
    }
    match failure(&results, request.allow_different_answers) {
        Some(why) => Err(Error::Run(why)),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn named(results: &[(Speed, Answers)]) -> Vec<(String, Speed, Answers)> {
        results.iter().enumerate().map(|(i, &(s, a))| (format!("c{i}"), s, a)).collect()
    }

    #[test]
    fn answers_are_the_same_only_when_every_run_of_both_builds_agrees() {
        assert_eq!(Answers::of(&[7, 7, 7], &[7, 7, 7]), Answers::Same);
        assert_eq!(Answers::of(&[7, 7, 7], &[8, 8, 8]), Answers::Differ);
        assert_eq!(Answers::of(&[7, 7, 9], &[7, 7, 7]), Answers::Unstable(true, false));
        assert_eq!(Answers::of(&[7, 7, 7], &[9, 7, 7]), Answers::Unstable(false, true));
        assert_eq!(Answers::of(&[7, 8], &[8, 7]), Answers::Unstable(true, true));
    }

    #[test]
    fn differing_answers_fail_unless_allowed_and_unstable_ones_always_fail() {
        let (same, differ) = ((Speed::Unchanged, Answers::Same), (Speed::Improved, Answers::Differ));
        assert_eq!(failure(&named(&[same, same]), false), None);
        let why = failure(&named(&[same, differ, differ]), false).expect("differing answers fail");
        assert!(why.starts_with("the builds' answers differ in c1, c2 ("), "{why}");
        assert_eq!(failure(&named(&[same, differ]), true), None, "allowed");
        let unstable = (Speed::Unchanged, Answers::Unstable(false, true));
        let why = failure(&named(&[unstable, differ]), true).expect("unstable answers fail even when allowed");
        assert_eq!(why, "answers change from run to run of the same build in c0");
        let why =
            failure(&named(&[(Speed::Regressed, Answers::Differ), (Speed::SlowerNotGating, Answers::Same)]), false)
                .expect("fails");
        assert!(!why.contains('\n') && why.contains("differ in c0 (") && why.ends_with("(single thread): c0"), "{why}");
        assert_eq!(failure(&named(&[(Speed::SlowerNotGating, Answers::Same)]), false), None);
    }

    #[test]
    fn only_a_significant_single_thread_slowdown_beyond_the_minimum_effect_regresses() {
        let e = |value, lo, hi| Estimate { value, lo, hi };
        // Old / new: 1/1.2 = the new build takes 1.2× the old time.
        assert_eq!(Speed::of(&e(1.0 / 1.2, 0.8, 0.87), 0.1, true), Speed::Regressed);
        assert_eq!(Speed::of(&e(1.0 / 1.2, 0.8, 0.87), 0.1, false), Speed::SlowerNotGating);
        assert_eq!(Speed::of(&e(1.0 / 1.05, 0.92, 0.98), 0.1, true), Speed::Unchanged, "within the minimum effect");
        assert_eq!(Speed::of(&e(1.0 / 1.2, 0.7, 1.05), 0.1, true), Speed::Unchanged, "not significant");
        assert_eq!(Speed::of(&e(1.25, 1.18, 1.33), 0.1, true), Speed::Improved);
    }

    #[test]
    fn a_regression_fails_only_when_the_second_measurement_agrees() {
        assert_eq!(confirmed(Speed::Regressed, Some(Speed::Regressed)), Speed::Regressed);
        assert_eq!(confirmed(Speed::Regressed, Some(Speed::Unchanged)), Speed::Unchanged);
        assert_eq!(confirmed(Speed::Regressed, Some(Speed::Improved)), Speed::Unchanged);
        assert_eq!(confirmed(Speed::Regressed, None), Speed::Regressed, "--no-confirm");
        assert_eq!(confirmed(Speed::Improved, None), Speed::Improved);
        let failing =
            |second| failure(&[("a".into(), confirmed(Speed::Regressed, second), Answers::Same)], false).is_some();
        assert!(failing(Some(Speed::Regressed)) && !failing(Some(Speed::Unchanged)));
    }
}
