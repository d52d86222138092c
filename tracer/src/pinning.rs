//! Worker threads pinned to distinct CPUs: every parallel strategy's threads, and the pools that callers start.
//!
//! Why: a pool's threads sleep between passes, and a pass (1–3 ms on a small mesh) is shorter than the scheduler's
//! load balancing; woken each time, both threads of a two-thread pool can land on one vCPU and stay there for a whole
//! sample, which then takes 2.0× as long. In a recording of `meshes.toml` at 379dacc (2-vCPU VM) 6% of the
//! two-thread samples of in-process backends did (docs/statistics.md). Pinned, the threads of a strategy run on
//! different CPUs; one-thread strategies stay unpinned. A thread inherits the mask of the thread that spawns it, so
//! every strategy pins its own workers ([`crate::executor`]) rather than relying on where it was called from: an
//! mpsc band thread spawned from a pinned pool thread once ran on that one CPU, whatever the thread count.

/// The CPUs `threads` workers are pinned to, worker `i` to entry `i`: the first `threads` CPUs this process may run
/// on; none for one thread, or when the process may use fewer CPUs than that (the threads then share them).
pub fn cpus_for(threads: usize) -> Vec<usize> {
    let allowed = allowed_cpus();
    if threads < 2 || allowed.len() < threads {
        return Vec::new();
    }
    allowed[..threads].to_vec()
}

/// Pins the calling thread to entry `worker` of `cpus` (from [`cpus_for`]); with no entry there, lets it run on every
/// CPU this process may use, so a worker spawned from a pinned thread does not inherit that one CPU.
pub fn pin_worker(cpus: &[usize], worker: usize) {
    match cpus.get(worker) {
        Some(&cpu) => set_current_thread(&[cpu]),
        None => set_current_thread(&allowed_cpus()),
    }
}

/// The CPUs this process may run on, in order (empty where that is not known). The process id names the main
/// thread, which is never pinned, so a pool started from a pinned thread still sees every CPU.
#[cfg(target_os = "linux")]
pub fn allowed_cpus() -> Vec<usize> {
    // SAFETY: getpid cannot fail.
    affinity(unsafe { libc::getpid() })
}

/// The CPUs the calling thread may run on, in order (empty where that is not known).
#[cfg(target_os = "linux")]
pub fn current_thread_cpus() -> Vec<usize> {
    affinity(0)
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

/// The CPUs the calling thread may run on, in order (empty where that is not known).
#[cfg(not(target_os = "linux"))]
pub fn current_thread_cpus() -> Vec<usize> {
    Vec::new()
}

/// Lets the calling thread run on `cpus` only (a no-op for none, where that is not supported, or when the call
/// fails).
fn set_current_thread(cpus: &[usize]) {
    if cpus.is_empty() {
        return;
    }
    #[cfg(target_os = "linux")]
    // SAFETY: `set` is a plain bit set; each CPU is below CPU_SETSIZE (it came from one); its size is passed; 0
    // names the calling thread.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        for &cpu in cpus.iter().filter(|&&c| c < libc::CPU_SETSIZE as usize) {
            libc::CPU_SET(cpu, &mut set);
        }
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    #[test]
    fn a_pinned_worker_runs_only_on_its_cpu_and_an_unlisted_one_anywhere() {
        let allowed = allowed_cpus();
        assert!(!allowed.is_empty());
        let cpu = *allowed.last().unwrap();
        let (pinned, unpinned, process) = std::thread::spawn(move || {
            pin_worker(&[cpu], 0);
            let pinned = current_thread_cpus();
            // A worker without an entry, spawned from the pinned thread, runs anywhere again.
            let unpinned = std::thread::spawn(|| {
                pin_worker(&[], 1);
                current_thread_cpus()
            })
            .join()
            .unwrap();
            (pinned, unpinned, allowed_cpus())
        })
        .join()
        .unwrap();
        assert_eq!(pinned, vec![cpu]);
        assert_eq!(unpinned, allowed);
        assert_eq!(process, allowed);
        assert!(cpus_for(1).is_empty());
        assert_eq!(cpus_for(allowed.len()), allowed);
        assert!(cpus_for(allowed.len() + 1).is_empty());
    }
}
