//! The sweep's state: one [`ConfigurationState`] per configuration (its validation, where it is timed, the runs it
//! still has) and the adaptive [`Sampler`] they share.

use schema::Row;

use super::adaptive::{self, Sampler};
use super::measure::{self, Timing};
use super::validate::RayBank;
use super::worker::Worker;
use super::{Checked, worker_request, workload_rays};
use crate::backend::{self, Setup};
use crate::config::Experiment;
use crate::error::Error;
use crate::plan::{Configuration, Plan, PlannedRun};

/// Every configuration's state, and the sampler that decides when one has repetitions enough.
pub(super) struct Sweep<'a> {
    exp: &'a Experiment,
    pub states: Vec<ConfigurationState<'a>>,
    pub sampler: Sampler,
}

/// One configuration through the sweep.
pub(super) struct ConfigurationState<'a> {
    pub configuration: &'a Configuration,
    /// Its validation and counters, from before its first timed run.
    pub checked: Option<Checked>,
    /// True once it failed validation (recorded once, never timed).
    pub failed: bool,
    /// Where it is timed, from its first timed run to its last.
    runner: Option<Runner>,
    /// The runs it still has in this sweep.
    pub pending: Pending,
}

/// Where a configuration is timed: in this process with its setup, or (a backend with threads of its own, as
/// Embree) in a worker process of its own, kept while its runs interleave with others'.
enum Runner {
    Here(Setup),
    Worker(Worker),
}

impl<'a> Sweep<'a> {
    pub fn new(exp: &'a Experiment, plan: &'a Plan) -> Self {
        let states = plan
            .configurations
            .iter()
            .map(|configuration| ConfigurationState {
                configuration,
                checked: None,
                failed: false,
                runner: None,
                pending: Pending::default(),
            })
            .collect();
        Sweep { exp, states, sampler: Sampler::new(exp.repetitions) }
    }

    /// The metric whose interval decides `c`'s repetitions.
    pub fn metric(&self, c: &Configuration) -> &'a str {
        report::spec::speedup_metric(self.exp.speedup_metric.as_deref(), schema::Named::name(c.settings.workload))
    }

    /// The `repetition_rule` of `c`'s rows.
    pub fn rule(&self, c: &Configuration) -> String {
        self.exp.repetitions.rule(self.metric(c))
    }

    /// Takes in rows already recorded (a resumed run): a failed configuration stays failed, and every recorded
    /// repetition counts as one done (and, with "auto", as a sample).
    pub fn resume(&mut self, recorded: &[Row]) {
        let index: std::collections::HashMap<&str, usize> =
            self.states.iter().enumerate().map(|(i, s)| (s.configuration.id.as_str(), i)).collect();
        let mut resumed: Vec<(usize, &Row)> =
            recorded.iter().filter_map(|r| index.get(r.config_id.as_str()).map(|&i| (i, r))).collect();
        resumed.sort_by_key(|(i, r)| (*i, r.repetition));
        for (i, r) in resumed {
            let (c, metric) = (self.states[i].configuration, self.metric(self.states[i].configuration));
            let state = &mut self.states[i];
            if r.validation == schema::ValidationStatus::Failed {
                state.failed = true;
            } else if state.pending.done.insert(r.repetition) {
                self.sampler.record(i, &c.id, adaptive::recorded_value(r, metric));
            }
        }
    }

    /// True for a planned run still to do: its configuration neither failed nor has repetitions enough, and the
    /// run is a repetition not yet recorded or a warm-up of a configuration without any.
    pub fn to_do(&self, run: &PlannedRun) -> bool {
        let state = &self.states[run.config];
        !state.failed
            && !self.sampler.is_done(run.config)
            && match run.repetition {
                Some(rep) => !state.pending.done.contains(&rep),
                None => self.sampler.count(run.config) == 0,
            }
    }

    /// Runs configuration `config` is still expected to take, for the time estimate.
    pub fn expected(&self, config: usize) -> f64 {
        let p = &self.states[config].pending;
        p.warmups as f64 + self.sampler.expected_left(config).min(p.repetitions as f64)
    }
}

impl ConfigurationState<'_> {
    /// Times one run, starting its runner on its first.
    pub fn time(&mut self, plan: &Plan, bank: &mut RayBank) -> Result<Timing, Error> {
        let c = self.configuration;
        if self.runner.is_none() {
            self.runner = Some(if backend::of(c.settings.accel).own_threads() {
                let exe = std::env::current_exe()
                    .map_err(|e| Error::Run(format!("cannot find the harness executable: {e}")))?;
                Runner::Worker(Worker::start(&exe, None)?)
            } else {
                Runner::Here(Setup::start(&c.settings)?)
            });
        }
        match self.runner.as_mut().expect("started above") {
            Runner::Worker(worker) => worker.time(&worker_request(plan, c)),
            Runner::Here(setup) => {
                let rays = workload_rays(plan, &c.settings, bank);
                measure::timed(&c.settings, plan.scene_file(), rays.as_deref(), setup, plan.sample_s)
            }
        }
    }

    /// Marks it failed and lets its runs go.
    pub fn fail(&mut self) {
        self.failed = true;
        self.finish();
    }

    /// Ends it: its worker process, pool and device go, and it expects no more runs.
    pub fn finish(&mut self) {
        self.runner = None;
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
