//! Run order: interleaved rounds, sequential blocks, or a seeded shuffle; warm-ups always come first.

use tracer::rng::SplitMix64;

use super::PlannedRun;
use crate::config::{Experiment, RunOrder};

/// The runs of the configurations in the experiment's order; `point_of` gives each configuration's point (its
/// values on the axes no series fixes). An interleaved round runs the configurations point by point, so that the
/// series compared at a point run back to back, and every other round in reverse, so that none of them always runs
/// first (a drift in the machine's speed within a round then cancels in the per-round ratios).
pub fn runs(exp: &Experiment, point_of: &[usize]) -> Vec<PlannedRun> {
    let (configs, reps, warm) = (point_of.len(), exp.repetitions.max(), exp.warmups);
    let round = |repetition: Option<u32>| (0..configs).map(move |config| PlannedRun { config, repetition });
    let mut by_point: Vec<usize> = (0..configs).collect();
    by_point.sort_by_key(|&c| point_of[c]); // stable: series order within a point
    let by_point = &by_point;
    let interleaved = move |r: u32, repetition: Option<u32>| {
        let forward = by_point.iter().copied();
        let order: Vec<usize> = if r.is_multiple_of(2) { forward.collect() } else { forward.rev().collect() };
        order.into_iter().map(move |config| PlannedRun { config, repetition })
    };
    match exp.order {
        RunOrder::Sequential => (0..configs)
            .flat_map(|config| {
                let warmups = (0..warm).map(move |_| PlannedRun { config, repetition: None });
                warmups.chain((0..reps).map(move |r| PlannedRun { config, repetition: Some(r) }))
            })
            .collect(),
        RunOrder::Interleaved => (0..warm)
            .flat_map(|w| interleaved(w, None))
            .chain((0..reps).flat_map(|r| interleaved(r, Some(r))))
            .collect(),
        RunOrder::Shuffled => {
            let mut timed: Vec<PlannedRun> = (0..reps).flat_map(|r| round(Some(r))).collect();
            let mut rng = SplitMix64::new(exp.order_seed);
            for i in (1..timed.len()).rev() {
                timed.swap(i, rng.below(i as u64 + 1) as usize);
            }
            (0..warm).flat_map(|_| round(None)).chain(timed).collect()
        }
    }
}
