//! Where each strategy's worker threads may run: on distinct CPUs, or on all of them, whoever spawns them.

use tracer::executor::{Strategy, StrategyKind};
use tracer::pinning;
use tracer::testing::threads::{distinct_or_unpinned, worker_cpus};

#[cfg(target_os = "linux")]
#[test]
fn every_strategys_workers_run_on_distinct_cpus_even_when_spawned_from_a_pinned_thread() {
    let allowed = pinning::allowed_cpus();
    for kind in StrategyKind::ALL {
        let strategy = Strategy::new(kind, 2);
        // From an unpinned thread, and from a thread pinned to one CPU (as a caller's pool thread is).
        let free = std::thread::spawn(move || worker_cpus(strategy)).join().unwrap();
        let from_pinned = std::thread::spawn(move || {
            pinning::pin_worker(&[pinning::allowed_cpus()[0]], 0);
            worker_cpus(strategy)
        })
        .join()
        .unwrap();
        for (from, workers) in [("an unpinned thread", free), ("a pinned thread", from_pinned)] {
            if kind == StrategyKind::MpscThreads {
                assert_eq!(workers.len(), 2, "{kind:?} from {from}: one thread per band");
            }
            assert!(distinct_or_unpinned(&workers, &allowed), "{kind:?}×2 from {from}: {workers:?}");
        }
    }
    assert!(!distinct_or_unpinned(&[vec![0], vec![0]], &[0, 1]), "two workers on one CPU");
    assert!(distinct_or_unpinned(&[vec![0], vec![1]], &[0, 1]) && distinct_or_unpinned(&[vec![0, 1]], &[0, 1]));
}
