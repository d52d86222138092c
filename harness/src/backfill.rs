//! `harness history backfill`: the history of past commits, counted now. Each selected commit of a range on the
//! branch's first-parent line is built as `harness ab` builds its base (a worktree, the running binary's target
//! folder and profile, the cached binary reused), and every single-thread configuration of today's suite that the
//! revision can run is counted under callgrind in the revision's own `harness worker` (build and trace
//! instructions, and the worker's answer hash and tree statistics), optionally timed too. One line per commit goes
//! to `commits.csv` and one per counted configuration to `instructions.csv` of the history folder (see
//! `report::history::commits`). Instruction counts depend on the code and the compiler, not on the machine's load,
//! so a history counted on any machine with the same compiler reads the same.
//!
//! Skipped, and said: commits already in `commits.csv` (recorded, or visited before and failed to build: those are
//! recorded as `build failed` and not tried again), and configurations a revision cannot run (a setting newer
//! than it, see [`Revision`], or its worker refusing the request or lacking the phase functions counted between).
//! Each commit's lines are written when it is done, so a killed backfill loses at most the commit it was counting,
//! and running it again goes on from there.

use std::fs;
use std::path::{Path, PathBuf};
use std::time::Instant;

use report::history::commits::{self, CommitEntry, CountedEntry};

use crate::ab::build::{Build, base_binary, git, rustc_version};
use crate::config::Experiment;
use crate::count::{self, How};
use crate::error::Error;
use crate::plan::{Configuration, Plan};
use crate::revision::Revision;
use crate::run::provenance::Provenance;
use crate::run::{self, worker};

/// What `harness history backfill` was asked.
pub struct BackfillRequest<'a> {
    /// A git revision range, e.g. `d4ea610^..main` (`rev-list --first-parent` order).
    pub range: &'a str,
    /// Every K-th commit of the range (its last commit always).
    pub every: usize,
    /// The suite (experiments/ci.toml).
    pub config: &'a Path,
    pub quick: bool,
    /// The history folder.
    pub dir: &'a Path,
    /// Timed runs per configuration (0: instruction counts only).
    pub timings: u32,
    /// Valgrind processes at once.
    pub jobs: usize,
}

/// The commits of `range` to visit: every `every`-th, first to last, and the last one always.
fn select(commits: &[String], every: usize) -> Vec<&String> {
    let last = commits.len().saturating_sub(1);
    commits.iter().enumerate().filter(|(i, _)| i % every.max(1) == 0 || *i == last).map(|(_, c)| c).collect()
}

/// The point of a configuration as the speedup history names it.
fn point(c: &Configuration) -> String {
    format!("objects {} (threads {})", c.settings.objects, c.settings.strategy().threads)
}

/// Runs the backfill (see the module's documentation).
pub fn run(request: &BackfillRequest<'_>) -> Result<(), Error> {
    let exp = Experiment::load(request.config)?;
    let exp = if request.quick { exp.quick() } else { exp };
    let mut plan = Plan::new(&exp, crate::plan::available_threads())?;
    plan.skip_unavailable(&exp.path.display().to_string(), false)?;
    let root = PathBuf::from(git(Path::new("."), &["rev-parse", "--show-toplevel"])?);
    let listed = git(&root, &["rev-list", "--first-parent", "--reverse", request.range]).map_err(|e| {
        Error::Input(format!("history backfill: {} is not a revision range of this repository ({e})", request.range))
    })?;
    let commits: Vec<String> = listed.lines().map(String::from).collect();
    if commits.is_empty() {
        return Err(Error::Input(format!(
            "history backfill: {} holds no commits (allowed: a git revision range, e.g. d4ea610^..main)",
            request.range
        )));
    }
    let history = |e: report::Error| Error::Input(e.to_string());
    let visited = commits::read_commits(request.dir).map_err(history)?;
    let todo: Vec<&Configuration> = plan.runnable().filter(|c| count::uncountable(c).is_none()).collect();
    if todo.is_empty() {
        return Err(Error::Input(format!("{}: no single-thread configuration to count", exp.path.display())));
    }
    count::valgrind_version()?;
    let build = Build::running()?;
    let compiler = rustc_version(&root).lines().next().unwrap_or("unknown").to_string();
    let provenance = Provenance::collect();
    let selected = select(&commits, request.every);
    say!(
        "backfill: {} of the {} commits of {} (every {}), {} configurations of {} each",
        selected.len(),
        commits.len(),
        request.range,
        request.every,
        todo.len(),
        exp.name
    );
    let (mut recorded, mut before, mut failed) = (0, Vec::new(), Vec::new());
    for (n, commit) in selected.iter().enumerate() {
        if let Some(v) = visited.iter().find(|v| &v.commit == *commit) {
            before.push(format!("{} ({})", &commit[..12], v.status));
            continue;
        }
        let started = Instant::now();
        let log = git(&root, &["log", "-1", "--format=%cI%n%s", commit])?;
        let (date, subject) = log.split_once('\n').unwrap_or((&log, ""));
        let position: u32 = git(&root, &["rev-list", "--first-parent", "--count", commit])?.parse().unwrap_or(1);
        let mut entry = CommitEntry {
            commit: commit.to_string(),
            position: position.saturating_sub(1),
            date: date.to_string(),
            subject: subject.to_string(),
            status: "recorded".into(),
            compiler: compiler.clone(),
            counted: 0,
            skipped: String::new(),
        };
        note!("backfill {}/{}: {} {subject}", n + 1, selected.len(), &commit[..12]);
        let binary = match base_binary(&root, &build, commit) {
            Ok(binary) => binary,
            Err(e) => {
                note!("backfill: {} does not build: {e}", &commit[..12]);
                failed.push(commit[..12].to_string());
                entry.status = "build failed".into();
                entry.skipped = e.to_string().lines().next().unwrap_or("").to_string();
                commits::record(request.dir, &entry, &[]).map_err(history)?;
                continue;
            }
        };
        let revision = Revision::read(&root, commit);
        let mut skipped: Vec<String> = Vec::new();
        let mut runnable: Vec<&Configuration> = Vec::new();
        for c in &todo {
            match revision.cannot_run(&c.settings) {
                Some(why) => skipped.push(format!("{} {}: {why}", c.series, point(c))),
                None => runnable.push(c),
            }
        }
        let dumps = build.target.join("ab").join(format!("backfill-dumps-{}", std::process::id()));
        fs::create_dir_all(&dumps).map_err(|e| Error::Run(format!("{}: cannot create: {e}", dumps.display())))?;
        let how = How { image: None, cache_sim: false };
        let results = count::count_each(&binary, &plan, &runnable, how, &dumps, request.jobs);
        let _ = fs::remove_dir_all(&dumps);
        let mut counted = Vec::new();
        for (c, result) in runnable.iter().zip(results) {
            let ([(_, build_ir, _), (_, trace_ir, _)], timing) = match result {
                Ok(r) => r,
                Err(e) => {
                    skipped.push(format!("{} {}: {}", c.series, point(c), why_not_counted(&e.to_string())));
                    continue;
                }
            };
            let times = if request.timings > 0 { Some(time(&binary, &root, &plan, c, request.timings)?) } else { None };
            counted.push(CountedEntry {
                commit: commit.to_string(),
                experiment: exp.name.clone(),
                series: c.series.clone(),
                point: point(c),
                config_id: c.id.clone(),
                build_instructions: build_ir,
                trace_instructions: trace_ir,
                output_hash: format!("{:016x}", timing.output_hash),
                nodes: timing.stats.nodes as u64,
                leaves: timing.stats.leaves as u64,
                depth: timing.stats.depth as u64,
                tree_bytes: timing.stats.bytes as u64,
                sah_cost: timing.stats.sah_cost,
                build_s: times.map(|t| t.0),
                trace_s: times.map(|t| t.1),
                machine_id: if times.is_some() { provenance.machine.machine_id.clone() } else { String::new() },
            });
        }
        entry.counted = counted.len() as u32;
        entry.skipped = skipped.join(" · ");
        commits::record(request.dir, &entry, &counted).map_err(history)?;
        recorded += 1;
        say!(
            "backfill: {} recorded: {} configurations counted, {} skipped ({:.0} s){}",
            &commit[..12],
            counted.len(),
            skipped.len(),
            started.elapsed().as_secs_f64(),
            if skipped.is_empty() { String::new() } else { format!(": {}", entry.skipped) }
        );
    }
    if !before.is_empty() {
        say!("backfill: already in the history, not visited again: {}", before.join(", "));
    }
    if !failed.is_empty() {
        say!("backfill: did not build (recorded as such): {}", failed.join(", "));
    }
    say!(
        "backfill: {recorded} commits recorded into {} and {}",
        request.dir.join(commits::COMMITS_CSV).display(),
        request.dir.join(commits::INSTRUCTIONS_CSV).display()
    );
    Ok(())
}

/// Why a configuration was not counted, in one short line.
fn why_not_counted(message: &str) -> String {
    if message.contains("no dump after") {
        return "the revision has no phase functions to count between (bvhlab_phase_build, bvhlab_phase_trace)".into();
    }
    let message = message.split_once("callgrind: ").map_or(message, |(_, why)| why);
    let line = message.lines().next().unwrap_or("");
    if line.chars().count() > 160 { format!("{}…", line.chars().take(159).collect::<String>()) } else { line.into() }
}

/// Median build and trace seconds of `repetitions` runs of `c` in one fresh worker of `binary`, after one warm-up.
fn time(binary: &Path, root: &Path, plan: &Plan, c: &Configuration, repetitions: u32) -> Result<(f64, f64), Error> {
    let request = run::worker_request(plan, c);
    let mut w = worker::Worker::start(binary, Some(root))?;
    w.time(&request)?;
    let mut builds = Vec::new();
    let mut traces = Vec::new();
    for _ in 0..repetitions {
        let t = w.time(&request)?;
        builds.push(t.build_s);
        traces.push(t.trace_s);
    }
    Ok((report::stats::median(&builds), report::stats::median(&traces)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kth_commit_is_visited_and_the_last_always() {
        let commits: Vec<String> = (0..10).map(|i| format!("c{i}")).collect();
        let names = |every| select(&commits, every).into_iter().cloned().collect::<Vec<_>>();
        assert_eq!(names(4), ["c0", "c4", "c8", "c9"]);
        assert_eq!(names(3), ["c0", "c3", "c6", "c9"]);
        assert_eq!(names(1).len(), 10);
        assert_eq!(names(100), ["c0", "c9"]);
    }
}
