//! Adaptive repetitions (`repetitions = "auto"`): a configuration stops being timed once the 95% interval of its
//! median is narrow enough, as hyperfine's `--min-runs`/`--max-runs` and criterion's measurement time decide it.
//!
//! The interval is the report's (the median's distribution-free interval, [`report::stats::median_ci`]) of the
//! metric speedups are ratios of. With interleaved rounds a configuration is decided by what its claims and
//! speedups use: the median of its per-round ratios to the reference series' configuration at its point (which
//! goes on while any configuration paired with it does, and stops with the last of them); otherwise by its own
//! median. So a configuration that stopped shows an interval at most the target wide (a reference: its ratios do). No configuration stops before it has
//! [`report::stats::MIN_SAMPLES_FOR_INTERVAL`] samples, whatever its minimum.

use schema::column;
use std::collections::HashMap;

use report::stats;

use super::trial::Timing;
use crate::config::{Experiment, Repetitions};
use crate::plan::Configuration;

/// The metric whose interval decides `c`'s repetitions: the experiment's speedup metric for its workload.
pub fn metric<'a>(exp: &'a Experiment, c: &Configuration) -> &'a str {
    report::spec::speedup_metric(exp.speedup_metric.as_deref(), schema::Named::name(c.settings.workload))
}

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
pub struct Stopping {
    rule: Repetitions,
    /// Each configuration's reference (the reference series' configuration at its point), when its rounds pair
    /// with it: the configuration is then decided by the interval of its per-round ratios to the reference.
    reference: Vec<Option<usize>>,
    /// The configurations paired with each reference (the inverse of `reference`).
    partners: HashMap<usize, Vec<usize>>,
    samples: HashMap<usize, Vec<f64>>,
    /// Configurations whose metric is a counter (the same every time).
    deterministic: HashMap<usize, bool>,
    /// Configurations that reached the minimum, and those of them that went past it.
    reached_min: usize,
    went_on: usize,
}

impl Stopping {
    /// No samples yet; `reference[c]` is configuration `c`'s paired reference, if any (see [`Stopping::paired`]).
    pub fn new(rule: Repetitions, reference: Vec<Option<usize>>) -> Self {
        let mut partners: HashMap<usize, Vec<usize>> = HashMap::new();
        for (c, r) in reference.iter().enumerate() {
            if let Some(r) = r {
                partners.entry(*r).or_default().push(c);
            }
        }
        let (samples, deterministic) = (HashMap::new(), HashMap::new());
        Self { rule, reference, partners, samples, deterministic, reached_min: 0, went_on: 0 }
    }

    /// Each configuration's reference for [`Stopping::new`]: with interleaved rounds, the one configuration of the
    /// `reference` series at the same point (`points[c]`, `series[c]`), none for the reference itself or where
    /// the point has not exactly one.
    pub fn paired(points: &[usize], series: &[&str], reference: Option<&str>) -> Vec<Option<usize>> {
        // The reference's configurations by point: one, or `None` where it has several.
        let mut at_point: HashMap<usize, Option<usize>> = HashMap::new();
        for (c, &point) in points.iter().enumerate().filter(|&(c, _)| Some(series[c]) == reference) {
            at_point.entry(point).and_modify(|r| *r = None).or_insert(Some(c));
        }
        (0..points.len())
            .map(|c| if Some(series[c]) == reference { None } else { at_point.get(&points[c]).copied().flatten() })
            .collect()
    }

    /// Records configuration `config`'s next repetition (`value`: its metric, `None` for a deterministic metric)
    /// and returns the interval width that decides it after it.
    pub fn record(&mut self, config: usize, value: Option<f64>) -> Option<f64> {
        self.samples.entry(config).or_default().push(value.unwrap_or(0.0));
        self.deterministic.insert(config, value.is_none());
        if self.count(config) == self.rule.min() {
            self.reached_min += 1;
            self.went_on += usize::from(!self.is_done(config));
        }
        self.width(config)
    }

    /// The relative width of the interval that decides `config`: of the median of its per-round ratios to its
    /// reference where it has one that is timed, else of its own median; 0 for a counter from two samples on.
    pub fn width(&self, config: usize) -> Option<f64> {
        let own = self.samples.get(&config)?;
        if self.deterministic.get(&config) == Some(&true) {
            return (own.len() >= 2).then_some(0.0);
        }
        let reference = self.reference.get(config).copied().flatten();
        match reference.and_then(|r| self.samples.get(&r).filter(|_| self.deterministic.get(&r) == Some(&false))) {
            Some(theirs) => {
                let ratios: Vec<f64> = own.iter().zip(theirs).map(|(a, b)| a / b).collect();
                interval_width(&ratios)
            }
            None => interval_width(own),
        }
    }

    /// True once `config` needs no more repetitions: its count, or (auto) the maximum, or the minimum with its
    /// interval narrow enough. A reference is decided by the configurations paired with it (what its rounds are
    /// for is their ratios to it, which claims and speedups read): it goes on while one of them does, and stops
    /// with the last of them, however wide its own median's interval.
    pub fn is_done(&self, config: usize) -> bool {
        let n = self.count(config);
        match self.rule {
            Repetitions::Fixed(reps) => n >= reps,
            Repetitions::Auto { min, max, target_width } => {
                n >= max
                    || (n >= min
                        && match self.partners.get(&config) {
                            Some(paired) => paired.iter().all(|&c| self.is_done(c)),
                            None => self.width(config).is_some_and(|w| w <= target_width),
                        })
            }
        }
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
        let mut s = Stopping::new(AUTO, vec![None, None]);
        for (i, x) in [1.000, 1.001, 0.999, 1.0005, 0.9995, 1.0].into_iter().enumerate() {
            assert!(!s.is_done(0), "done after {i}");
            s.record(0, Some(x));
        }
        assert!(s.is_done(0));
        assert_eq!(s.expected_left(0), 0.0);
    }

    #[test]
    fn no_configuration_stops_before_its_median_has_an_interval() {
        let mut s = Stopping::new(Repetitions::Auto { min: 3, max: 20, target_width: 0.05 }, vec![None]);
        for i in 0..stats::MIN_SAMPLES_FOR_INTERVAL {
            assert!(!s.is_done(0), "done after {i} identical samples");
            assert_eq!(s.record(0, Some(1.0)).is_some(), i + 1 >= stats::MIN_SAMPLES_FOR_INTERVAL);
        }
        assert!(s.is_done(0));
    }

    #[test]
    fn noisy_samples_run_to_the_maximum() {
        let mut s = Stopping::new(AUTO, vec![None, None]);
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
        let mut s = Stopping::new(Repetitions::Auto { min: 3, max: 20, target_width: 0.05 }, vec![None]);
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
    fn a_configuration_paired_with_its_reference_stops_on_its_ratio_and_the_reference_waits_for_it() {
        // Configuration 1 is paired with reference 0; both swing by ±20% from round to round, together, so the
        // ratio is 0.5 throughout; configuration 2 is noisy on its own and paired with nothing.
        let reference = Stopping::paired(&[0, 0, 1], &["ref", "new", "new"], Some("ref"));
        assert_eq!(reference, [None, Some(0), None]);
        let mut s = Stopping::new(AUTO, reference);
        let swings = [1.0, 1.2, 0.8, 1.1, 0.9, 1.0];
        for (i, x) in swings.into_iter().enumerate() {
            assert!(!s.is_done(1), "done after {i}");
            s.record(0, Some(2.0 * x));
            s.record(1, Some(x));
            s.record(2, Some(x));
        }
        assert_eq!(s.width(1), Some(0.0), "the ratio is the same in every round");
        assert!(s.width(2).unwrap() > 0.03 && s.width(0).unwrap() > 0.03);
        assert!(s.is_done(1), "settled on its ratio at the minimum");
        assert!(!s.is_done(2), "settles nothing by its own median");
        assert!(s.width(0).unwrap() > 0.03 && s.is_done(0), "the reference stops with its partner, wide as it is");
        for _ in 6..9 {
            s.record(2, Some(1.0));
        }
        assert!(s.is_done(2), "at the maximum");
        // A reference that is quiet on its own still waits for a configuration paired with it.
        let mut s = Stopping::new(AUTO, vec![None, Some(0)]);
        for x in [1.0, 1.2, 0.8, 1.1, 0.9, 1.0] {
            s.record(0, Some(1.0));
            s.record(1, Some(x));
        }
        assert_eq!(s.width(0), Some(0.0));
        assert!(!s.is_done(1) && !s.is_done(0));
    }

    /// A timing of nothing in particular.
    fn any_timing() -> Timing {
        let stats = r#"{"nodes": 0, "leaves": 0, "depth": 0, "bytes": 0, "sah_cost": 0}"#;
        let json = format!(
            r#"{{"scene_s": 0, "build_s": 0, "trace_s": 0, "encode_s": 0, "output_hash": 0, "scene_fingerprint": 0, "stats": {stats}, "peer_info": "-"}}"#
        );
        serde_json::from_str(&json).unwrap()
    }

    #[test]
    fn deterministic_metrics_stop_at_the_minimum_and_fixed_rules_at_their_count() {
        let mut s = Stopping::new(AUTO, vec![None, None]);
        for _ in 0..6 {
            assert!(!s.is_done(1));
            assert_eq!(timed_value(&any_timing(), "nodes_per_ray"), None);
            s.record(1, None);
        }
        assert!(s.is_done(1));
        let mut f = Stopping::new(Repetitions::Fixed(2), vec![None]);
        f.record(0, Some(1.0));
        assert!(!f.is_done(0));
        f.record(0, Some(5.0));
        assert!(f.is_done(0));
    }

    #[test]
    fn expected_repetitions_follow_what_configurations_did() {
        let mut s = Stopping::new(AUTO, vec![None, None]);
        assert_eq!(s.expected_left(0), 6.0 + 0.5 * 3.0, "before any configuration reached the minimum");
        for x in [1.0; 6] {
            s.record(0, Some(x));
        }
        assert_eq!(s.expected_left(1), 6.0, "the one that reached the minimum stopped there");
    }
}
