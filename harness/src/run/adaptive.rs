//! Adaptive repetitions (`repetitions = "auto"`): a configuration stops being timed once the 95% interval of its
//! median is narrow enough, as hyperfine's `--min-runs`/`--max-runs` and criterion's measurement time decide it.
//!
//! The interval is the report's (the median's distribution-free interval, [`report::stats::median_ci`]) of the
//! metric speedups are ratios of, so a configuration that stopped shows an interval at most the target wide. No
//! configuration stops before it has [`report::stats::MIN_SAMPLES_FOR_INTERVAL`] samples, whatever its minimum.

use schema::column;
use std::collections::HashMap;

use report::stats;

use super::measure::Timing;
use crate::config::Repetitions;

/// The phase whose samples decide for `metric`: the phase itself, `trace_s` for `mrays_per_s` (the same relative
/// interval); `None` for a counter, which is the same in every repetition.
pub fn deciding_phase(metric: &str) -> Option<&'static str> {
    [column::setup_s, column::scene_s, column::build_s, column::trace_s, column::encode_s, column::total_s]
        .into_iter()
        .find(|p| *p == metric)
        .or((metric == column::mrays_per_s).then_some(column::trace_s))
}

/// The value of `metric`'s deciding phase in a run's timing.
pub fn timed_value(t: &Timing, metric: &str) -> Option<f64> {
    Some(match deciding_phase(metric)? {
        column::setup_s => t.setup_s,
        column::scene_s => t.scene_s,
        column::build_s => t.build_s,
        column::trace_s => t.trace_s,
        column::encode_s => t.encode_s,
        _ => t.total_s(),
    })
}

/// The value of `metric`'s deciding phase in a recorded row.
pub fn recorded_value(row: &schema::Row, metric: &str) -> Option<f64> {
    deciding_phase(metric).and_then(|p| row.cell(p)).map(|c| c.number())
}

/// Relative width `(hi - lo) / median` of the 95% interval of the median of `samples`; `None` below
/// [`stats::MIN_SAMPLES_FOR_INTERVAL`] samples, which have no interval.
pub fn interval_width(samples: &[f64]) -> Option<f64> {
    let e = stats::median_ci(samples);
    e.lo.is_finite().then(|| if e.value > 0.0 { (e.hi - e.lo) / e.value } else { 0.0 })
}

/// Each configuration's samples so far, and whether it is done.
pub struct Sampler {
    rule: Repetitions,
    samples: HashMap<usize, Vec<f64>>,
    done: HashMap<usize, bool>,
    /// Configurations that reached the minimum, and those of them that went past it.
    reached_min: usize,
    went_on: usize,
}

impl Sampler {
    /// No samples yet.
    pub fn new(rule: Repetitions) -> Self {
        Self { rule, samples: HashMap::new(), done: HashMap::new(), reached_min: 0, went_on: 0 }
    }

    /// Records configuration `config`'s next repetition (`value`: its metric, `None` for a deterministic metric)
    /// and returns the interval width after it.
    pub fn record(&mut self, config: usize, value: Option<f64>) -> Option<f64> {
        let samples = self.samples.entry(config).or_default();
        samples.push(value.unwrap_or(0.0));
        let n = samples.len() as u32;
        let width = match value {
            Some(_) => interval_width(samples),
            None => (n >= 2).then_some(0.0),
        };
        let done = match self.rule {
            Repetitions::Fixed(reps) => n >= reps,
            Repetitions::Auto { min, max, target_width } => {
                n >= max || (n >= min && width.is_some_and(|w| w <= target_width))
            }
        };
        self.done.insert(config, done);
        if n == self.rule.min() {
            self.reached_min += 1;
            self.went_on += usize::from(!done);
        }
        width
    }

    /// True once `config` needs no more repetitions.
    pub fn is_done(&self, config: usize) -> bool {
        self.done.get(&config).copied().unwrap_or(false)
    }

    /// Repetitions recorded for `config`.
    pub fn count(&self, config: usize) -> u32 {
        self.samples.get(&config).map_or(0, |s| s.len() as u32)
    }

    /// The repetitions `config` is expected to need beyond those recorded, for the time estimate: up to the
    /// minimum surely, and past it as often as configurations that reached the minimum went on so far (half of
    /// the way to the maximum before any did).
    pub fn expected_left(&self, config: usize) -> f64 {
        if self.is_done(config) {
            return 0.0;
        }
        let (min, max) = (self.rule.min(), self.rule.max());
        let n = self.count(config);
        let share = if self.reached_min == 0 { 0.5 } else { self.went_on as f64 / self.reached_min as f64 };
        if n < min {
            (min - n) as f64 + share * (max - min) as f64
        } else {
            // Past the minimum and not done: it was too noisy to stop; assume it runs to the maximum.
            (max - n) as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const AUTO: Repetitions = Repetitions::Auto { min: 6, max: 9, target_width: 0.03 };

    #[test]
    fn quiet_samples_stop_at_the_minimum() {
        let mut s = Sampler::new(AUTO);
        for (i, x) in [1.000, 1.001, 0.999, 1.0005, 0.9995, 1.0].into_iter().enumerate() {
            assert!(!s.is_done(0), "done after {i}");
            s.record(0, Some(x));
        }
        assert!(s.is_done(0));
        assert_eq!(s.expected_left(0), 0.0);
    }

    #[test]
    fn no_configuration_stops_before_its_median_has_an_interval() {
        let mut s = Sampler::new(Repetitions::Auto { min: 3, max: 20, target_width: 0.05 });
        for i in 0..stats::MIN_SAMPLES_FOR_INTERVAL {
            assert!(!s.is_done(0), "done after {i} identical samples");
            assert_eq!(s.record(0, Some(1.0)).is_some(), i + 1 >= stats::MIN_SAMPLES_FOR_INTERVAL);
        }
        assert!(s.is_done(0));
    }

    #[test]
    fn noisy_samples_run_to_the_maximum() {
        let mut s = Sampler::new(AUTO);
        for x in [1.0, 1.2, 0.9, 1.1, 0.8, 1.15, 0.85, 1.05] {
            s.record(0, Some(x));
            assert!(!s.is_done(0));
        }
        assert_eq!(s.expected_left(0), 1.0);
        let width = s.record(0, Some(1.3)).unwrap();
        assert!(width > 0.03, "{width}");
        assert!(s.is_done(0), "stops at max_repetitions");
    }

    #[test]
    fn a_noisy_start_goes_on_until_the_interval_narrows() {
        let mut s = Sampler::new(Repetitions::Auto { min: 3, max: 20, target_width: 0.05 });
        let xs = [1.0, 1.3, 1.0, 1.01, 0.99, 1.0, 1.02, 0.98, 1.0, 1.01, 0.99, 1.0, 1.0, 1.0, 1.0];
        let mut stopped = None;
        for (i, x) in xs.into_iter().enumerate() {
            s.record(0, Some(x));
            if s.is_done(0) {
                stopped = Some(i + 1);
                break;
            }
        }
        let n = stopped.expect("the interval narrows within 15 samples");
        assert!((7..=15).contains(&n), "stopped after {n}");
    }

    #[test]
    fn deterministic_metrics_stop_at_the_minimum_and_fixed_rules_at_their_count() {
        let mut s = Sampler::new(AUTO);
        for _ in 0..6 {
            assert!(!s.is_done(1));
            assert_eq!(timed_value(&Timing::untimed(0), "nodes_per_ray"), None);
            s.record(1, None);
        }
        assert!(s.is_done(1));
        let mut f = Sampler::new(Repetitions::Fixed(2));
        f.record(0, Some(1.0));
        assert!(!f.is_done(0));
        f.record(0, Some(5.0));
        assert!(f.is_done(0));
    }

    #[test]
    fn expected_repetitions_follow_what_configurations_did() {
        let mut s = Sampler::new(AUTO);
        assert_eq!(s.expected_left(0), 6.0 + 0.5 * 3.0, "before any configuration reached the minimum");
        for x in [1.0; 6] {
            s.record(0, Some(x));
        }
        assert_eq!(s.expected_left(1), 6.0, "the one that reached the minimum stopped there");
    }
}
