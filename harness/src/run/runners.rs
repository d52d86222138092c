//! Runners: where configurations are timed, in this process or in a worker process of their own, one timed run of
//! each of a round's configurations at a time, their passes one [`sample`] taken in turn. A configuration keeps its
//! runner (its pool and backend, or its worker) from its first timed run to its last, or per block of runs with
//! `processes` above 1.

use std::sync::Arc;

use tracer::rays::RaySet;

use super::rays::RayFiles;
use super::sample::{TakesPasses, sample};
use super::trial::{Context, Local, Timing, Trial};
use super::worker::{Step, Worker, WorkerRequest, worker_request};
use crate::backend::{self, Setup};
use crate::config::Experiment;
use crate::error::Error;
use crate::plan::{Configuration, Plan};

/// Where every configuration of a sweep is timed: one slot each, and the ray sets handed to its workers.
pub(super) struct Runners {
    slots: Vec<Slot>,
    /// Calls of [`Runners::sample`] so far.
    clock: u64,
    /// The ray sets handed to workers.
    ray_files: RayFiles,
}

/// One configuration's runner and where it is in its blocks of runs.
#[derive(Default)]
struct Slot {
    /// Where it is timed now: in this process or its worker, kept from its first timed run to its last; with
    /// `processes` above 1, the worker of its current block of runs (see [`Slot::runner`]).
    runner: Option<Runner>,
    /// Which block of runs `runner` serves (with `processes` above 1).
    block: usize,
    /// Its timed runs so far in this sweep (which block is next).
    turns: usize,
    /// When it was last timed (the count of [`Runners::sample`] calls), to end the workers of the configuration idle
    /// longest when memory runs low.
    last_timed: u64,
}

/// Where a configuration is timed: in this process with its setup, or (a backend with threads of its own, as
/// Embree) in a worker process of its own, kept while its runs interleave with others'.
enum Runner {
    Here(Setup),
    Worker(Worker),
}

impl Runners {
    /// No runner started yet for any of `configurations` configurations.
    pub fn new(configurations: usize) -> Self {
        Runners {
            slots: (0..configurations).map(|_| Slot::default()).collect(),
            clock: 0,
            ray_files: RayFiles::default(),
        }
    }

    /// One timed run of each of `runs`' configurations (each over the ray set its validation gave it), starting their
    /// runners on their first: each is built, one after the other, and then they are sampled together, a pass of each
    /// in turn ([`sample`]; one configuration alone is one run as it always was). Several are the series of one point
    /// in an interleaved round with `sample_ms`.
    pub fn sample(
        &mut self,
        runs: &[(usize, Option<Arc<RaySet>>)],
        plan: &Plan,
        exp: &Experiment,
    ) -> Result<Vec<Timing>, Error> {
        let (configs, rays): (Vec<usize>, Vec<Option<Arc<RaySet>>>) = runs.iter().cloned().unzip();
        self.clock += 1;
        for &i in &configs {
            self.slots[i].last_timed = self.clock;
        }
        self.make_room(&configs, exp.processes);
        let mut picked: Vec<(usize, &mut Slot)> =
            self.slots.iter_mut().enumerate().filter(|(i, _)| configs.contains(i)).collect();
        picked.sort_by_key(|(i, _)| configs.iter().position(|c| c == i));
        // Start the runners. A fresh worker's untimed warm-up (a build and a pass) begins at once and is awaited
        // only once every runner has started, so a round's new workers start side by side; their timed builds
        // then run one after the other, with no warm-up beside them.
        let processes = exp.processes;
        let mut requests = Vec::with_capacity(picked.len());
        for ((i, state), rays) in picked.iter_mut().zip(&rays) {
            let c = &plan.configurations[*i];
            let (runner, fresh) = state.runner(c, processes, exp.warmups, exp.repetitions.max())?;
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
        for (((i, state), rays), request) in picked.iter_mut().zip(&rays).zip(requests) {
            let c = &plan.configurations[*i];
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
        let (passes, steal_s) = sample(&mut takers, plan.sample_s)?;
        let n = turns.len() as u32;
        turns.into_iter().zip(passes).map(|(turn, passes)| turn.finish(passes, steal_s, n)).collect()
    }

    /// Ends configuration `config`'s runner: its worker process, pool and device go.
    pub fn end(&mut self, config: usize) {
        self.slots[config].runner = None;
    }

    /// With `processes` above 1 every configuration keeps a worker from its first run to its last, and an
    /// interleaved sweep's configurations all live at once: while less than a quarter of the machine's memory is
    /// available, the worker of the configuration idle longest (not one of `configs`) ends; another starts, and is
    /// warmed, on its next turn.
    fn make_room(&mut self, configs: &[usize], processes: u32) {
        if processes <= 1 {
            return;
        }
        while memory_low() {
            let idle = (0..self.slots.len())
                .filter(|i| !configs.contains(i) && self.slots[*i].runner.is_some())
                .min_by_key(|&i| self.slots[i].last_timed);
            let Some(i) = idle else { return };
            self.slots[i].runner = None;
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

impl Slot {
    /// Where its next run is timed, started on its first turn: in this process, or in a worker of its own (a
    /// backend with threads of its own, as Embree; or every backend with `processes` above 1). With `processes` N
    /// above 1 its `repetitions` (at most) fall into N blocks of consecutive runs (its `warmups` run in the first),
    /// each timed in a worker started for it and ended when the next block begins: N processes, one alive at a
    /// time. Returns it, and whether it was started for this run.
    fn runner(
        &mut self,
        c: &Configuration,
        processes: u32,
        warmups: u32,
        repetitions: u32,
    ) -> Result<(&mut Runner, bool), Error> {
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
            self.runner = Some(if processes > 1 || backend::of(c.settings.accel).own_threads(&c.settings) {
                let exe = std::env::current_exe()
                    .map_err(|e| Error::Run(format!("cannot find the harness executable: {e}")))?;
                Runner::Worker(Worker::start(&exe, None)?)
            } else {
                Runner::Here(Setup::start(&c.settings)?)
            });
        }
        Ok((self.runner.as_mut().expect("started above"), fresh))
    }
}
