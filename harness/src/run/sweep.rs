//! The sweep's state: one [`ConfigurationState`] per configuration (its validation, where it is timed, the runs it
//! still has) and the adaptive [`Sampler`] they share.

use std::sync::Arc;

use schema::Row;
use tracer::rays::RaySet;

use super::adaptive::{self, Sampler};
use super::measure::{self, Context, Local, TakesPasses, Timing, Trial};
use super::validate::RayBank;
use super::worker::{Step, Worker, WorkerRequest};
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
    /// Calls of [`Sweep::time`] so far.
    clock: u64,
    /// The ray sets handed to workers.
    ray_files: RayFiles,
}

/// The ray sets the sweep's workers read instead of making them again (each worker started for a block of runs would
/// otherwise trace the scene's primary rays anew): written once each into a folder of the system's temporary
/// directory, removed when the sweep ends.
#[derive(Default)]
struct RayFiles {
    dir: Option<std::path::PathBuf>,
    written: Vec<(Arc<RaySet>, std::path::PathBuf)>,
}

impl RayFiles {
    /// The file that holds `rays`, written on first use.
    fn path_of(&mut self, rays: &Arc<RaySet>) -> Result<std::path::PathBuf, Error> {
        if let Some((_, path)) = self.written.iter().find(|(set, _)| Arc::ptr_eq(set, rays)) {
            return Ok(path.clone());
        }
        let io = |p: &std::path::Path, e: std::io::Error| Error::Run(format!("{}: cannot write: {e}", p.display()));
        let dir = match &self.dir {
            Some(dir) => dir.clone(),
            None => {
                // One folder per sweep, even where one process runs several at once.
                static SWEEPS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
                let sweep = SWEEPS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let dir = std::env::temp_dir().join(format!("bvhlab-rays-{}-{sweep}", std::process::id()));
                std::fs::create_dir_all(&dir).map_err(|e| io(&dir, e))?;
                self.dir.insert(dir).clone()
            }
        };
        let path = dir.join(format!("{}.bin", self.written.len()));
        std::fs::write(&path, rays.to_bytes()).map_err(|e| io(&path, e))?;
        self.written.push((Arc::clone(rays), path.clone()));
        Ok(path)
    }
}

impl Drop for RayFiles {
    fn drop(&mut self) {
        if let Some(dir) = &self.dir {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// One configuration through the sweep.
pub(super) struct ConfigurationState<'a> {
    pub configuration: &'a Configuration,
    /// Its validation and counters, from before its first timed run.
    pub checked: Option<Checked>,
    /// True once it failed validation (recorded once, never timed).
    pub failed: bool,
    /// Where it is timed now: in this process or its worker, kept from its first timed run to its last; with
    /// `processes` above 1, the worker of its current block of runs (see [`ConfigurationState::runner`]).
    runner: Option<Runner>,
    /// Which block of runs `runner` serves (with `processes` above 1).
    block: usize,
    /// Its timed runs so far in this sweep (which block is next).
    turns: usize,
    /// When it was last timed (the sweep's count of [`Sweep::time`] calls), to end the workers of the configuration
    /// idle longest when memory runs low.
    last_timed: u64,
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
                block: 0,
                turns: 0,
                last_timed: 0,
                pending: Pending::default(),
            })
            .collect();
        let reference = if exp.order == crate::config::RunOrder::Interleaved {
            let points: Vec<usize> = plan.configurations.iter().map(|c| c.point).collect();
            let series: Vec<&str> = plan.configurations.iter().map(|c| c.series.as_str()).collect();
            Sampler::paired(&points, &series, exp.reference.as_deref())
        } else {
            vec![None; plan.configurations.len()]
        };
        Sweep {
            exp,
            states,
            sampler: Sampler::new(exp.repetitions, reference),
            clock: 0,
            ray_files: RayFiles::default(),
        }
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
            let metric = self.metric(self.states[i].configuration);
            let state = &mut self.states[i];
            if r.validation == schema::ValidationStatus::Failed {
                state.failed = true;
            } else if state.pending.done.insert(r.repetition) {
                self.sampler.record(i, adaptive::recorded_value(r, metric));
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

    /// Times one run of each of `configs`, starting their runners on their first: each is built, one after the
    /// other, and then they are sampled together, a pass of each in turn ([`measure::sample`]; one configuration
    /// alone is one run as it always was). Several are the series of one point in an interleaved round with
    /// `sample_ms`.
    pub fn time(&mut self, configs: &[usize], plan: &Plan, bank: &mut RayBank) -> Result<Vec<Timing>, Error> {
        self.clock += 1;
        for &i in configs {
            self.states[i].last_timed = self.clock;
        }
        self.make_room(configs);
        let rays: Vec<_> =
            configs.iter().map(|&i| workload_rays(plan, &self.states[i].configuration.settings, bank)).collect();
        let mut picked: Vec<(usize, &mut ConfigurationState<'a>)> =
            self.states.iter_mut().enumerate().filter(|(i, _)| configs.contains(i)).collect();
        picked.sort_by_key(|(i, _)| configs.iter().position(|c| c == i));
        // Start the runners. A fresh worker's untimed warm-up (a build and a pass) begins at once and is awaited
        // only once every runner has started, so a round's new workers start side by side; their timed builds
        // then run one after the other, with no warm-up beside them.
        let processes = self.exp.processes;
        let mut requests = Vec::with_capacity(picked.len());
        for ((_, state), rays) in picked.iter_mut().zip(&rays) {
            let c = state.configuration;
            let (runner, fresh) = state.runner(processes, self.exp.warmups, self.exp.repetitions.max())?;
            requests.push(match runner {
                Runner::Worker(worker) => {
                    let rays_file = match rays {
                        Some(rays) if processes > 1 => Some(self.ray_files.path_of(rays)?),
                        _ => None,
                    };
                    let request = WorkerRequest { rays_file, ..worker_request(plan, c) };
                    let warming = fresh && processes > 1;
                    if warming {
                        // Its own warm-up, one untimed pass: every process's runs are warm.
                        worker.begin(&WorkerRequest { sample_s: 0.0, ..request.clone() });
                    }
                    Some((request, warming))
                }
                Runner::Here(_) => None,
            });
        }
        for ((_, state), request) in picked.iter_mut().zip(&requests) {
            if let (Some(Runner::Worker(worker)), Some((_, true))) = (state.runner.as_mut(), request) {
                worker.end()?; // the warm-up's timing is not recorded
            }
        }
        let mut turns = Vec::new();
        for (((_, state), rays), request) in picked.iter_mut().zip(&rays).zip(requests) {
            let c = state.configuration;
            turns.push(match (state.runner.as_mut().expect("started above"), request) {
                (Runner::Worker(worker), Some((request, _))) => {
                    worker.step::<()>(&request, Step::Prepare)?;
                    Turn::Worker { worker, request }
                }
                (Runner::Here(setup), _) => {
                    let cx = Context { settings: &c.settings, file: plan.scene_file(), rays: rays.as_deref(), setup };
                    Turn::Here(Local { trial: Trial::prepare(&cx)?, cx })
                }
                (Runner::Worker(_), None) => unreachable!("a worker's request is made when it is picked"),
            });
        }
        let mut takers: Vec<&mut dyn TakesPasses> = turns.iter_mut().map(|t| t as &mut dyn TakesPasses).collect();
        let (passes, steal_s) = measure::sample(&mut takers, plan.sample_s)?;
        let n = turns.len() as u32;
        turns.into_iter().zip(passes).map(|(turn, passes)| turn.finish(passes, steal_s, n)).collect()
    }
}

impl Sweep<'_> {
    /// With `processes` above 1 every configuration keeps a worker from its first run to its last, and an
    /// interleaved sweep's configurations all live at once: while less than a quarter of the machine's memory is
    /// available, the worker of the configuration idle longest (not one of `configs`) ends; another starts, and is
    /// warmed, on its next turn.
    fn make_room(&mut self, configs: &[usize]) {
        if self.exp.processes <= 1 {
            return;
        }
        while memory_low() {
            let idle = (0..self.states.len())
                .filter(|i| !configs.contains(i) && self.states[*i].runner.is_some())
                .min_by_key(|&i| self.states[i].last_timed);
            let Some(i) = idle else { return };
            self.states[i].runner = None;
        }
    }
}

/// True while the kernel counts less than a quarter of the machine's memory available (`/proc/meminfo`; false where
/// it does not say).
fn memory_low() -> bool {
    let info = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    let kib = |key: &str| {
        info.lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|rest| rest.split_whitespace().next()?.parse::<u64>().ok())
    };
    matches!((kib("MemAvailable:"), kib("MemTotal:")), (Some(available), Some(total)) if available < total / 4)
}

/// A configuration's run taken pass by pass: a trial in this process, or one in its worker.
enum Turn<'a> {
    Here(Local<'a>),
    Worker { worker: &'a mut Worker, request: WorkerRequest },
}

impl TakesPasses for Turn<'_> {
    fn pass(&mut self) -> Result<f64, Error> {
        match self {
            Turn::Here(local) => local.pass(),
            Turn::Worker { worker, request } => worker.step(request, Step::Pass),
        }
    }
}

impl Turn<'_> {
    /// The run's timing from the passes the sample kept.
    fn finish(self, passes: Vec<f64>, steal_s: Option<f64>, sample_configs: u32) -> Result<Timing, Error> {
        match self {
            Turn::Here(local) => Ok(local.finish(&passes, steal_s, sample_configs)),
            Turn::Worker { worker, request } => worker.step(&request, Step::Finish { passes, steal_s, sample_configs }),
        }
    }
}

impl ConfigurationState<'_> {
    /// Where its next run is timed, started on its first turn: in this process, or in a worker of its own (a
    /// backend with threads of its own, as Embree; or every backend with `processes` above 1). With `processes` N
    /// above 1 its `repetitions` (at most) fall into N blocks of consecutive runs (its `warmups` run in the first),
    /// each timed in a worker started for it and ended when the next block begins: N processes, one alive at a
    /// time. Returns it, and whether it was started for this run.
    fn runner(&mut self, processes: u32, warmups: u32, repetitions: u32) -> Result<(&mut Runner, bool), Error> {
        let processes = processes.max(1) as usize;
        let per_block = (repetitions as usize).div_ceil(processes).max(1);
        let block = self.turns.saturating_sub(warmups as usize) / per_block;
        self.turns += 1;
        if processes > 1 && block != self.block {
            self.runner = None; // the last block's worker ends
            self.block = block;
        }
        let fresh = self.runner.is_none();
        if fresh {
            self.runner = Some(if processes > 1 || backend::of(self.configuration.settings.accel).own_threads() {
                let exe = std::env::current_exe()
                    .map_err(|e| Error::Run(format!("cannot find the harness executable: {e}")))?;
                Runner::Worker(Worker::start(&exe, None)?)
            } else {
                Runner::Here(Setup::start(&self.configuration.settings)?)
            });
        }
        Ok((self.runner.as_mut().expect("started above"), fresh))
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
