//! Runs a plan, one configuration's runs through these stages, each a file:
//!
//! - [`folder`]: the run folder and its row log (continued, replaced, or an earlier run moved aside);
//! - [`schedule`]: the runs still to do (a resumed sweep skips those recorded) and when a configuration has
//!   repetitions enough ([`stopping`]);
//! - planned → [`validate`]d (or rejected) before its first timed run: one counted pass over its [`scenes`] scene and
//!   [`rays`] ray set, its answers judged against the reference's;
//! - validated → sampled: a timed run in this process ([`trial`]) or in a [`worker`] process, by its [`runners`], its
//!   passes one [`sample`] taken in turn with its point's other series;
//! - sampled → [`record`]ed: one row appended and flushed per timed repetition (a rejected configuration: its one
//!   row, never timed).
//!
//! The report is rebuilt from the rows afterwards.

pub mod folder;
pub mod provenance;
mod rays;
mod record;
mod reference;
mod runners;
mod sample;
pub mod scenes;
mod schedule;
mod stopping;
pub mod trial;
pub mod validate;
pub mod worker;

use std::path::Path;

use schema::Row;

use crate::config::Experiment;
use crate::error::Error;
use crate::output::Progress;
use crate::plan::{Plan, PlannedRun};
pub use folder::{CONFIG_COPY, Existing, PREVIOUS, RUNS_CSV, default_dir, move_aside};
use provenance::Provenance;
use rays::RayBank;
use record::{Recording, Started};
use runners::Runners;
use schedule::Schedule;
use validate::Validation;
pub use worker::worker_request;

/// Runs every planned run not yet recorded in `dir`, appending rows as they finish, round by round: each round's
/// runs (with `sample_ms` and interleaved order, the series of one point together) are validated on their
/// configuration's first turn, then sampled, then recorded. A rejected configuration is recorded once and never
/// timed; with `repetitions = "auto"` a configuration's remaining repetitions are skipped once its median is known
/// well enough ([`stopping`]).
pub fn sweep(exp: &Experiment, plan: &Plan, dir: &Path, existing: Existing) -> Result<(), Error> {
    let provenance = Provenance::collect();
    let recording = Recording { exp, provenance: &provenance, shard: plan.shard };
    let (mut log, recorded) = folder::open_log(exp, dir, existing)?;
    folder::refuse_mixed_pages(dir, &recorded, &provenance.huge_pages)?;
    let mut append = |row: &Row| {
        log.append(row).map_err(|e| Error::Run(format!("{}: cannot append a row: {e}", dir.join(RUNS_CSV).display())))
    };
    let mut schedule = Schedule::new(exp, plan);
    schedule.resume(&recorded);
    let todo: Vec<&PlannedRun> = plan.runs.iter().filter(|r| schedule.to_do(r)).collect();
    if !recorded.is_empty() {
        note!(
            "resuming {}: {} rows already recorded, at most {} runs to go",
            dir.display(),
            recorded.len(),
            todo.len()
        );
    }
    for run in &todo {
        schedule.states[run.config].pending.add(run);
    }
    let cores = crate::plan::available_threads();
    let model = plan.configurations.iter().map(|c| crate::plan::estimate_seconds(&c.settings, cores)).collect();
    let mut progress = Progress::new(model);
    progress.update(|config| schedule.expected(config));
    let mut bank = RayBank::default();
    let mut runners = Runners::new(plan.configurations.len());
    for mut round in schedule.rounds(plan, todo) {
        round.retain(|run| schedule.wants(run));
        // Planned → validated, on a configuration's first turn; or rejected, recorded once and never timed.
        let mut ready = Vec::new();
        for run in round {
            let (c, state) = (&plan.configurations[run.config], &mut schedule.states[run.config]);
            if state.validation.is_none() {
                let started = std::time::Instant::now();
                let v = validate::validate(plan, c, &mut bank)?;
                progress.validated(run.config, started.elapsed().as_secs_f64());
                if let Validation::Rejected(findings) = &v {
                    let recorded = record::rejected(&recording, c, findings, Started::now());
                    append(recorded.row.as_ref().expect("a rejected configuration's row"))?;
                    state.reject();
                    runners.end(run.config);
                    progress.untimed(&recorded.what);
                    progress.update(|config| schedule.expected(config));
                    continue;
                }
                state.validation = Some(v);
            }
            ready.push(run);
        }
        if ready.is_empty() {
            continue;
        }
        // Validated → sampled.
        let started_run = Started::now();
        let started = std::time::Instant::now();
        let configs: Vec<usize> = ready.iter().map(|r| r.config).collect();
        let timings = runners.sample(&configs, plan, exp, &mut bank)?;
        let seconds = started.elapsed().as_secs_f64() / ready.len() as f64;
        // Sampled → recorded.
        for (run, timing) in ready.iter().zip(timings) {
            let (width, done) = schedule.took(run, &timing);
            let (c, state) = (&plan.configurations[run.config], &schedule.states[run.config]);
            let validation = state.validation.as_ref().expect("validated before its first timed run");
            let recorded = record::timed(&recording, c, validation, run, &timing, width, started_run.clone())?;
            if let Some(row) = &recorded.row {
                append(row)?;
            }
            if done {
                // After a configuration's last run its worker process, pool and device go.
                runners.end(run.config);
            }
            progress.finished(run.config, seconds, &recorded.what);
            progress.update(|config| schedule.expected(config));
        }
    }
    progress.finish();
    Ok(())
}
