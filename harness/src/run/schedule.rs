//! The schedule: what each configuration still has to run in this sweep ([`Pending`]), what a resumed sweep already
//! recorded, the rounds its runs take, and when a configuration has repetitions enough ([`Stopping`], decided by
//! each configuration's metric, found once here).

use schema::Row;

use super::stopping::{self, Stopping};
use super::trial::Timing;
use super::validate::Validation;
use crate::config::Experiment;
use crate::plan::{Configuration, Plan, PlannedRun};

/// Every configuration's state, and the stopping rule that decides when one has repetitions enough.
pub(super) struct Schedule<'a> {
    exp: &'a Experiment,
    plan: &'a Plan,
    pub states: Vec<ConfigurationState<'a>>,
    stopping: Stopping,
}

/// One configuration through the sweep.
pub(super) struct ConfigurationState<'a> {
    pub configuration: &'a Configuration,
    /// The metric whose interval decides its repetitions ([`stopping::metric`]).
    metric: &'a str,
    /// Its repetition rule as its rows record it (the rule and its metric).
    pub repetition_rule: String,
    /// Its validation, from before its first timed run.
    pub validation: Option<Validation>,
    /// True once it was rejected (recorded once, never timed), here or in the rows it resumes.
    pub rejected: bool,
    /// The runs it still has in this sweep.
    pending: Pending,
}

impl<'a> Schedule<'a> {
    /// Nothing run yet of `plan`; with interleaved rounds each configuration is paired with its point's reference.
    pub fn new(exp: &'a Experiment, plan: &'a Plan) -> Self {
        let reference = if exp.order == crate::config::RunOrder::Interleaved {
            let points: Vec<usize> = plan.configurations.iter().map(|c| c.point).collect();
            let series: Vec<&str> = plan.configurations.iter().map(|c| c.series.as_str()).collect();
            Stopping::paired(&points, &series, exp.reference.as_deref())
        } else {
            vec![None; plan.configurations.len()]
        };
        let stopping = Stopping::new(exp.repetitions, reference);
        let states = plan
            .configurations
            .iter()
            .map(|configuration| {
                let metric = stopping::metric(exp, configuration);
                ConfigurationState {
                    configuration,
                    metric,
                    repetition_rule: exp.repetitions.rule(metric),
                    validation: None,
                    rejected: false,
                    pending: Pending::default(),
                }
            })
            .collect();
        Schedule { exp, plan, states, stopping }
    }

    /// Takes in rows already recorded (a resumed run): a rejected configuration stays rejected, and every recorded
    /// repetition counts as one done (and, with "auto", as a sample). Returns the planned runs still to do, round by
    /// round: a run is to do while its configuration is wanted ([`Schedule::wants`]) and it is a repetition not yet
    /// recorded or a warm-up of a configuration without any; a round is one run, or with `sample_ms` and interleaved
    /// order the consecutive runs of one point's series in one repetition, sampled together a pass of each in turn.
    pub fn resume(&mut self, recorded: &[Row]) -> Vec<Vec<&'a PlannedRun>> {
        let index: std::collections::HashMap<&str, usize> =
            self.states.iter().enumerate().map(|(i, s)| (s.configuration.id.as_str(), i)).collect();
        let mut resumed: Vec<(usize, &Row)> =
            recorded.iter().filter_map(|r| index.get(r.config_id.as_str()).map(|&i| (i, r))).collect();
        resumed.sort_by_key(|(i, r)| (*i, r.repetition));
        for (i, r) in resumed {
            let state = &mut self.states[i];
            if r.validation == schema::ValidationStatus::Failed {
                state.rejected = true;
            } else if state.pending.done.insert(r.repetition) {
                self.stopping.record(i, stopping::recorded_value(r, state.metric));
            }
        }
        let plan = self.plan;
        let together = plan.sample_s > 0.0 && self.exp.order == crate::config::RunOrder::Interleaved;
        let mut rounds: Vec<Vec<&PlannedRun>> = Vec::new();
        for run in &plan.runs {
            let state = &mut self.states[run.config];
            let wanted = !state.rejected && !self.stopping.is_done(run.config);
            let to_do = wanted
                && match run.repetition {
                    Some(rep) => !state.pending.done.contains(&rep),
                    None => self.stopping.count(run.config) == 0,
                };
            if !to_do {
                continue;
            }
            state.pending.add(run);
            match rounds.last_mut() {
                Some(round)
                    if together
                        && plan.configurations[round[0].config].point == plan.configurations[run.config].point
                        && round[0].repetition == run.repetition =>
                {
                    round.push(run)
                }
                _ => rounds.push(vec![run]),
            }
        }
        rounds
    }

    /// True while `run` is still wanted when its round comes: its configuration was not rejected and has not
    /// repetitions enough.
    pub fn wants(&self, run: &PlannedRun) -> bool {
        !self.states[run.config].rejected && !self.stopping.is_done(run.config)
    }

    /// Takes in `run`'s timing: one run less to do, its metric's value to the stopping rule. Returns the interval
    /// width its configuration has reached (repetitions only) and whether the configuration is done.
    pub fn took(&mut self, run: &PlannedRun, timing: &Timing) -> (Option<f64>, bool) {
        let state = &mut self.states[run.config];
        state.pending.take(run);
        let width = match run.repetition {
            Some(_) => self.stopping.record(run.config, stopping::timed_value(timing, state.metric)),
            None => None,
        };
        let done = state.pending.is_empty() || self.stopping.is_done(run.config);
        if done {
            state.finish();
        }
        (width, done)
    }

    /// Runs each configuration is still expected to take, for the time estimate.
    pub fn expected(&self) -> Vec<f64> {
        let left = |(config, state): (usize, &ConfigurationState)| {
            let p = &state.pending;
            p.warmups as f64 + self.stopping.expected_left(config).min(p.repetitions as f64)
        };
        self.states.iter().enumerate().map(left).collect()
    }
}

impl ConfigurationState<'_> {
    /// Marks it rejected and lets its runs go.
    pub fn reject(&mut self) {
        self.rejected = true;
        self.finish();
    }

    /// Ends it: it expects no more runs.
    pub fn finish(&mut self) {
        self.pending.warmups = 0;
        self.pending.repetitions = 0;
    }
}

/// The runs of one configuration still to do in this sweep, and its repetitions recorded.
#[derive(Debug, Default)]
pub(super) struct Pending {
    warmups: usize,
    repetitions: usize,
    done: std::collections::HashSet<u32>,
}

impl Pending {
    /// Counts `run` as one to do.
    pub fn add(&mut self, run: &PlannedRun) {
        if run.repetition.is_some() { self.repetitions += 1 } else { self.warmups += 1 }
    }

    /// Counts `run` as done.
    pub fn take(&mut self, run: &PlannedRun) {
        if run.repetition.is_some() { self.repetitions -= 1 } else { self.warmups -= 1 }
    }

    /// True when no run is left.
    pub fn is_empty(&self) -> bool {
        self.warmups + self.repetitions == 0
    }
}
