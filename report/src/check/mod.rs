//! Regression check: compares a new run directory with a stored baseline of the same experiment.
//!
//! Two kinds of evidence: deterministic counters (rays, work per ray, tree statistics, hashes) must
//! match exactly per configuration; speedups against the reference series, pooled over seeds like
//! the figures' points, are compared with a percentile-bootstrap interval of `new / old`.
//!
//! [`compare`] computes a [`CheckOutcome`] (module `compare`); [`CheckOutcome::markdown`] and
//! [`CheckOutcome::to_json`] render it (module `render`).

mod compare;
mod render;

use serde::Serialize;

pub use crate::stats::Estimate;
pub use compare::compare;
pub(crate) use compare::speedups;

/// Deterministic columns compared exactly between the first repetitions of a configuration: the schema's
/// counters (`schema::row::counter_names`).
pub fn counters() -> Vec<&'static str> {
    schema::row::counter_names()
}

/// How strict the comparison is.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOptions {
    /// Metric column the speedups are computed from (a time: smaller is better).
    pub metric: String,
    /// Smallest relative change of a speedup that counts (0.10: 10%).
    pub min_effect: f64,
    /// Counter changes and configurations present on one side only do not fail the check.
    pub accept_counter_changes: bool,
    /// Only points whose series runs use this many threads gate the check.
    pub gate_threads: u32,
    /// Speedups are compared for information only and never fail the check (a baseline from another machine).
    pub timings_for_information: bool,
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            metric: "trace_s".into(),
            min_effect: 0.10,
            accept_counter_changes: false,
            gate_threads: 1,
            timings_for_information: false,
        }
    }
}

/// One deterministic column that differs between baseline and new run for one configuration.
///
/// Serialized as it appears in `check.json`'s `counter_changes`: the field names are the keys.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CounterChange {
    /// The configuration id.
    pub config_id: String,
    /// The series label.
    pub series: String,
    /// Short description of the configuration's settings, e.g. `random-spheres objects 1000 seed 1`.
    pub settings: String,
    /// The column that changed.
    pub column: String,
    /// Baseline value.
    pub old: String,
    /// New value.
    pub new: String,
}

/// Outcome of one speedup comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpeedupVerdict {
    /// The speedup fell significantly and by more than the minimum effect.
    Regressed,
    /// The speedup rose significantly and by more than the minimum effect.
    Improved,
    /// Neither.
    Unchanged,
}

impl SpeedupVerdict {
    /// Lower-case word for the verdict.
    pub fn word(self) -> &'static str {
        match self {
            SpeedupVerdict::Regressed => "regressed",
            SpeedupVerdict::Improved => "improved",
            SpeedupVerdict::Unchanged => "unchanged",
        }
    }
}

/// The speedup of one series at one point, in baseline and new run.
#[derive(Clone, Debug, PartialEq)]
pub struct SpeedupComparison {
    /// The series label.
    pub series: String,
    /// The point, e.g. `objects 1000 (threads 1)`.
    pub point: String,
    /// Baseline speedup (reference median / series median) with its 95% interval.
    pub old: Estimate,
    /// New speedup with its 95% interval.
    pub new: Estimate,
    /// `new.value / old.value`.
    pub ratio: f64,
    /// Lower end of the ratio's 95% bootstrap interval.
    pub lo: f64,
    /// Upper end of the ratio's 95% bootstrap interval.
    pub hi: f64,
    /// Regressed, improved or unchanged.
    pub verdict: SpeedupVerdict,
    /// Whether this point can fail the check (its threads equal `gate_threads`).
    pub gating: bool,
}

/// Everything the check found.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOutcome {
    /// Counter differences, one per configuration and column.
    pub counter_changes: Vec<CounterChange>,
    /// Configurations present on one side only, described.
    pub missing: Vec<String>,
    /// Speedup comparisons, by series then point.
    pub speedups: Vec<SpeedupComparison>,
    /// Configurations present on both sides.
    pub common: usize,
    /// The gate: a gating regression, or counter changes / missing configurations not accepted.
    pub failed: bool,
    /// Speedups were compared for information only.
    pub timings_for_information: bool,
}
