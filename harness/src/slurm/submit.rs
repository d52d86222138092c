//! `harness slurm submit` and `harness slurm resubmit`.

use std::path::{Path, PathBuf};
use std::process::Command;

use schema::Threads;

use super::sbatch::{self, JobOptions};
use super::{Jobs, SLURM_DIR, Submission, config_hash, read_json, shard_dir, write_json};
use crate::cli::SubmitArgs;
use crate::error::Error;
use crate::merge;
use crate::plan::Plan;
use crate::run::provenance::timestamp_now;

/// `path` made absolute against the current folder (without touching the file system).
fn absolute(path: &Path) -> Result<PathBuf, Error> {
    std::path::absolute(path).map_err(|e| Error::Input(format!("{}: cannot make it absolute: {e}", path.display())))
}

/// CPUs a task asks for: the largest explicit thread count of the plan (at least 1). `threads = "all"` is left to
/// the node: with `--exclusive` the task has the whole node and `all` resolves there to its logical cores.
fn cpus_per_task(plan: &Plan) -> usize {
    plan.configurations
        .iter()
        .filter_map(|c| match c.threads {
            Threads::Count(n) => Some(n as usize),
            Threads::All => None,
        })
        .max()
        .unwrap_or(1)
        .max(1)
}

/// Runs `sbatch --parsable [extra] script` and returns the job id it prints.
fn sbatch(script: &Path, extra: &[String]) -> Result<String, Error> {
    let out = Command::new("sbatch").arg("--parsable").args(extra).arg(script).output().map_err(|e| {
        Error::Input(format!("sbatch: cannot run it ({e}): is Slurm installed here? (--dry-run prints the scripts)"))
    })?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        let why = String::from_utf8_lossy(&out.stderr).trim().replace('\n', " ");
        return Err(Error::Run(format!("sbatch {}: {why}", script.display())));
    }
    // `--parsable` prints `id` or `id;cluster`.
    let id = stdout.trim().split(';').next().unwrap_or_default().to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(Error::Run(format!("sbatch {}: expected a job id, got {:?}", script.display(), stdout.trim())));
    }
    Ok(id)
}

/// Writes the scripts of `tasks`, submits the array then the merge job after it, and records both in jobs.json.
fn launch(options: &JobOptions, tasks: &[usize], previous: Vec<Submission>) -> Result<Submission, Error> {
    let slurm = options.run_dir.join(SLURM_DIR);
    let io = |p: &Path, e: std::io::Error| Error::Run(format!("{}: cannot write: {e}", p.display()));
    let logs = sbatch::log_dir(options);
    std::fs::create_dir_all(&logs).map_err(|e| io(&logs, e))?;
    let job = slurm.join("job.sbatch");
    std::fs::write(&job, sbatch::array_script(options, tasks)).map_err(|e| io(&job, e))?;
    let array_job_id = sbatch(&job, &[])?;
    let merge = slurm.join("merge.sbatch");
    std::fs::write(&merge, sbatch::merge_script(options, &array_job_id)).map_err(|e| io(&merge, e))?;
    let mut submission =
        Submission { array_job_id, merge_job_id: String::new(), tasks: tasks.to_vec(), submitted: timestamp_now() };
    let mut submissions = previous;
    submissions.push(submission.clone());
    let jobs_json = slurm.join("jobs.json");
    // Recorded before the merge job is submitted, so that a failing sbatch still leaves the array on record.
    write_json(&jobs_json, &Jobs { options: options.clone(), submissions: submissions.clone() })?;
    submission.merge_job_id = sbatch(&merge, &[])?;
    *submissions.last_mut().expect("pushed above") = submission.clone();
    write_json(&jobs_json, &Jobs { options: options.clone(), submissions })?;
    Ok(submission)
}

fn print_scripts(options: &JobOptions, tasks: &[usize]) {
    say!("# ---- {}/{SLURM_DIR}/job.sbatch", options.run_dir.display());
    say!("{}", sbatch::array_script(options, tasks).trim_end_matches('\n'));
    say!("# ---- {}/{SLURM_DIR}/merge.sbatch", options.run_dir.display());
    say!("{}", sbatch::merge_script(options, "<ARRAY_JOB_ID>").trim_end_matches('\n'));
}

/// `harness slurm submit`: plans the config, writes `RUN_DIR/slurm/{job,merge}.sbatch`, submits both and records
/// the job ids in `RUN_DIR/slurm/jobs.json` (with `--dry-run`: prints the scripts, writes and submits nothing).
pub fn submit(args: &SubmitArgs) -> Result<(), Error> {
    let exp = crate::load(&args.config, args.quick)?;
    let plan = Plan::new(&exp, crate::plan::available_threads())?;
    let (shards, cells) = (args.shards as usize, plan.cell_count());
    if shards > cells {
        return Err(Error::Input(format!(
            "--shards {shards}: {} has only {cells} scene cells, and a cell never spans shards (allowed: 1..={cells})",
            exp.path.display()
        )));
    }
    let run_dir = absolute(&args.out.clone().unwrap_or_else(|| crate::run::default_dir(&exp, args.quick)))?;
    let jobs_json = run_dir.join(SLURM_DIR).join("jobs.json");
    if jobs_json.exists() {
        return Err(Error::Input(format!(
            "{}: already submitted (allowed: `harness slurm resubmit {}` for the missing shards, or a new --out)",
            jobs_json.display(),
            run_dir.display()
        )));
    }
    let harness =
        std::env::current_exe().map_err(|e| Error::Run(format!("cannot find the harness executable: {e}")))?;
    let options = JobOptions {
        experiment: exp.name.clone(),
        config: absolute(&args.config)?,
        config_hash: config_hash(&exp.text),
        quick: args.quick,
        shards,
        max_parallel: args.max_parallel.map_or(shards, |k| k as usize),
        exclusive: !args.no_exclusive,
        cpus_per_task: cpus_per_task(&plan),
        partition: args.partition.clone(),
        constraint: args.constraint.clone(),
        time: args.time.clone(),
        allow_mixed_machines: args.allow_mixed_machines,
        harness: absolute(&harness)?,
        run_dir: run_dir.clone(),
        workdir: std::env::current_dir().map_err(|e| Error::Run(format!("cannot read the current folder: {e}")))?,
    };
    if args.no_exclusive && plan.configurations.iter().any(|c| c.threads == Threads::All) {
        note!(
            "note: without --exclusive, threads = \"all\" resolves on each node to the CPUs the task may use there, and \
             other jobs share the node: timings may not compare"
        );
    }
    let tasks: Vec<usize> = (0..shards).collect();
    if args.dry_run {
        print_scripts(&options, &tasks);
        return Ok(());
    }
    let s = launch(&options, &tasks, Vec::new())?;
    say!("array job {} ({shards} shards, at most {} at once)", s.array_job_id, options.max_parallel);
    say!("merge job {} (after the array ends)", s.merge_job_id);
    say!("jobs: {}", jobs_json.display());
    Ok(())
}

/// Whether any job of `ids` is still queued or running (`squeue`; false where squeue is absent).
fn still_queued(ids: &[&str]) -> Vec<String> {
    let Ok(out) = Command::new("squeue").args(["-h", "-o", "%i", "-j", &ids.join(",")]).output() else { return vec![] };
    String::from_utf8_lossy(&out.stdout).lines().map(|l| l.trim().to_string()).filter(|l| !l.is_empty()).collect()
}

/// `harness slurm resubmit`: submits again the array tasks whose shard folders lack planned rows, and a new merge
/// job after them.
pub fn resubmit(run_dir: &Path, dry_run: bool) -> Result<(), Error> {
    let jobs_json = run_dir.join(SLURM_DIR).join("jobs.json");
    let jobs: Jobs = read_json(&jobs_json)?;
    let o = &jobs.options;
    let exp = crate::load(&o.config, o.quick)?;
    if config_hash(&exp.text) != o.config_hash {
        return Err(Error::Input(format!(
            "{}: its text changed since it was submitted (hash {}, now {}); restore it or submit anew",
            o.config.display(),
            o.config_hash,
            config_hash(&exp.text)
        )));
    }
    if let Some(last) = jobs.submissions.last() {
        let queued = still_queued(&[&last.array_job_id, &last.merge_job_id]);
        if !queued.is_empty() {
            return Err(Error::Input(format!(
                "{}: jobs {} are still queued or running (allowed: resubmit once they have ended, or scancel them)",
                run_dir.display(),
                queued.join(", ")
            )));
        }
    }
    let plan = Plan::new(&exp, crate::plan::available_threads())?;
    let mut tasks = Vec::new();
    for i in 1..=o.shards {
        let missing = merge::missing_rows(&plan, &shard_dir(run_dir, i, o.shards), i, o.shards)?;
        if missing > 0 {
            say!("shard {i} of {}: {missing} planned rows missing", o.shards);
            tasks.push(i - 1);
        }
    }
    if tasks.is_empty() {
        say!(
            "all {} shards are complete: nothing to resubmit (merge with `harness merge {}`)",
            o.shards,
            run_dir.display()
        );
        return Ok(());
    }
    if dry_run {
        print_scripts(o, &tasks);
        return Ok(());
    }
    let s = launch(o, &tasks, jobs.submissions.clone())?;
    say!(
        "array job {} (shards {})",
        s.array_job_id,
        tasks.iter().map(|t| (t + 1).to_string()).collect::<Vec<_>>().join(", ")
    );
    say!("merge job {} (after the array ends)", s.merge_job_id);
    Ok(())
}
