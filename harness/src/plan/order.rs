//! Run order: interleaved rounds, sequential blocks, or a seeded shuffle; warm-ups always come first.

use tracer::rng::SplitMix64;

use super::PlannedRun;
use crate::config::{Experiment, RunOrder};

/// The runs of `configs` configurations in the experiment's order.
pub fn runs(exp: &Experiment, configs: usize) -> Vec<PlannedRun> {
    let (reps, warm) = (exp.repetitions.max(), exp.warmups);
    let round = |repetition: Option<u32>| (0..configs).map(move |config| PlannedRun { config, repetition });
    match exp.order {
        RunOrder::Sequential => (0..configs)
            .flat_map(|config| {
                let warmups = (0..warm).map(move |_| PlannedRun { config, repetition: None });
                warmups.chain((0..reps).map(move |r| PlannedRun { config, repetition: Some(r) }))
            })
            .collect(),
        RunOrder::Interleaved => {
            (0..warm).flat_map(|_| round(None)).chain((0..reps).flat_map(|r| round(Some(r)))).collect()
        }
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
