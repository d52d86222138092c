//! Where a strategy's worker threads may run: the affinity check every strategy and peer is held to.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Mutex;

use crate::counters::NoCounters;
use crate::executor::Strategy;

/// The CPUs each worker thread that ran a row of a 64-row image under `strategy` may run on, one entry per thread.
pub fn worker_cpus(strategy: Strategy) -> Vec<Vec<usize>> {
    let mut out = vec![0u8; 64];
    let seen = Mutex::new(BTreeMap::new());
    let _: NoCounters = strategy.run_rows(1, &mut out, |_, _, _| {
        let id = format!("{:?}", std::thread::current().id());
        seen.lock().unwrap().insert(id, crate::pinning::current_thread_cpus());
    });
    seen.into_inner().unwrap().into_values().collect()
}

/// Whether every worker may run on all of `allowed`, or on one CPU that no other worker has.
pub fn distinct_or_unpinned(workers: &[Vec<usize>], allowed: &[usize]) -> bool {
    let singles: Vec<usize> = workers.iter().filter(|w| w.len() == 1).map(|w| w[0]).collect();
    let distinct = singles.iter().collect::<BTreeSet<_>>().len() == singles.len();
    distinct && workers.iter().all(|w| w.len() == 1 || w.as_slice() == allowed)
}
