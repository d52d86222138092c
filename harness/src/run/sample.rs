//! A sample: the trace passes of one or more trials taken in turn until each has run at least `sample_ms`, and the
//! hypervisor's steal over it. "Sample" means this one thing in the harness.

use crate::error::Error;

/// Seconds per tick of `/proc/stat` (`USER_HZ`, 100 on Linux).
const STAT_TICK_S: f64 = 0.01;

/// The hypervisor's steal time so far, summed over all CPUs, in ticks (`/proc/stat`'s `cpu` line, 8th value).
fn steal_ticks() -> Option<u64> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    stat.lines().next()?.split_whitespace().nth(8)?.parse().ok()
}

/// Attempts of a timed sample when steal time was seen during it (the attempt with the least steal is kept).
const STEAL_ATTEMPTS: u32 = 3;

/// Something whose trace passes can be taken one at a time: a [`super::trial::Trial`] in this process, or one in a
/// worker.
pub trait TakesPasses {
    /// Takes one more pass of the trace: its seconds.
    fn pass(&mut self) -> Result<f64, Error>;
}

/// One sample of every trial in `trials`, taken in turn: a pass of each, then again, until each trial's passes add
/// up to `min_s` (at least one pass each, so 0 takes exactly one). With `min_s` above 0 the hypervisor's steal
/// over the sample is read, and a sample that saw steal is taken again, up to [`STEAL_ATTEMPTS`] times, keeping
/// the attempt with the least. Returns each trial's pass times and the steal of the kept attempt.
pub fn sample(trials: &mut [&mut dyn TakesPasses], min_s: f64) -> Result<(Vec<Vec<f64>>, Option<f64>), Error> {
    let mut attempt = || -> Result<(Vec<Vec<f64>>, Option<f64>), Error> {
        let steal = (min_s > 0.0).then(steal_ticks).flatten();
        let mut passes = vec![Vec::new(); trials.len()];
        let mut sums = vec![0.0; trials.len()];
        while sums.iter().zip(&passes).any(|(&sum, p)| p.is_empty() || sum < min_s) {
            for (i, trial) in trials.iter_mut().enumerate() {
                if passes[i].is_empty() || sums[i] < min_s {
                    let seconds = trial.pass()?;
                    passes[i].push(seconds);
                    sums[i] += seconds;
                }
            }
        }
        let stolen = steal.and_then(|a| steal_ticks().map(|b| b.saturating_sub(a) as f64 * STAT_TICK_S));
        Ok((passes, stolen))
    };
    let mut kept = attempt()?;
    for _ in 1..if min_s > 0.0 { STEAL_ATTEMPTS } else { 1 } {
        if kept.1.is_none_or(|s| s == 0.0) {
            break;
        }
        let again = attempt()?;
        if again.1 <= kept.1 {
            kept = again;
        }
    }
    Ok(kept)
}

#[cfg(test)]
mod tests {
    use std::time::Instant;

    use super::*;

    /// A trial whose passes take `ms` milliseconds each, logging its name in `log` per pass.
    struct Sleeper<'a> {
        name: char,
        ms: u64,
        log: &'a std::cell::RefCell<String>,
    }

    impl TakesPasses for Sleeper<'_> {
        fn pass(&mut self) -> Result<f64, Error> {
            self.log.borrow_mut().push(self.name);
            let t = Instant::now();
            std::thread::sleep(std::time::Duration::from_millis(self.ms));
            Ok(t.elapsed().as_secs_f64())
        }
    }

    #[test]
    fn a_sample_takes_passes_in_turn_until_each_trial_reaches_its_floor() {
        let log = std::cell::RefCell::new(String::new());
        let (mut a, mut b) = (Sleeper { name: 'a', ms: 10, log: &log }, Sleeper { name: 'b', ms: 1, log: &log });
        let (passes, steal) = sample(&mut [&mut a, &mut b], 0.0).unwrap();
        assert_eq!((passes.iter().map(Vec::len).collect::<Vec<_>>(), steal), (vec![1, 1], None), "no floor: one pass");
        assert_eq!(*log.borrow(), "ab");
        log.borrow_mut().clear();
        let (passes, _) = sample(&mut [&mut a, &mut b], 0.02).unwrap();
        for (p, name) in passes.iter().zip(["a", "b"]) {
            assert!(p.iter().sum::<f64>() >= 0.02, "{name}: {p:?}");
            assert!(p.iter().sum::<f64>() - p.last().unwrap() < 0.02, "{name} stops once past the floor: {p:?}");
        }
        // The log holds every attempt (a sample that saw hypervisor steal is taken again): in each, `a` and `b` in
        // turn while both sample, then `b`, whose passes are shorter, alone. So `a` never passes twice in a row.
        let log = log.borrow();
        let turns = passes[0].len().min(passes[1].len());
        assert!(log.starts_with("ab") && log.ends_with('b') && !log.contains("aa"), "in turn while both sample: {log}");
        assert!(log.contains(&"ab".repeat(turns)), "the kept attempt's {turns} turns: {log}");
    }
}
