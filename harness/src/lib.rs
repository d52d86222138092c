//! `harness`: the bvhlab command line as a library (the `harness` binary calls [`main`]; examples reach the
//! peers' bindings and the run path). The data's trip: config → plan → run → rows → report.

/// Progress and the `say!`/`note!` macros every other module prints with (declared first for them).
#[macro_use]
mod output;
mod ab;
mod backend;
mod backfill;
mod baseline;
mod check;
mod cli;
mod config;
mod count;
mod error;
mod list;
mod merge;
pub mod meshes;
/// Transparent huge pages for every backend's allocations (the harness starts itself again with them).
mod pages;
pub mod peers;
mod plan;
mod render;
mod reproduce;
mod revision;
mod rows;
pub mod run;
mod slurm;
/// The hash of the sources a binary is built from (shared with `build.rs`).
mod source_tree;

use std::path::Path;
use std::process::ExitCode;

use clap::Parser;
use report::spec::Verdict;

use cli::{
    BaselineCommand, CheckArgs, Command, HistoryCommand, ReportArgs, RunArgs, SiteArgs, SlurmCommand, ValidateArgs,
};
use config::{Experiment, Repetitions};
use error::Error;
use plan::Plan;

/// The command line: parses the arguments, runs the command, and returns its exit code.
pub fn main() -> ExitCode {
    let cli = cli::Cli::parse();
    // A worker runs on the pages its parent chose (it inherits the environment; its arguments do not say).
    if !matches!(cli.command, Command::Worker) {
        pages::ensure(cli.huge_pages);
    }
    let result = match cli.command {
        Command::Run(args) => run_command(&args),
        Command::Report(args) => report_command(&args),
        Command::Validate(args) => validate_command(&args),
        Command::Render(args) => render::run(&args),
        Command::Worker => worker_command(),
        Command::Check(args) => check_command(&args),
        Command::Instructions(args) => count::run(&count::CountRequest {
            config: &args.config,
            quick: args.quick,
            out: args.out.clone(),
            cache_sim: args.cache_sim,
            image: args.image,
            jobs: args.jobs.map_or_else(plan::available_threads, |j| j as usize),
        }),
        Command::History(HistoryCommand::Append { run_dir, dir }) => history_append(&run_dir, &dir),
        Command::History(HistoryCommand::Backfill(args)) => backfill::run(&backfill::BackfillRequest {
            range: &args.range,
            every: args.every as usize,
            config: &args.config,
            quick: args.quick,
            dir: &args.dir,
            timings: args.timings,
            jobs: args.jobs.map_or_else(plan::available_threads, |j| j as usize),
        }),
        Command::History(HistoryCommand::Plot { dir }) => report::history::plot(&dir)
            .map(|files| files.iter().for_each(|f| say!("{}", f.display())))
            .map_err(|e| Error::Input(e.to_string())),
        Command::Site(args) => site_command(&args),
        Command::Ab(args) => ab::run(&ab::AbRequest {
            base: &args.base,
            config: &args.config,
            quick: args.quick,
            min_effect: args.min_effect,
            allow_different_answers: args.allow_different_answers,
            no_confirm: args.no_confirm,
        }),
        Command::Baseline(BaselineCommand::Save { run_dir, name, force }) => baseline::save(&run_dir, &name, force)
            .map(|dest| {
                say!("baseline saved: {}", dest.display());
            }),
        Command::Slurm(SlurmCommand::Submit(args)) => slurm::submit(&args),
        Command::Slurm(SlurmCommand::Resubmit { run_dir, dry_run }) => slurm::resubmit(&run_dir, dry_run),
        Command::Merge(args) => merge::run(&args.run_dir, args.allow_mixed_machines),
        Command::Reproduce(args) => reproduce::run(&args),
        Command::RowsDiff(args) => rows::diff::run(&args.a, &args.b, args.ignore_timing),
        Command::Fetch(args) => match &args.name {
            Some(name) => meshes::fetch(name),
            None => {
                meshes::list();
                Ok(())
            }
        },
        Command::List => {
            list::run();
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            note!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

fn load(path: &Path, quick: bool) -> Result<Experiment, Error> {
    let exp = Experiment::load(path)?;
    Ok(if quick { exp.quick() } else { exp })
}

/// Writes the report of `dir` and prints its claims; returns whether any claim failed.
fn write_report(dir: &Path, exp: &Experiment, notes: Vec<String>) -> Result<bool, Error> {
    write_report_with(dir, exp, notes, vec![])
}

/// [`write_report`] with warnings for the top of REPORT.md.
fn write_report_with(dir: &Path, exp: &Experiment, notes: Vec<String>, warnings: Vec<String>) -> Result<bool, Error> {
    let spec = report::spec::ReportSpec { warnings, ..exp.report_spec(notes) };
    let outcome = report::write(dir, &spec).map_err(|e| Error::Run(e.to_string()))?;
    for (c, claim) in outcome.claims.iter().zip(&spec.claims) {
        let verdict = match c.verdict {
            Verdict::Holds => "holds",
            Verdict::Fails => "FAILS",
            Verdict::Inconclusive => "inconclusive",
        };
        let interval = if c.lo.is_nan() {
            format!("(no interval: fewer than {} runs)", report::stats::MIN_SAMPLES_FOR_INTERVAL)
        } else {
            format!("[{:.3}, {:.3}]", c.lo, c.hi)
        };
        // The bound as REPORT.md states it: a factor to reach, or a band around 1.
        let bound = match claim.kind {
            report::spec::ClaimKind::Within { tolerance, .. } => format!("within 1 ± {tolerance:.3}"),
            report::spec::ClaimKind::Faster { .. } => format!("vs ≥ {:.3}", c.threshold),
        };
        say!("claim {verdict:<12} ratio {:.3} {interval} {bound}: {}", c.ratio, c.text);
    }
    say!("report: {}", dir.join("REPORT.md").display());
    Ok(outcome.claims.iter().any(|c| c.verdict == Verdict::Fails))
}

fn run_command(args: &RunArgs) -> Result<(), Error> {
    let shard = args.shard.map(|a| slurm::env::resolve(a, |k| std::env::var(k).ok())).transpose()?;
    let exp = load(&args.config, args.quick)?;
    if let Some(want) = &args.config_hash {
        let have = slurm::config_hash(&exp.text);
        if *want != have {
            return Err(Error::Input(format!(
                "{}: config hash {have}, but --config-hash {want}: the config changed since the job was written \
                 (allowed: the config as submitted)",
                exp.path.display()
            )));
        }
    }
    let mut plan = Plan::new(&exp, plan::available_threads())?;
    let mut dir = args.out.clone().unwrap_or_else(|| run::default_dir(&exp, args.quick));
    if let Some((i, n)) = shard {
        plan.keep_shard(i, n);
        dir = slurm::shard_dir(&dir, i, n);
    }
    let existing = match (args.resume, args.force) {
        (true, true) => {
            return Err(Error::Input("--resume and --force: choose one (allowed: either, or neither)".into()));
        }
        (true, false) => run::Existing::Resume,
        (false, true) => run::Existing::Replace,
        (false, false) => run::Existing::MoveAside,
    };
    let before: std::collections::BTreeSet<usize> = plan.runs.iter().map(|r| r.config).collect();
    plan.skip_unavailable(&exp.path.display().to_string(), args.require_all)?;
    if let Some((i, n)) = shard {
        let config = std::path::absolute(&args.config).unwrap_or_else(|_| args.config.clone());
        let skipped = before.iter().filter(|c| !plan.runs.iter().any(|r| r.config == **c));
        let skipped = skipped.map(|c| plan.configurations[*c].id.clone()).collect();
        let info = slurm::ShardInfo {
            shard: (i, n),
            config,
            config_hash: slurm::config_hash(&exp.text),
            quick: args.quick,
            skipped,
        };
        std::fs::create_dir_all(&dir).map_err(|e| Error::Input(format!("{}: cannot create: {e}", dir.display())))?;
        slurm::write_json(&dir.join(slurm::SHARD_JSON), &info)?;
    }
    for mesh in plan.mesh_summaries()? {
        note!("mesh {mesh}");
    }
    run::sweep(&exp, &plan, &dir, existing)?;
    if let Some((i, n)) = shard
        && plan.runs.is_empty()
    {
        say!("shard {i} of {n} is empty (the plan has fewer scene cells than shards): nothing to run");
        return Ok(());
    }
    let failed = write_report(&dir, &exp, plan.notes.clone())?;
    if failed && args.check_claims {
        return Err(Error::Run("a claim failed (see the claims above and REPORT.md)".into()));
    }
    Ok(())
}

fn history_append(run_dir: &Path, dir: &Path) -> Result<(), Error> {
    let path = run_dir.join(run::CONFIG_COPY);
    if !run_dir.join(run::RUNS_CSV).is_file() {
        return Err(Error::Input(format!("{}: no {} here (not a run folder)", run_dir.display(), run::RUNS_CSV)));
    }
    let exp = Experiment::load(&path)?;
    let n = report::history::append(run_dir, &exp.report_spec(vec![]), dir, &Default::default())
        .map_err(|e| Error::Input(e.to_string()))?;
    say!("history: {n} speedups of {} appended to {}", run_dir.display(), dir.join("history.csv").display());
    Ok(())
}

fn check_command(args: &CheckArgs) -> Result<(), Error> {
    for (name, value) in [("--min-effect", args.min_effect), ("--min-effect-build", args.min_effect_build)] {
        if !(0.0..1.0).contains(&value) {
            return Err(Error::Input(format!("{name} {value}: out of range (allowed: 0 <= x < 1)")));
        }
    }
    if !(0.0..1.0).contains(&args.instruction_threshold) {
        return Err(Error::Input(format!(
            "--instruction-threshold {}: out of range (allowed: 0 <= x < 1)",
            args.instruction_threshold
        )));
    }
    let options = report::check::CheckOptions {
        metric: args.metric.clone(),
        min_effect: args.min_effect,
        min_effect_build: args.min_effect_build,
        accept_counter_changes: args.accept_counter_changes,
        timings_for_information: args.timings_for_information,
        min_time_s: args.min_time,
        instruction_threshold: args.instruction_threshold,
        max_extra_load: args.max_extra_load,
    };
    check::run(&check::CheckRequest {
        run_dir: &args.run_dir,
        baseline: &args.baseline,
        options,
        json: args.json.clone(),
        confirm: !args.no_confirm,
    })
}

/// Answers JSON worker requests on stdin with JSON timing lines on stdout (see `run::worker`).
fn worker_command() -> Result<(), Error> {
    run::worker::serve(std::io::stdin().lock(), std::io::stdout().lock())
}

fn report_command(args: &ReportArgs) -> Result<(), Error> {
    let path = args.dir.join(run::CONFIG_COPY);
    if !args.dir.join(run::RUNS_CSV).is_file() {
        return Err(Error::Input(format!("{}: no {} here (not a run folder)", args.dir.display(), run::RUNS_CSV)));
    }
    let exp = Experiment::load(&path)?;
    if let Some(recorded) = &args.claims_against
        && !recorded.join(run::RUNS_CSV).is_file()
    {
        return Err(Error::Input(format!(
            "--claims-against {}: no {} here (allowed: a run folder of the same config)",
            recorded.display(),
            run::RUNS_CSV
        )));
    }
    write_report(&args.dir, &exp, vec![])?;
    match &args.claims_against {
        Some(recorded) => claims_against(&args.dir, recorded, &exp),
        None => Ok(()),
    }
}

/// Fails, naming them, when claims that held in the rows of `recorded` fail at every point in those of `dir`
/// (`harness report DIR --claims-against RECORDED`, a run folder checked before anything is written: CI's guard on
/// the main job's answers).
fn claims_against(dir: &Path, recorded: &Path, exp: &Experiment) -> Result<(), Error> {
    let lost = report::lost_claims(recorded, dir, &exp.report_spec(vec![])).map_err(|e| Error::Input(e.to_string()))?;
    for c in &lost {
        note!(
            "claim lost: \"{}\" held in {} and fails here at all {} points (least favourable {:.3} [{:.3}, {:.3}], {})",
            c.text,
            recorded.display(),
            c.points.len(),
            c.ratio,
            c.lo,
            c.hi,
            c.detail
        );
    }
    if lost.is_empty() {
        say!("claims: none that held in {} fails at every point here", recorded.display());
        Ok(())
    } else {
        Err(Error::Run(format!("{} claim(s) held in {} and fail here at every point", lost.len(), recorded.display())))
    }
}

/// Writes the static site of `--results` into `--out`: every experiment folder with its experiment.toml's spec.
fn site_command(args: &SiteArgs) -> Result<(), Error> {
    if !args.results.is_dir() {
        return Err(Error::Input(format!("{}: no such results folder", args.results.display())));
    }
    let dirs = report::site::experiment_dirs(&args.results).map_err(|e| Error::Input(e.to_string()))?;
    let mut experiments = Vec::new();
    for dir in dirs {
        let exp = Experiment::load(&dir.join(run::CONFIG_COPY))?;
        experiments.push((dir, exp.report_spec(vec![])));
    }
    let files = report::site::write(&experiments, &args.results.join("history"), &args.out)
        .map_err(|e| Error::Run(e.to_string()))?;
    say!("site: {} pages and files, open {}", files.len(), args.out.join("index.html").display());
    Ok(())
}

fn validate_command(args: &ValidateArgs) -> Result<(), Error> {
    let exp = load(&args.config, args.quick)?;
    let cores = plan::available_threads();
    let mut plan = Plan::new(&exp, cores)?;
    plan.skip_unavailable(&exp.path.display().to_string(), false)?;
    let seconds_at = |repetitions: u32| plan::plan_seconds(&exp, &plan, cores, repetitions);
    let series: Vec<String> = exp
        .series
        .iter()
        .map(|s| {
            let n = plan.configurations.iter().filter(|c| c.series == s.label).count();
            format!("{} ({n})", s.label)
        })
        .collect();
    say!("{}: ok", exp.path.display());
    say!("configurations {} ({})", plan.configurations.len(), series.join(", "));
    for mesh in plan.mesh_summaries()? {
        say!("mesh           {mesh}");
    }
    let each = match exp.repetitions {
        Repetitions::Fixed(n) => format!("{n} repetitions each"),
        Repetitions::Auto { min, max, target_width } => {
            format!(
                "auto: {min} to {max} repetitions each, until the median's 95% interval is within {:.1}%",
                target_width * 100.0
            )
        }
    };
    let warmups = plan.runs.len() - plan.recorded_runs();
    say!(
        "runs           at most {} recorded ({each}) + {warmups} warm-ups, order {}",
        plan.recorded_runs(),
        format!("{:?}", exp.order).to_lowercase()
    );
    let (min, max) = (exp.repetitions.min(), exp.repetitions.max());
    let sampling = format!(
        "{}{}",
        if exp.sample_s > 0.0 { format!("{:.0}-ms samples", exp.sample_s * 1e3) } else { "one pass a sample".into() },
        match exp.processes {
            1 => String::new(),
            n => format!(", each configuration in {n} processes"),
        }
    );
    if min < max {
        say!(
            "estimate       ~{:.0} to ~{:.0} s on {cores} cores ({sampling}; rough cost model, within about 2x)",
            seconds_at(min),
            seconds_at(max)
        );
    } else {
        say!(
            "estimate       ~{:.0} s on {cores} cores ({sampling}; rough cost model, within about 2x)",
            seconds_at(max)
        );
    }
    if seconds_at(max) > output::LONG_RUN_S {
        say!("note           {}", output::long_run_warning(seconds_at(max)));
    }
    for n in &plan.notes {
        say!("note           {n}");
    }
    Ok(())
}
