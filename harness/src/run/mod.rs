//! Runs a plan: every planned run timed, its counters from a separate counted pass (once per
//! configuration), one row appended and flushed per timed repetition, then the report rebuilt.

mod measure;
pub mod provenance;

use std::collections::{HashMap, HashSet};
use std::path::Path;

use tracer::counters::WorkCounters;

use crate::config::Experiment;
use crate::error::Error;
use crate::output::Progress;
use crate::plan::{Configuration, Plan};
use crate::rows::RowLog;
use provenance::{Provenance, load_average_1m, timestamp_now};

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

fn row(exp: &Experiment, c: &Configuration, rep: u32, t: &measure::Timing, w: &WorkCounters, p: &Provenance, load: f64, ts: String) -> Vec<String> {
    let (nodes, boxes, prims) = w.per_ray();
    let trace_s = t.trace_s.max(1e-12);
    let mut v = vec![exp.name.clone(), c.id.clone(), c.series.clone(), rep.to_string()];
    v.extend(c.settings.columns());
    v.extend([
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
    ]);
    v
}

/// Runs every planned run not yet recorded in `dir`, appending rows as they finish.
pub fn sweep(exp: &Experiment, plan: &Plan, dir: &Path, resume: bool) -> Result<(), Error> {
    let (mut log, done) = open_log(exp, dir, resume)?;
    let provenance = Provenance::collect();
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
    let mut counted: HashMap<usize, (WorkCounters, u64)> = HashMap::new();
    for run in todo {
        let c = &plan.configurations[run.config];
        let load = load_average_1m();
        let ts = timestamp_now();
        let timing = measure::timed(&c.settings);
        let Some(rep) = run.repetition else {
            progress.finished(&format!("{} warm-up", describe(c)));
            continue;
        };
        let (counters, hash) = *counted.entry(run.config).or_insert_with(|| measure::counted(&c.settings));
        if hash != timing.output_hash {
            return Err(Error::Run(format!(
                "{}: the counted pass produced output {hash:016x} but the timed pass {:016x}: the tracer is not deterministic",
                describe(c),
                timing.output_hash
            )));
        }
        let values = row(exp, c, rep, &timing, &counters, &provenance, load, ts);
        log.append(&values).map_err(|e| Error::Run(format!("{}: cannot append a row: {e}", dir.join(RUNS_CSV).display())))?;
        progress.finished(&format!("{} rep {rep}: {:.3} s", describe(c), timing.total_s()));
    }
    progress.finish();
    Ok(())
}
