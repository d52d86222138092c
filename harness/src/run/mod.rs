//! Runs a plan: every planned run timed, its counters from a separate counted pass (once per
//! configuration), one row appended and flushed per timed repetition, then the report rebuilt.

mod adaptive;
pub mod measure;
pub mod provenance;
mod sweep;
pub mod validate;
pub mod worker;

use std::path::Path;

use schema::{Row, Settings, ValidationStatus, Workload, WrongSide};
use tracer::counters::WorkCounters;
use tracer::rays::RaySet;

use crate::backend;
use crate::config::Experiment;
use crate::error::Error;
use crate::output::Progress;
use crate::plan::{Configuration, Plan, PlannedRun};
use crate::rows::RowLog;
use measure::Timing;
use provenance::{Provenance, load_average_1m, timestamp_now};
use sweep::Sweep;
use validate::{Judgement, RayBank};
use worker::WorkerRequest;

/// File names inside a run folder.
pub const RUNS_CSV: &str = "runs.csv";
pub const CONFIG_COPY: &str = "experiment.toml";

/// Where a run of `exp` is recorded unless told otherwise: `results/<name>/`, or `results/<name>-quick/` for the
/// config's quick form.
pub fn default_dir(exp: &Experiment, quick: bool) -> std::path::PathBuf {
    std::path::PathBuf::from("results").join(if quick { format!("{}-quick", exp.name) } else { exp.name.clone() })
}

/// What a run does with a folder that already holds recorded rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Existing {
    /// Move the earlier run aside into `previous/` (the default: no recorded row is lost).
    MoveAside,
    /// Continue it (`--resume`): skip the runs already recorded.
    Resume,
    /// Replace it (`--force`): its rows are deleted.
    Replace,
}

/// The folder an earlier run moves into when a new run starts in its folder; older ones become `previous-1`,
/// `previous-2`, … in the order they were recorded.
pub const PREVIOUS: &str = "previous";

/// True for the entries of a run folder that belong to other runs and stay where they are when the folder's own
/// run moves aside: earlier runs, shard folders (each moves its own run aside) and Slurm job files.
fn belongs_to_other_runs(name: &str) -> bool {
    name == PREVIOUS
        || name.strip_prefix("previous-").is_some_and(|n| n.parse::<u32>().is_ok())
        || (name.starts_with("shard-") && name.contains("-of-"))
        || name == crate::slurm::SLURM_DIR
}

/// Moves the run recorded in `dir` (its rows, config copy, summaries, figures, report and counts) into
/// `dir/previous/`, after renaming an existing `previous/` to the next free `previous-K`. Returns the folder the
/// rows moved to.
pub fn move_aside(dir: &Path) -> Result<std::path::PathBuf, Error> {
    let io = |what: &str, p: &Path, e: std::io::Error| Error::Run(format!("{}: cannot {what}: {e}", p.display()));
    let previous = dir.join(PREVIOUS);
    if previous.exists() {
        let older = (1..).map(|k| dir.join(format!("{PREVIOUS}-{k}"))).find(|p| !p.exists()).expect("a free name");
        std::fs::rename(&previous, &older).map_err(|e| io("move aside", &previous, e))?;
    }
    std::fs::create_dir(&previous).map_err(|e| io("create", &previous, e))?;
    let entries = std::fs::read_dir(dir).map_err(|e| io("read", dir, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| io("read", dir, e))?;
        if belongs_to_other_runs(&entry.file_name().to_string_lossy()) {
            continue;
        }
        let to = previous.join(entry.file_name());
        std::fs::rename(entry.path(), &to).map_err(|e| io("move aside", &entry.path(), e))?;
    }
    Ok(previous)
}

/// Opens the row log in `dir`. A folder holding rows is continued ([`Existing::Resume`], when made by the same
/// config text), replaced ([`Existing::Replace`]) or, by default, moved aside first ([`move_aside`]). Returns the
/// rows already recorded (those of a continued log).
fn open_log(exp: &Experiment, dir: &Path, existing: Existing) -> Result<(RowLog, Vec<Row>), Error> {
    let runs = dir.join(RUNS_CSV);
    let copy = dir.join(CONFIG_COPY);
    let io = |what: &str, p: &Path, e: std::io::Error| Error::Input(format!("{}: cannot {what}: {e}", p.display()));
    if runs.exists() {
        match existing {
            Existing::Resume => {
                let recorded = std::fs::read_to_string(&copy).map_err(|e| io("read", &copy, e))?;
                if recorded != exp.text {
                    return Err(Error::Input(format!(
                        "{}: was recorded with a different config than {}; run without --resume to move it aside \
                         into {PREVIOUS}/ and start over",
                        dir.display(),
                        exp.path.display()
                    )));
                }
                return RowLog::resume(&runs).map_err(|e| io("resume", &runs, e));
            }
            Existing::MoveAside => {
                let to = move_aside(dir)?;
                note!(
                    "{}: the earlier run's rows moved to {} (--force replaces them instead)",
                    dir.display(),
                    to.display()
                );
            }
            Existing::Replace => {}
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| io("create", dir, e))?;
    std::fs::write(&copy, &exp.text).map_err(|e| io("write", &copy, e))?;
    Ok((RowLog::create(&runs).map_err(|e| io("create", &runs, e))?, Vec::new()))
}

/// Refuses to continue rows timed on other pages than this process's: `huge_pages` is not part of a point's
/// key (older rows say `-`, recorded before the column, when every run used 4-KiB pages), so a resumed run that
/// switched `--huge-pages` on or off would pool both into one point.
fn refuse_mixed_pages(dir: &Path, recorded: &[Row], pages: &str) -> Result<(), Error> {
    let spelled = |p: &str| if p == "-" { "no" } else { p }.to_string();
    match recorded.iter().map(|r| spelled(&r.huge_pages)).find(|p| *p != spelled(pages)) {
        Some(theirs) => Err(Error::Input(format!(
            "{}: huge_pages: its rows were timed with `{theirs}` and this run has `{pages}`; resume with{} \
             --huge-pages (allowed: the pages its rows were timed on), or run without --resume to start over",
            dir.join(RUNS_CSV).display(),
            if theirs == "no" { "out" } else { "" }
        ))),
        None => Ok(()),
    }
}

fn describe(c: &Configuration) -> String {
    let s = &c.settings;
    format!("{} {} objects={} seed={} {}", c.series, schema::Named::name(s.workload), s.objects, s.seed, s.strategy())
}

/// What validation found for one configuration.
#[derive(Clone, Debug)]
struct Checked {
    status: ValidationStatus,
    counters: WorkCounters,
    output_hash: u64,
    reference: &'static str,
    /// Mismatches, tolerated disagreements by kind, the reference's own check and whose answers were wrong.
    judged: Judgement,
    rays: usize,
}

impl Checked {
    /// The note for a configuration (`what`) that failed validation.
    fn failure(&self, what: &str) -> String {
        format!(
            "VALIDATION FAILED: {what}: {} of {} rays disagree with {} beyond f64 brute force's tolerance ({} grazing, \
             {} ties, {} leaks tolerated); f64 shows the {} answers wrong; this configuration is not timed",
            self.judged.mismatches,
            self.rays,
            self.reference,
            self.judged.grazing,
            self.judged.ties,
            self.judged.leaks,
            match self.judged.wrong_side {
                WrongSide::Both => "backend's and the reference's",
                WrongSide::Reference => "reference's",
                WrongSide::Backend | WrongSide::Neither => "backend's",
            }
        )
    }
}

/// The ray set a configuration's workload traces (`None` for the render workload).
fn workload_rays(plan: &Plan, s: &Settings, bank: &mut RayBank) -> Option<std::sync::Arc<RaySet>> {
    match s.workload {
        Workload::Rays(k) => Some(bank.get(s, plan.scene_file(), k).0),
        Workload::Render => None,
    }
}

/// The worker request of a configuration.
pub fn worker_request(plan: &Plan, c: &Configuration) -> WorkerRequest {
    WorkerRequest {
        settings: c.settings.clone(),
        sphere_file: plan.sphere_file.as_ref().map(|f| f.path.clone()),
        sample_s: plan.sample_s,
        rays_file: None,
        step: worker::Step::Whole,
    }
}

fn check(plan: &Plan, c: &Configuration, bank: &mut RayBank) -> Result<Checked, Error> {
    let rays = workload_rays(plan, &c.settings, bank);
    if !backend::of(c.settings.accel).answers() {
        let (counters, output_hash, _) = measure::counted(&c.settings, plan.scene_file(), rays.as_deref(), None)?;
        return Ok(Checked {
            status: ValidationStatus::Unchecked,
            counters,
            output_hash,
            reference: "-",
            judged: Judgement::default(),
            rays: 0,
        });
    }
    let reference = bank.reference(&c.settings, plan.scene_file(), c.settings.workload.validation_kind());
    let set = &reference.set;
    let (counters, output_hash, answers) =
        measure::counted(&c.settings, plan.scene_file(), rays.as_deref(), Some(set))?;
    let judged = validate::judge(&reference, &answers.expect("answers were asked for"));
    Ok(Checked {
        status: if judged.mismatches == 0 { ValidationStatus::Exact } else { ValidationStatus::Failed },
        counters,
        output_hash,
        reference: reference.name,
        judged,
        rays: set.rays.len(),
    })
}

/// What every row of one sweep shares: the experiment, where and how it was recorded, and its shard.
struct Recording<'a> {
    exp: &'a Experiment,
    provenance: &'a Provenance,
    shard: Option<(usize, usize)>,
}

/// When a run started: the 1-minute load average just before it and its RFC 3339 time.
#[derive(Clone)]
struct Started {
    load: f64,
    timestamp: String,
}

impl Started {
    fn now() -> Self {
        Started { load: load_average_1m(), timestamp: timestamp_now() }
    }
}

/// The row of one timed repetition (or of a configuration that failed validation, with NaN timings).
fn row(r: &Recording, c: &Configuration, rep: u32, t: &Timing, v: &Checked, started: Started) -> Row {
    let (exp, p, shard) = (r.exp, r.provenance, r.shard);
    let Started { load, timestamp } = started;
    let w = &v.counters;
    let (nodes, boxes, prims) = w.per_ray();
    let mut row = Row::of(&c.settings);
    row.experiment = exp.name.clone();
    row.config_id = c.id.clone();
    row.series = c.series.clone();
    row.repetition = rep;
    // A configuration that failed validation is never timed: its metrics stay empty.
    let metric = |x: f64| x.is_finite().then_some(x);
    row.setup_s = metric(t.setup_s);
    row.scene_s = metric(t.scene_s);
    row.build_s = metric(t.build_s);
    row.trace_s = metric(t.trace_s);
    row.overhead_s = t.overhead_s.and_then(metric);
    row.trace_passes = t.trace_passes;
    row.sample_configs = t.sample_configs;
    row.steal_s = t.steal_s;
    row.process_id = t.process_id;
    row.encode_s = metric(t.encode_s);
    row.total_s = metric(t.total_s());
    row.rays = w.rays;
    row.mrays_per_s = metric(t.trace_s).map(|trace_s| w.rays as f64 / trace_s.max(1e-12) / 1e6);
    row.nodes_per_ray = nodes;
    row.box_tests_per_ray = boxes;
    row.prim_tests_per_ray = prims;
    row.tree_nodes = t.stats.nodes as u64;
    row.tree_leaves = t.stats.leaves as u64;
    row.tree_depth = t.stats.depth as u64;
    row.tree_bytes = t.stats.bytes as u64;
    row.sah_cost = t.stats.sah_cost;
    row.image_hash = format!("{:016x}", t.output_hash);
    row.scene_fingerprint = format!("{:016x}", t.scene_fingerprint);
    row.git_commit = p.git_commit.clone();
    row.git_dirty = p.git_dirty;
    row.rustc = p.rustc.clone();
    row.cpu_model = p.cpu_model.clone();
    row.logical_cores = p.logical_cores as u32;
    row.threads = c.threads;
    row.threads_used = c.settings.strategy().threads as u32;
    row.load_avg_1m = load;
    row.timestamp = timestamp;
    row.harness_version = p.harness_version.clone();
    row.validation = v.status;
    row.validated_against = v.reference.to_string();
    row.mismatches = v.judged.mismatches as u64;
    row.grazing = v.judged.grazing as u64;
    row.ties = v.judged.ties as u64;
    row.leaks = v.judged.leaks as u64;
    row.reference_checked = v.judged.reference_checked as u64;
    row.wrong_side = v.judged.wrong_side;
    row.peer_info = t.peer_info.clone();
    // A configuration never timed (failed validation) records the kernel it was validated with.
    row.simd_kernel_used = match (t.simd_kernel.as_str(), c.settings.simd_kernel) {
        ("-", Some(k)) => k.resolve_for(c.settings.accel_params().wide.leaf_block).name().to_string(),
        (used, _) => used.to_string(),
    };
    let m = &p.machine;
    row.cpu_vendor = m.cpu_vendor.clone();
    row.cpu_signature = m.cpu_signature.clone();
    row.cpu_isa = m.cpu_isa.clone();
    row.cpu_caches = m.cpu_caches.clone();
    row.hypervisor = m.hypervisor;
    row.kernel = m.kernel.clone();
    row.target_features = m.target_features.clone();
    row.machine_id = m.machine_id.clone();
    row.boot_id = m.boot_id.clone();
    row.cargo_lock = p.cargo_lock.clone();
    row.slurm_job_id = p.slurm_job_id.clone();
    row.huge_pages = p.huge_pages.clone();
    if let Some((i, n)) = shard {
        row.shard = format!("{i}/{n}");
        row.node = if p.node.is_empty() { provenance::hostname() } else { p.node.clone() };
    } else {
        row.node = p.node.clone();
    }
    row.rounded()
}

/// Runs every planned run not yet recorded in `dir`, appending rows as they finish. Each configuration is
/// validated (and counted) once before its first timed run; one that disagrees with the reference is
/// recorded once with `validation = FAILED` and no timings, and never timed. With `repetitions = "auto"` a
/// configuration's remaining repetitions are skipped once its median is known well enough ([`adaptive`]).
pub fn sweep(exp: &Experiment, plan: &Plan, dir: &Path, existing: Existing) -> Result<(), Error> {
    let provenance = Provenance::collect();
    let recording = Recording { exp, provenance: &provenance, shard: plan.shard };
    let (mut log, recorded) = open_log(exp, dir, existing)?;
    refuse_mixed_pages(dir, &recorded, &provenance.huge_pages)?;
    let mut append = |row: &Row| {
        log.append(row).map_err(|e| Error::Run(format!("{}: cannot append a row: {e}", dir.join(RUNS_CSV).display())))
    };
    let mut sweep = Sweep::new(exp, plan);
    sweep.resume(&recorded);
    let todo: Vec<&PlannedRun> = plan.runs.iter().filter(|r| sweep.to_do(r)).collect();
    if !recorded.is_empty() {
        note!(
            "resuming {}: {} rows already recorded, at most {} runs to go",
            dir.display(),
            recorded.len(),
            todo.len()
        );
    }
    for run in &todo {
        sweep.states[run.config].pending.add(run);
    }
    let cores = crate::plan::available_threads();
    let model = plan.configurations.iter().map(|c| crate::plan::estimate_seconds(&c.settings, cores)).collect();
    let mut progress = Progress::new(model);
    progress.update(|config| sweep.expected(config));
    let mut bank = RayBank::default();
    // With `sample_ms`, an interleaved round's series of one point are sampled together, a pass of each in turn.
    let together = plan.sample_s > 0.0 && exp.order == crate::config::RunOrder::Interleaved;
    let mut todo = todo.into_iter().peekable();
    while let Some(first) = todo.next() {
        let mut group = vec![first];
        while let Some(next) = todo.peek().filter(|_| together)
            && plan.configurations[next.config].point == plan.configurations[first.config].point
            && next.repetition == first.repetition
        {
            group.push(*next);
            todo.next();
        }
        // Each is validated (and counted) before its first timed run; one that fails is recorded and never timed.
        let mut ready = Vec::new();
        for run in group {
            let c = &plan.configurations[run.config];
            let rule = sweep.rule(c);
            let state = &mut sweep.states[run.config];
            if state.failed || sweep.sampler.is_done(run.config) {
                continue;
            }
            if state.checked.is_none() {
                let started = std::time::Instant::now();
                let v = check(plan, c, &mut bank)?;
                progress.validated(run.config, started.elapsed().as_secs_f64());
                if v.status == ValidationStatus::Failed {
                    note!("{}", v.failure(&describe(c)));
                    let mut failed = row(&recording, c, 0, &Timing::untimed(v.output_hash), &v, Started::now());
                    failed.repetition_rule = rule;
                    append(&failed)?;
                    state.fail();
                    progress.untimed(&format!("{} FAILED validation", describe(c)));
                    progress.update(|config| sweep.expected(config));
                    continue;
                }
                state.checked = Some(v);
            }
            ready.push(*run);
        }
        if ready.is_empty() {
            continue;
        }
        let started_run = Started::now();
        let started = std::time::Instant::now();
        let configs: Vec<usize> = ready.iter().map(|r| r.config).collect();
        let timings = sweep.time(&configs, plan, &mut bank)?;
        let seconds = started.elapsed().as_secs_f64() / ready.len() as f64;
        for (run, timing) in ready.iter().zip(timings) {
            let c = &plan.configurations[run.config];
            let (metric, rule) = (sweep.metric(c), sweep.rule(c));
            let state = &mut sweep.states[run.config];
            state.pending.take(run);
            let what = match run.repetition {
                None => format!("{} warm-up", describe(c)),
                Some(rep) => {
                    let v = state.checked.clone().expect("checked before its first run");
                    if v.output_hash != timing.output_hash {
                        return Err(Error::Run(format!(
                            "{}: the counted pass produced output {:016x} but the timed pass {:016x}: the tracer is not deterministic",
                            describe(c),
                            v.output_hash,
                            timing.output_hash
                        )));
                    }
                    let mut recorded = row(&recording, c, rep, &timing, &v, started_run.clone());
                    recorded.repetition_rule = rule;
                    recorded.interval_width = sweep.sampler.record(run.config, adaptive::timed_value(&timing, metric));
                    // Rounding is idempotent: the rest of the row was rounded by `row` already.
                    let recorded = recorded.rounded();
                    append(&recorded)?;
                    let width =
                        recorded.interval_width.map_or(String::new(), |w| format!(" (interval ±{:.1}%)", w * 50.0));
                    format!("{} rep {rep}: {:.3} s{width}", describe(c), timing.total_s())
                }
            };
            // After a configuration's last run its worker process, pool and device go.
            let state = &mut sweep.states[run.config];
            if state.pending.is_empty() || sweep.sampler.is_done(run.config) {
                state.finish();
            }
            progress.finished(run.config, seconds, &what);
            progress.update(|config| sweep.expected(config));
        }
    }
    progress.finish();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_rows_leave_every_metric_empty() {
        let exp = Experiment::parse(Path::new("t.toml"), "name = \"t\"\n[sweep]\nworkload = \"primary\"\n").unwrap();
        let plan = Plan::new(&exp, 2).unwrap();
        let counters = WorkCounters { rays: 786_432, ..Default::default() };
        let v = Checked {
            status: ValidationStatus::Failed,
            counters,
            output_hash: 1,
            reference: "reference",
            judged: Judgement {
                mismatches: 3,
                grazing: 2,
                ties: 4,
                leaks: 5,
                reference_checked: 16_384,
                wrong_side: WrongSide::Backend,
            },
            rays: 786_432,
        };
        let provenance = Provenance::collect();
        let recording = Recording { exp: &exp, provenance: &provenance, shard: None };
        let started = Started { load: 0.5, timestamp: "t".into() };
        let row = row(&recording, &plan.configurations[0], 0, &Timing::untimed(1), &v, started);
        assert_eq!((row.validation, row.mismatches), (ValidationStatus::Failed, 3));
        assert_eq!((row.grazing, row.reference_checked, row.wrong_side), (2, 16_384, WrongSide::Backend));
        assert_eq!((row.ties, row.leaks), (4, 5));
        let text = format!("{}\n{}", schema::row::header(), schema::row::csv_line(&row).unwrap());
        let back = &schema::row::read_rows(&text).unwrap()[0];
        let metrics =
            [back.setup_s, back.scene_s, back.build_s, back.trace_s, back.encode_s, back.total_s, back.mrays_per_s];
        assert!(metrics.iter().all(Option::is_none), "{metrics:?} in {text}");
    }
}
