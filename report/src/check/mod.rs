//! Regression check: compares a new run directory with a stored baseline of the same experiment.
//!
//! Four kinds of evidence, two of them deterministic and gating on any machine:
//! - **work counters** (rays, work per ray, tree statistics, hashes) must match exactly per configuration;
//! - **instruction counts** under callgrind (`instructions.csv`, written by `harness instructions`): a phase of a
//!   configuration that executes more than `1 + instruction_threshold` times the baseline's instructions fails,
//!   when both sides were counted by the same compiler with the same target features (else they are compared for
//!   information);
//!
//! and two from wall times, whose gating depends on the [`TimingMode`]:
//! - **absolute times** (`trace_s`, `build_s`) of every configuration, the reference series and multi-thread
//!   ones included: a ratio of medians new/old with a 95% bootstrap interval, regressed when the interval lies
//!   above `1 + min_effect` (builds: `min_effect_build`); they gate only when every row of run and baseline comes
//!   from one machine (`machine_id`). A flagged configuration is measured again
//!   (`confirm.csv`, see [`CheckOutcome::confirm`]) and fails only if the second measurement agrees;
//! - **speedups** over the reference series, pooled over seeds like the figures' points, with a bootstrap
//!   interval of `new / old`: always for information (a slowdown of shared code slows the reference most and
//!   raises them; the absolute times see it).
//!
//! [`compare`] computes a [`CheckOutcome`] (module `compare`, instruction counts in module `instructions`);
//! [`CheckOutcome::markdown`] and [`CheckOutcome::to_json`] render it (module `render`).

mod compare;
pub mod instructions;
mod render;

use schema::column;
use serde::Serialize;

pub use crate::stats::Estimate;
pub use compare::compare;
pub(crate) use compare::speedups;
pub use instructions::{InstructionCheck, InstructionComparison, InstructionCount};

/// Deterministic columns compared exactly between the first repetitions of a configuration: the schema's
/// counters (`schema::row::counter_names`).
pub fn counters() -> Vec<&'static str> {
    schema::row::counter_names()
}

/// The wall-time phases compared per configuration.
pub const TIMED_PHASES: [&str; 2] = [column::trace_s, column::build_s];

/// How strict the comparison is.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOptions {
    /// Metric column the speedups are computed from (a time: smaller is better).
    pub metric: String,
    /// Smallest relative change of a trace time or a speedup that counts (0.10: 10%): a trace time regressed when
    /// the 95% interval of its ratio new/old lies above `1 + min_effect`.
    pub min_effect: f64,
    /// The same for build times (0.30: 30%): builds of a few milliseconds drift by up to 1.5× between runs of one
    /// binary on this project's shared 2-vCPU machines, while their instruction counts gate at +2%.
    pub min_effect_build: f64,
    /// Counter changes and configurations present on one side only do not fail the check.
    pub accept_counter_changes: bool,
    /// Timings are compared for information only and never fail the check, even from one machine.
    pub timings_for_information: bool,
    /// Phases whose baseline median is shorter than this (seconds) are compared for information only: timer
    /// and scheduling noise dominates them (their instruction counts still gate).
    pub min_time_s: f64,
    /// Largest relative growth of a phase's instruction count that passes (0.02: 2%).
    pub instruction_threshold: f64,
    /// Times gate only where the run's median 1-minute load average exceeds the baseline's by at most this much:
    /// on a shared machine more runnable tasks than cores slow every phase for minutes (its second measurement
    /// too), e.g. 1.16× in a flat BVH trace at load 3.0 against a baseline at 1.8 on 2 vCPUs.
    pub max_extra_load: f64,
}

impl CheckOptions {
    /// The minimum effect of a phase time (`build_s`: [`CheckOptions::min_effect_build`]; else `min_effect`).
    pub fn time_effect(&self, metric: &str) -> f64 {
        if metric == column::build_s { self.min_effect_build } else { self.min_effect }
    }
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            metric: column::trace_s.into(),
            min_effect: 0.10,
            min_effect_build: 0.30,
            accept_counter_changes: false,
            timings_for_information: false,
            min_time_s: 1e-4,
            instruction_threshold: 0.02,
            max_extra_load: 1.0,
        }
    }
}

/// Which wall times gate, and why: the check's first output line ([`TimingMode::line`]).
#[derive(Clone, Debug, PartialEq)]
pub enum TimingMode {
    /// Every row of run and baseline has this `machine_id` and `boot_id`: absolute times gate.
    SameMachine {
        /// The one machine.
        machine_id: String,
        /// The one boot of it.
        boot_id: String,
    },
    /// Timings are compared for information only, because of `reason` (another machine, rows without a
    /// machine, or `--timings-for-information`).
    Information {
        /// Why, e.g. `run on machine 3f2a…, baseline on 700e…`.
        reason: String,
    },
}

impl TimingMode {
    /// Whether absolute times gate.
    pub fn gates_times(&self) -> bool {
        matches!(self, TimingMode::SameMachine { .. })
    }

    /// One line: the mode and why.
    pub fn line(&self) -> String {
        match self {
            TimingMode::SameMachine { machine_id, boot_id } => format!(
                "timing mode: same machine (machine_id {machine_id}, boot {}): trace_s and build_s of every \
                 configuration gated, besides instruction counts and work counters",
                compare::short_boot(boot_id)
            ),
            TimingMode::Information { reason } => {
                format!("timing mode: information only: {reason}; gating instruction counts and work counters")
            }
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

/// Outcome of one comparison of a measure between baseline and run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Worse, significantly and by more than the minimum effect (or, for instruction counts, the threshold).
    Regressed,
    /// Better by as much.
    Improved,
    /// Neither.
    Unchanged,
}

/// The old name of [`Verdict`].
pub type SpeedupVerdict = Verdict;

impl Verdict {
    /// Lower-case word for the verdict.
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Regressed => "regressed",
            Verdict::Improved => "improved",
            Verdict::Unchanged => "unchanged",
        }
    }

    /// Sort key: regressions first, then improvements.
    pub(crate) fn rank(self) -> u8 {
        match self {
            Verdict::Regressed => 0,
            Verdict::Improved => 1,
            Verdict::Unchanged => 2,
        }
    }
}

/// The speedup of one series at one point, in baseline and new run (for information).
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
    /// Regressed (the speedup fell), improved or unchanged.
    pub verdict: Verdict,
}

/// One wall-time phase of one configuration, in baseline and run.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeComparison {
    /// The configuration id.
    pub config_id: String,
    /// The series label.
    pub series: String,
    /// Short description of the configuration's settings.
    pub settings: String,
    /// Threads the configuration used.
    pub threads: String,
    /// `trace_s` or `build_s`.
    pub metric: &'static str,
    /// The first measurement: baseline and run medians, ratio and verdict.
    pub first: TimeRatio,
    /// Whether this phase can fail the check: same machine, and a baseline median of at least
    /// [`CheckOptions::min_time_s`].
    pub gating: bool,
    /// The second measurement of a gating regression (`confirm.csv`), once made.
    pub confirmation: Option<TimeRatio>,
}

impl TimeComparison {
    /// A gating regression that a second measurement did not clear: confirmed, or not measured again.
    pub fn fails(&self) -> bool {
        self.gating
            && self.first.verdict == Verdict::Regressed
            && self.confirmation.as_ref().is_none_or(|c| c.verdict == Verdict::Regressed)
    }

    /// A gating regression of the first measurement, to be measured again.
    pub fn flagged(&self) -> bool {
        self.gating && self.first.verdict == Verdict::Regressed
    }
}

/// Medians of one phase in baseline and run (each with its 95% interval), and their ratio run/baseline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeRatio {
    /// Baseline median.
    pub old: Estimate,
    /// Run median.
    pub new: Estimate,
    /// `new / old` medians with the ratio's 95% bootstrap interval.
    pub ratio: Estimate,
    /// Regressed (slower), improved (faster) or unchanged.
    pub verdict: Verdict,
}

/// Everything the check found.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOutcome {
    /// Which timings gate, and why.
    pub mode: TimingMode,
    /// Counter differences, one per configuration and column.
    pub counter_changes: Vec<CounterChange>,
    /// Configurations present on one side only, described.
    pub missing: Vec<String>,
    /// Instruction counts, when both sides have them.
    pub instructions: InstructionCheck,
    /// Wall times per configuration and phase.
    pub times: Vec<TimeComparison>,
    /// Speedup comparisons, by series then point (for information).
    pub speedups: Vec<SpeedupComparison>,
    /// Configurations present on both sides.
    pub common: usize,
    /// Counter changes and configurations on one side only do not fail.
    pub accept_counter_changes: bool,
}

impl CheckOutcome {
    /// The gate: a gating instruction-count regression, a gating time regression not cleared by its second
    /// measurement, or counter changes / missing configurations not accepted.
    pub fn failed(&self) -> bool {
        self.instructions.failed()
            || self.times.iter().any(TimeComparison::fails)
            || (!self.accept_counter_changes && (!self.counter_changes.is_empty() || !self.missing.is_empty()))
    }

    /// Configuration ids with a time regression to measure again (each once).
    pub fn to_confirm(&self) -> Vec<String> {
        let mut ids: Vec<String> = Vec::new();
        for t in self.times.iter().filter(|t| t.flagged()) {
            if !ids.contains(&t.config_id) {
                ids.push(t.config_id.clone());
            }
        }
        ids
    }
}
