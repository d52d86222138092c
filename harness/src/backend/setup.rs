//! What a configuration starts once per process, before any timed phase (the `setup_s` phase).

use std::any::Any;

use schema::Settings;

use crate::error::Error;

/// The rayon pool of the configured threads that builds and traces run in (two or more each pinned to a CPU of its
/// own: [`pinning`]), and what the backend started ([`super::Backend::start`]: Embree's library and device).
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
            .start_handler(move |i| {
                if let Some(cpu) = cpus.get(i) {
                    pinning::pin_current_thread(*cpu);
                }
            })
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

    /// What the backend started, as the type it started.
    pub fn started<T: 'static>(&self) -> Option<&T> {
        self.started.as_ref().and_then(|s| s.downcast_ref())
    }
}

/// Pool threads pinned to distinct CPUs.
///
/// Why: a pool's threads sleep between passes, and a pass (1–3 ms on a small mesh) is shorter than the
/// scheduler's load balancing; woken each time, both threads of a two-thread pool can land on one vCPU and stay
/// there for a whole sample, which then takes 2.0× as long. In a recording of `meshes.toml` at 379dacc (2-vCPU VM)
/// 6% of the two-thread samples of in-process backends did (docs/statistics.md). Pinned, the pool's threads run on
/// different CPUs, in this process and in Embree's worker alike; one-thread pools stay unpinned.
pub mod pinning {
    /// The CPUs a pool of `threads` threads pins its threads to: the first `threads` CPUs this process may run on;
    /// none for one thread, or when the process may use fewer CPUs than that (threads then share them).
    pub fn cpus_for(threads: usize) -> Vec<usize> {
        let allowed = allowed_cpus();
        if threads < 2 || allowed.len() < threads {
            return Vec::new();
        }
        allowed[..threads].to_vec()
    }

    /// The CPUs this process may run on, in order (empty where that is not known). The process id names the main
    /// thread, which is never pinned, so a pool started from a pinned thread still sees every CPU.
    #[cfg(target_os = "linux")]
    pub fn allowed_cpus() -> Vec<usize> {
        // SAFETY: getpid cannot fail.
        affinity(unsafe { libc::getpid() })
    }

    /// The CPUs thread or process `id` may run on (0: the calling thread).
    #[cfg(target_os = "linux")]
    fn affinity(id: libc::pid_t) -> Vec<usize> {
        // SAFETY: `set` is a plain bit set that the call fills; its size is passed.
        unsafe {
            let mut set: libc::cpu_set_t = std::mem::zeroed();
            if libc::sched_getaffinity(id, std::mem::size_of::<libc::cpu_set_t>(), &mut set) != 0 {
                return Vec::new();
            }
            (0..libc::CPU_SETSIZE as usize).filter(|&c| libc::CPU_ISSET(c, &set)).collect()
        }
    }

    /// The CPUs this process may run on, in order (empty where that is not known).
    #[cfg(not(target_os = "linux"))]
    pub fn allowed_cpus() -> Vec<usize> {
        Vec::new()
    }

    /// Pins the calling thread to `cpu` (a no-op where that is not supported, or when the call fails).
    pub fn pin_current_thread(cpu: usize) {
        #[cfg(target_os = "linux")]
        // SAFETY: `set` is a plain bit set with one bit set; its size is passed; 0 names the calling thread.
        unsafe {
            let mut set: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_SET(cpu, &mut set);
            libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
        }
        #[cfg(not(target_os = "linux"))]
        let _ = cpu;
    }

    #[cfg(all(test, target_os = "linux"))]
    mod tests {
        use super::*;

        #[test]
        fn a_pinned_thread_runs_only_on_its_cpu() {
            let allowed = allowed_cpus();
            assert!(!allowed.is_empty());
            let cpu = *allowed.last().unwrap();
            let (thread, process) = std::thread::spawn(move || {
                pin_current_thread(cpu);
                (affinity(0), allowed_cpus())
            })
            .join()
            .unwrap();
            assert_eq!(thread, vec![cpu]);
            assert_eq!(process, allowed);
            assert!(cpus_for(1).is_empty());
            assert_eq!(cpus_for(allowed.len()), allowed);
            assert!(cpus_for(allowed.len() + 1).is_empty());
        }
    }
}
