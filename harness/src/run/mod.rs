//! Runs a plan: every planned run timed, its counters from a separate counted pass (once per
//! configuration), one row appended and flushed per timed repetition, then the report rebuilt.

mod backend;
pub mod measure;
pub mod provenance;
pub mod validate;

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::process::Command;

use tracer::counters::WorkCounters;
use tracer::rays::RaySet;

use crate::config::Experiment;
use crate::error::Error;
use crate::output::Progress;
use crate::plan::{Configuration, Plan, Settings};
use crate::rows::RowLog;
use measure::Timing;
use provenance::{Provenance, load_average_1m, timestamp_now};
use validate::RayBank;

/// File names inside a run folder.
pub const RUNS_CSV: &str = "runs.csv";
pub const CONFIG_COPY: &str = "experiment.toml";

/// Opens the row log in `dir`: continues it with `resume` (if it exists and was made by the same config
/// text), else starts it over. Returns the runs already recorded.
fn open_log(exp: &Experiment, dir: &Path, resume: bool) -> Result<(RowLog, HashSet<(String, u32)>), Error> {
    let runs = dir.join(RUNS_CSV);
    let copy = dir.join(CONFIG_COPY);
    let io = |what: &str, p: &Path, e: std::io::Error| Error::Input(format!("{}: cannot {what}: {e}", p.display()));
    if resume && runs.exists() {
        let recorded = std::fs::read_to_string(&copy).map_err(|e| io("read", &copy, e))?;
        if recorded != exp.text {
            return Err(Error::Input(format!(
                "{}: was recorded with a different config than {}; run without --resume to start over",
                dir.display(),
                exp.path.display()
            )));
        }
        return RowLog::resume(&runs).map_err(|e| io("resume", &runs, e));
    }
    std::fs::create_dir_all(dir).map_err(|e| io("create", dir, e))?;
    std::fs::write(&copy, &exp.text).map_err(|e| io("write", &copy, e))?;
    Ok((RowLog::create(&runs).map_err(|e| io("create", &runs, e))?, HashSet::new()))
}

fn describe(c: &Configuration) -> String {
    let s = &c.settings;
    format!("{} {} objects={} seed={} {}", c.series, s.workload.name(), s.objects, s.seed, s.strategy)
}

/// What validation found for one configuration.
#[derive(Clone, Debug)]
struct Checked {
    counters: WorkCounters,
    output_hash: u64,
    reference: &'static str,
    mismatches: usize,
    rays: usize,
}

/// How to start a worker process for runs that must not share this process (Embree: TBB's thread limit
/// is process-wide).
#[derive(Clone, Debug)]
pub struct WorkerCall {
    pub config: PathBuf,
    pub quick: bool,
}

impl WorkerCall {
    fn time(&self, c: &Configuration) -> Result<Timing, Error> {
        let exe = std::env::current_exe().map_err(|e| Error::Run(format!("cannot find the harness executable: {e}")))?;
        let mut cmd = Command::new(exe);
        cmd.arg("worker").arg(&self.config).args(["--config-id", &c.id]);
        if self.quick {
            cmd.arg("--quick");
        }
        let out = cmd.output().map_err(|e| Error::Run(format!("cannot start a worker process: {e}")))?;
        let text = String::from_utf8_lossy(&out.stdout);
        match (out.status.success(), text.lines().last().and_then(Timing::from_line)) {
            (true, Some(t)) => Ok(t),
            _ => Err(Error::Run(format!(
                "worker for {} failed: {}",
                describe(c),
                String::from_utf8_lossy(&out.stderr).trim().lines().last().unwrap_or("no output")
            ))),
        }
    }
}

/// The ray set a settings' workload traces (`None` for the render workload).
fn workload_rays(s: &Settings, bank: &mut RayBank) -> Option<std::sync::Arc<RaySet>> {
    match s.workload {
        crate::config::axes::Workload::Rays(k) => Some(bank.get(s, k).0),
        crate::config::axes::Workload::Render => None,
    }
}

/// Runs one configuration of the plan in this process and returns its timing: the worker side of
/// [`WorkerCall`].
pub fn work(plan: &Plan, config_id: &str) -> Result<Timing, Error> {
    let c = plan.configurations.iter().find(|c| c.id == config_id).ok_or_else(|| Error::Input(format!("no configuration {config_id} in this plan")))?;
    let rays = match c.settings.workload {
        crate::config::axes::Workload::Rays(k) => Some(validate::generate(k, &measure::make_scene(&c.settings), c.settings.seed)),
        crate::config::axes::Workload::Render => None,
    };
    measure::timed(&c.settings, rays.as_ref())
}

fn check(c: &Configuration, bank: &mut RayBank) -> Result<Checked, Error> {
    let rays = workload_rays(&c.settings, bank);
    let (set, reference, name) = bank.get(&c.settings, RayBank::validation_kind(c.settings.workload));
    let (counters, output_hash, answers) = measure::counted(&c.settings, rays.as_deref(), &set)?;
    Ok(Checked { counters, output_hash, reference: name, mismatches: validate::mismatches(&set, &reference, &answers), rays: set.rays.len() })
}

fn row(exp: &Experiment, c: &Configuration, rep: u32, t: &Timing, v: &Checked, p: &Provenance, load: f64, ts: String) -> Vec<String> {
    let w = &v.counters;
    let (nodes, boxes, prims) = w.per_ray();
    let trace_s = t.trace_s.max(1e-12);
    let mut row = vec![exp.name.clone(), c.id.clone(), c.series.clone(), rep.to_string()];
    row.extend(c.settings.columns());
    row.extend([
        format!("{:.9}", t.scene_s),
        format!("{:.9}", t.build_s),
        format!("{:.9}", t.trace_s),
        format!("{:.9}", t.encode_s),
        format!("{:.9}", t.total_s()),
        w.rays.to_string(),
        format!("{:.6}", w.rays as f64 / trace_s / 1e6),
        format!("{nodes:.6}"),
        format!("{boxes:.6}"),
        format!("{prims:.6}"),
        t.stats.nodes.to_string(),
        t.stats.leaves.to_string(),
        t.stats.depth.to_string(),
        t.stats.bytes.to_string(),
        format!("{:.6}", t.stats.sah_cost),
        format!("{:016x}", t.output_hash),
        format!("{:016x}", t.scene_fingerprint),
        p.git_commit.clone(),
        p.git_dirty.to_string(),
        p.rustc.clone(),
        p.cpu_model.clone(),
        p.logical_cores.to_string(),
        format!("{load:.2}"),
        ts,
        p.harness_version.clone(),
        if v.mismatches == 0 { "exact".into() } else { "FAILED".into() },
        v.reference.to_string(),
        v.mismatches.to_string(),
        t.peer_info.clone(),
    ]);
    row
}

/// Runs every planned run not yet recorded in `dir`, appending rows as they finish. Each configuration is
/// validated (and counted) once before its first timed run; one that disagrees with the reference is
/// recorded once with `validation = FAILED` and no timings, and never timed.
pub fn sweep(exp: &Experiment, plan: &Plan, dir: &Path, resume: bool, worker: &WorkerCall) -> Result<(), Error> {
    let provenance = Provenance::collect();
    let (mut log, done) = open_log(exp, dir, resume)?;
    let is_done = |config: usize, rep: u32| done.contains(&(plan.configurations[config].id.clone(), rep));
    let reps = exp.repetitions;
    let todo: Vec<_> = plan
        .runs
        .iter()
        .filter(|r| match r.repetition {
            Some(rep) => !is_done(r.config, rep),
            None => !(0..reps).all(|rep| is_done(r.config, rep)),
        })
        .collect();
    if !done.is_empty() {
        eprintln!("resuming {}: {} rows already recorded, {} runs to go", dir.display(), done.len(), todo.len());
    }
    let mut progress = Progress::new(todo.len());
    let mut bank = RayBank::default();
    let mut checked: HashMap<usize, Checked> = HashMap::new();
    let mut failed: HashSet<usize> = HashSet::new();
    for run in todo {
        let c = &plan.configurations[run.config];
        if failed.contains(&run.config) {
            progress.finished(&format!("{} skipped: failed validation", describe(c)));
            continue;
        }
        if !checked.contains_key(&run.config) {
            let v = check(c, &mut bank)?;
            if v.mismatches > 0 {
                eprintln!(
                    "VALIDATION FAILED: {}: {} of {} rays disagree with {}; this configuration is not timed",
                    describe(c), v.mismatches, v.rays, v.reference
                );
                let nan = Timing { scene_s: f64::NAN, build_s: f64::NAN, trace_s: f64::NAN, encode_s: f64::NAN, output_hash: v.output_hash, scene_fingerprint: 0, stats: Default::default(), peer_info: "-".into() };
                let values = row(exp, c, 0, &nan, &v, &provenance, load_average_1m(), timestamp_now());
                log.append(&values).map_err(|e| Error::Run(format!("{}: cannot append a row: {e}", dir.join(RUNS_CSV).display())))?;
                failed.insert(run.config);
                progress.finished(&format!("{} FAILED validation", describe(c)));
                continue;
            }
            checked.insert(run.config, v);
        }
        let load = load_average_1m();
        let ts = timestamp_now();
        let timing = if c.settings.peer.is_some_and(|p| p.kind.needs_embree()) {
            worker.time(c)?
        } else {
            let rays = workload_rays(&c.settings, &mut bank);
            measure::timed(&c.settings, rays.as_deref())?
        };
        let Some(rep) = run.repetition else {
            progress.finished(&format!("{} warm-up", describe(c)));
            continue;
        };
        let v = &checked[&run.config];
        let hash = v.output_hash;
        if hash != timing.output_hash {
            return Err(Error::Run(format!(
                "{}: the counted pass produced output {hash:016x} but the timed pass {:016x}: the tracer is not deterministic",
                describe(c),
                timing.output_hash
            )));
        }
        let values = row(exp, c, rep, &timing, v, &provenance, load, ts);
        log.append(&values).map_err(|e| Error::Run(format!("{}: cannot append a row: {e}", dir.join(RUNS_CSV).display())))?;
        progress.finished(&format!("{} rep {rep}: {:.3} s", describe(c), timing.total_s()));
    }
    progress.finish();
    Ok(())
}
