//! What a configuration starts once per process, before any timed phase (the `setup_s` phase).

use std::any::Any;

use schema::Settings;
use tracer::pinning;

use super::workload::bvhlab_phase_build;
use super::{Backend, Built, Geometry};
use crate::error::Error;

/// The rayon pool of the configured threads that builds and traces run in (two or more each pinned to a CPU of its
/// own: [`tracer::pinning`]), and what the backend started ([`super::Backend::start`]: Embree's library and device).
pub struct Setup {
    pool: rayon::ThreadPool,
    started: Option<Box<dyn Any + Send + Sync>>,
    /// Wall time of starting all of it.
    pub setup_s: f64,
}

impl Setup {
    /// Starts what `settings` needs, timed.
    pub fn start(settings: &Settings) -> Result<Setup, Error> {
        let t = std::time::Instant::now();
        let threads = settings.strategy().threads.max(1);
        let cpus = pinning::cpus_for(threads);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .start_handler(move |i| pinning::pin_worker(&cpus, i))
            .build()
            .map_err(|e| Error::Run(format!("cannot start a pool of {threads} threads: {e}")))?;
        // Every worker thread started before the clock stops.
        pool.broadcast(|_| ());
        let started = super::of(settings.accel).start(settings)?;
        Ok(Setup { pool, started, setup_s: t.elapsed().as_secs_f64() })
    }

    /// Runs `f` in the pool (builds and traces run here, so the tracer's executor reuses the pool).
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        self.pool.install(f)
    }

    /// Builds `backend`'s structure for `settings` over `geometry`: in the pool, or, for a backend with threads of
    /// its own (Embree's TBB), on the calling thread, whose workers then inherit its CPUs and not a pinned pool
    /// thread's one. `run` and `render` build here alike.
    pub fn build(&self, backend: &dyn Backend, settings: &Settings, geometry: &Geometry<'_>) -> Result<Built, Error> {
        if backend.own_threads(settings) {
            backend.build(settings, geometry, self)
        } else {
            // The phase function runs in the pool (installing from inside the pool again, as the backends' builds
            // do, runs in place), where callgrind sees the building thread enter it.
            self.install(|| bvhlab_phase_build(|| backend.build(settings, geometry, self)))
        }
    }

    /// What the backend started, as the type it started.
    pub fn started<T: 'static>(&self) -> Option<&T> {
        self.started.as_ref().and_then(|s| s.downcast_ref())
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use std::collections::BTreeMap;
    use std::process::Command;

    use tracer::executor::StrategyKind;
    use tracer::pinning::allowed_cpus;
    use tracer::testing::threads::{distinct_or_unpinned, worker_cpus};

    use super::*;
    use crate::render::settings_of;
    use crate::run::scenes::make_scene;

    fn settings(set: &[&str]) -> Settings {
        settings_of(&set.iter().map(|s| s.to_string()).collect::<Vec<_>>()).unwrap()
    }

    #[test]
    fn every_strategys_workers_run_on_distinct_cpus_in_a_setups_pinned_pool() {
        let allowed = allowed_cpus();
        for kind in StrategyKind::ALL {
            let s = settings(&[&format!("strategy={}", kind.name()), "threads=2"]);
            let setup = Setup::start(&s).unwrap();
            let workers = setup.install(|| worker_cpus(s.strategy()));
            assert!(distinct_or_unpinned(&workers, &allowed), "{kind:?}×2 in the pool: {workers:?}");
            if kind == StrategyKind::MpscThreads && allowed.len() >= 2 {
                assert_eq!(workers.len(), 2, "one band thread per thread");
                assert!(workers.iter().all(|w| w.len() == 1), "pinned like the pool's threads: {workers:?}");
            }
        }
    }

    /// Every thread of this process and the CPUs it may run on (`/proc/self/task/*/status`).
    fn threads_here() -> BTreeMap<String, Vec<usize>> {
        let cpus = |list: &str| -> Vec<usize> {
            let range = |r: &str| match r.split_once('-') {
                Some((a, b)) => (a.parse().unwrap()..=b.parse().unwrap()).collect::<Vec<usize>>(),
                None => vec![r.parse().unwrap()],
            };
            list.split(',').flat_map(range).collect()
        };
        let mut out = BTreeMap::new();
        for task in std::fs::read_dir("/proc/self/task").unwrap() {
            let task = task.unwrap();
            let Ok(status) = std::fs::read_to_string(task.path().join("status")) else { continue };
            if let Some(list) = status.lines().find_map(|l| l.strip_prefix("Cpus_allowed_list:")) {
                out.insert(task.file_name().to_string_lossy().into_owned(), cpus(list.trim()));
            }
        }
        out
    }

    /// Embree builds on TBB's threads, which inherit the mask of the thread that starts them: built where `run` and
    /// `render` build ([`Setup::build`]) in a two-thread setup, every thread the setup and the build started runs on
    /// a CPU of its own or on all of them. In a process of its own (this test binary again, running
    /// [`embree_build_threads_in_a_fresh_process`]), so that the threads it sees are the setup's and Embree's.
    #[test]
    fn embree_build_threads_run_on_distinct_cpus_or_all() {
        if crate::peers::testing::embree_device("embree_build_threads_run_on_distinct_cpus_or_all").is_none() {
            return;
        }
        let child = "backend::setup::tests::embree_build_threads_in_a_fresh_process";
        let out = Command::new(std::env::current_exe().unwrap())
            .args(["--exact", child, "--ignored", "--test-threads=1", "--nocapture"])
            .output()
            .unwrap();
        let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        assert!(out.status.success() && text.contains("1 passed"), "{text}");
    }

    #[test]
    #[ignore = "run in a process of its own by embree_build_threads_run_on_distinct_cpus_or_all"]
    fn embree_build_threads_in_a_fresh_process() {
        let allowed = allowed_cpus();
        let before = threads_here();
        let s = settings(&["accel=embree", "objects=100000", "strategy=rayon-bands", "threads=2"]);
        let setup = Setup::start(&s).unwrap();
        let scene = make_scene(&s, None);
        setup.build(super::super::of(s.accel), &s, &scene.geometry()).unwrap();
        let started: Vec<Vec<usize>> =
            threads_here().into_iter().filter(|(t, _)| !before.contains_key(t)).map(|(_, c)| c).collect();
        // The pool's two threads and at least one of TBB's.
        assert!(started.len() > 2, "threads started: {started:?}");
        if allowed.len() < 2 {
            assert!(started.iter().all(|c| *c == allowed), "{started:?}");
            return;
        }
        let (pinned, free): (Vec<_>, Vec<_>) = started.iter().cloned().partition(|c| c.len() == 1);
        assert_eq!(pinned.len(), 2, "the pool's threads, and no other: {started:?}");
        assert!(distinct_or_unpinned(&pinned, &allowed), "the pool's threads: {started:?}");
        assert!(free.iter().all(|c| *c == allowed), "Embree's threads may run anywhere: {started:?}");
    }
}
