//! Runs a plan, one configuration's runs through these stages, each a file:
//!
//! - [`folder`]: the run folder and its row log (continued, replaced, or an earlier run moved aside);
//! - [`schedule`]: the runs still to do, round by round (a resumed sweep skips those recorded), and when a
//!   configuration has repetitions enough ([`stopping`], decided by its metric, found once);
//! - planned → [`validate`]d (or rejected) before its first timed run: its [`scenes`] scene made once, its ray set
//!   and the reference's answers from the [`rays`] bank, one counted pass, its answers judged against the
//!   [`reference`]'s; a validated configuration carries the ray set its timed runs trace;
//! - validated → sampled: a timed run in this process ([`trial`]) or in a [`worker`] process, by its [`runners`], its
//!   passes one [`sample`] taken in turn with its point's other series, its timing taken in by the schedule;
//! - sampled → [`record`]ed: one row appended and flushed per timed repetition (a rejected configuration: its one
//!   row, never timed), then the round on the progress line.
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

pub use reference::{BRUTE_FORCE_MAX, checked_count};

use std::path::Path;
use std::time::Instant;

use schema::Row;

use crate::config::Experiment;
use crate::error::Error;
use crate::output::Progress;
use crate::plan::Plan;
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
    let (mut log, recorded) = folder::open_log(exp, dir, existing)?;
    folder::refuse_mixed_pages(dir, &recorded, &provenance.huge_pages)?;
    let mut append = |row: &Row| {
        log.append(row).map_err(|e| Error::Run(format!("{}: cannot append a row: {e}", dir.join(RUNS_CSV).display())))
    };
    let mut schedule = Schedule::new(exp, plan);
    let rounds = schedule.resume(&recorded);
    if !recorded.is_empty() {
        note!(
            "resuming {}: {} rows already recorded, at most {} runs to go",
            dir.display(),
            recorded.len(),
            rounds.iter().map(Vec::len).sum::<usize>()
        );
    }
    let cores = crate::plan::available_threads();
    let model = plan.configurations.iter().map(|c| crate::plan::round_seconds(exp, &c.settings, cores)).collect();
    let mut progress = Progress::new(model);
    progress.update(&schedule.expected());
    let recording = Recording { exp, provenance: &provenance, shard: plan.shard };
    let mut bank = RayBank::default();
    let mut runners = Runners::new(plan.configurations.len());
    for mut round in rounds {
        round.retain(|run| schedule.wants(run));
        // Planned → validated on a configuration's first turn, or rejected (recorded once, never timed).
        let mut rejected = Vec::new();
        let mut validated = Vec::new();
        for run in round {
            let state = &mut schedule.states[run.config];
            if state.validation.is_none() {
                let started = Instant::now();
                let validation = validate::validate(plan, state.configuration, &mut bank)?;
                progress.validated(run.config, started.elapsed().as_secs_f64());
                state.validation = Some(validation);
            }
            if let Some(Validation::Validated { rays, .. }) = &state.validation {
                validated.push((run, rays.clone()));
            } else {
                state.reject();
                rejected.push((run, Started::now()));
            }
        }
        // Validated → sampled: one timed run of each, their passes taken in turn, each timing taken in by the
        // schedule (the interval its configuration reached, and whether it is done).
        let started_run = Started::now();
        let started = Instant::now();
        let configs: Vec<_> = validated.iter().map(|(run, rays)| (run.config, rays.clone())).collect();
        let timings = if configs.is_empty() { Vec::new() } else { runners.sample(&configs, plan, exp)? };
        let seconds = started.elapsed().as_secs_f64() / configs.len().max(1) as f64;
        let sampled: Vec<_> = validated
            .iter()
            .zip(timings)
            .map(|((run, _), timing)| (*run, schedule.took(run, &timing), timing))
            .collect();
        // Rejected or sampled → recorded: a rejected configuration's one row, then each timed repetition's, each
        // appended as it is made.
        let mut untimed = Vec::new();
        for (run, started) in rejected {
            let recorded = record::rejected(&recording, &schedule.states[run.config], started);
            append(recorded.row.as_ref().expect("a rejected configuration's row"))?;
            untimed.push(recorded.what);
        }
        let mut finished = Vec::new();
        for (run, (width, done), timing) in sampled {
            let state = &schedule.states[run.config];
            let recorded = record::timed(&recording, state, run, &timing, width, started_run.clone())?;
            if let Some(row) = &recorded.row {
                append(row)?;
            }
            if done {
                // After a configuration's last run its worker process, pool and device go.
                runners.end(run.config);
            }
            finished.push((run.config, recorded.what));
        }
        // The round on the progress line.
        for what in &untimed {
            progress.untimed(what);
        }
        for (config, what) in &finished {
            progress.finished(*config, seconds, what);
        }
        progress.update(&schedule.expected());
    }
    progress.finish();
    Ok(())
}
