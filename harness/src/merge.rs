//! `harness merge RUN_DIR`: the shard folders of a sharded sweep (`shard-I-of-N/`) checked and concatenated into
//! `RUN_DIR/runs.csv`, then the report rebuilt from them.
//!
//! Refused (exit 2, nothing written): a missing shard or missing rows, a row in the wrong shard or twice, shards
//! of different configs, commits or `Cargo.lock`s, and rows of more than one machine without
//! `--allow-mixed-machines` (with it the report keeps every machine's times apart and says so at the top).

use schema::column;
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::path::{Path, PathBuf};

use schema::Row;

use crate::config::Experiment;
use crate::error::Error;
use crate::plan::{Plan, shard};
use crate::rows::{RowLog, read_log};
use crate::run::{CONFIG_COPY, RUNS_CSV};
use crate::slurm::{SHARD_JSON, ShardInfo, config_hash, read_json, shard_dir};

/// The `(config_id, repetition)` pairs shard `i` of `n` of `plan` records.
fn planned(plan: &Plan, shard_of: &[usize], i: usize) -> Vec<(String, u32)> {
    plan.runs
        .iter()
        .filter(|r| shard_of[r.config] == i - 1)
        .filter_map(|r| r.repetition.map(|rep| (plan.configurations[r.config].id.clone(), rep)))
        .collect()
}

/// The planned rows of shard `i` of `n` absent from `rows` (a configuration recorded as `FAILED` validation is
/// never timed, so its one row completes it; one `skipped` for want of its backend has none).
fn absent(plan: &Plan, shard_of: &[usize], i: usize, rows: &[Row], skipped: &[String]) -> Vec<(String, u32)> {
    let done: HashSet<(&str, u32)> = rows.iter().map(|r| (r.config_id.as_str(), r.repetition)).collect();
    let mut complete: HashSet<&str> = rows
        .iter()
        .filter(|r| r.validation == schema::ValidationStatus::Failed)
        .map(|r| r.config_id.as_str())
        .collect();
    complete.extend(skipped.iter().map(String::as_str));
    planned(plan, shard_of, i)
        .into_iter()
        .filter(|(id, rep)| !complete.contains(id.as_str()) && !done.contains(&(id.as_str(), *rep)))
        .collect()
}

/// How many planned rows of shard `i` of `n` the shard folder `dir` lacks (all of them without a runs.csv).
pub fn missing_rows(plan: &Plan, dir: &Path, i: usize, n: usize) -> Result<usize, Error> {
    let shard_of = shard::assign(plan, n);
    let path = dir.join(RUNS_CSV);
    let rows = if path.is_file() { read_log(&path)? } else { Vec::new() };
    let info = dir.join(SHARD_JSON);
    let skipped = if info.is_file() { read_json::<ShardInfo>(&info)?.skipped } else { Vec::new() };
    Ok(absent(plan, &shard_of, i, &rows, &skipped).len())
}

/// The shard folders of `run_dir`: N and their paths by I.
fn shard_folders(run_dir: &Path) -> Result<(usize, BTreeMap<usize, PathBuf>), Error> {
    let entries =
        std::fs::read_dir(run_dir).map_err(|e| Error::Input(format!("{}: cannot read: {e}", run_dir.display())))?;
    let mut found: BTreeMap<usize, BTreeMap<usize, PathBuf>> = BTreeMap::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let parsed = name.strip_prefix("shard-").and_then(|rest| rest.split_once("-of-"));
        if let Some((Ok(i), Ok(n))) = parsed.map(|(i, n)| (i.parse::<usize>(), n.parse::<usize>())) {
            found.entry(n).or_default().insert(i, entry.path());
        }
    }
    let mut counts = found.keys();
    match (counts.next(), counts.next()) {
        (None, _) => Err(Error::Input(format!(
            "{}: no shard-I-of-N folders here (allowed: a run folder of `harness run --shard` or `harness slurm submit`)",
            run_dir.display()
        ))),
        (Some(a), Some(b)) => Err(Error::Input(format!(
            "{}: shards of different counts (shard-*-of-{a}, shard-*-of-{b}); keep one cut",
            run_dir.display()
        ))),
        (Some(&n), None) => Ok((n, found.remove(&n).expect("listed"))),
    }
}

/// A shard's folder, its shard.json and its rows.
struct Shard {
    i: usize,
    dir: PathBuf,
    info: ShardInfo,
    text: String,
    rows: Vec<Row>,
}

fn shard_name(dir: &Path) -> String {
    dir.file_name().map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// Reads and checks every shard folder of `run_dir`.
fn read_shards(run_dir: &Path) -> Result<Vec<Shard>, Error> {
    let (n, mut folders) = shard_folders(run_dir)?;
    let mut shards = Vec::new();
    for i in 1..=n {
        let dir = folders.remove(&i).unwrap_or_else(|| shard_dir(run_dir, i, n));
        for file in [SHARD_JSON, CONFIG_COPY, RUNS_CSV] {
            if !dir.join(file).is_file() {
                return Err(Error::Input(format!(
                    "{}: shard {i} of {n} is missing (no {}/{file}; allowed: `harness slurm resubmit` or `harness run \
                     --shard {i}/{n} --resume --out {}` first)",
                    run_dir.display(),
                    shard_name(&dir),
                    dir.display()
                )));
            }
        }
        let info: ShardInfo = read_json(&dir.join(SHARD_JSON))?;
        if info.shard != (i, n) {
            return Err(Error::Input(format!(
                "{}: says shard {}/{} (allowed: {i}/{n}, as its folder name)",
                dir.join(SHARD_JSON).display(),
                info.shard.0,
                info.shard.1
            )));
        }
        let copy = dir.join(CONFIG_COPY);
        let text = std::fs::read_to_string(&copy)
            .map_err(|e| Error::Input(format!("{}: cannot read: {e}", copy.display())))?;
        if config_hash(&text) != info.config_hash {
            return Err(Error::Input(format!(
                "{}: config hash {} differs from the {} its {SHARD_JSON} records",
                copy.display(),
                config_hash(&text),
                info.config_hash
            )));
        }
        let rows = read_log(&dir.join(RUNS_CSV))?;
        shards.push(Shard { i, dir, info, text, rows });
    }
    Ok(shards)
}

/// `1, 2, 5`.
fn list(shards: &BTreeSet<usize>) -> String {
    shards.iter().map(usize::to_string).collect::<Vec<_>>().join(", ")
}

/// Fails when `column` takes more than one value over the shards' rows, naming them and their shards.
fn agree(run_dir: &Path, shards: &[Shard], column: &str, what: &str, remedy: &str) -> Result<(), Error> {
    let mut values: BTreeMap<String, BTreeSet<usize>> = BTreeMap::new();
    for s in shards {
        for r in &s.rows {
            values.entry(r.cell(column).map(|c| c.to_string()).unwrap_or_default()).or_default().insert(s.i);
        }
    }
    if values.len() > 1 {
        let each: Vec<String> = values.iter().map(|(v, shards)| format!("{v:?} (shards {})", list(shards))).collect();
        return Err(Error::Input(format!(
            "{}: shards come from different {what}: {column} {} (allowed: one; {remedy})",
            run_dir.display(),
            each.join(", ")
        )));
    }
    Ok(())
}

/// The machines of the rows: id → (cpu model, nodes, shards).
fn machines(shards: &[Shard]) -> BTreeMap<String, (String, BTreeSet<String>, BTreeSet<usize>)> {
    let mut out: BTreeMap<String, (String, BTreeSet<String>, BTreeSet<usize>)> = BTreeMap::new();
    for s in shards {
        for r in s.rows.iter().filter(|r| !r.machine_id.is_empty()) {
            let e = out
                .entry(r.machine_id.clone())
                .or_insert_with(|| (r.cpu_model.clone(), BTreeSet::new(), BTreeSet::new()));
            if !r.node.is_empty() {
                e.1.insert(r.node.clone());
            }
            e.2.insert(s.i);
        }
    }
    out
}

/// `harness merge`: checks the shards of `run_dir` against the plan and each other, writes `run_dir/runs.csv` and
/// `experiment.toml`, and rebuilds the report.
pub fn run(run_dir: &Path, allow_mixed_machines: bool) -> Result<(), Error> {
    let shards = read_shards(run_dir)?;
    let n = shards.len();
    let first = &shards[0];
    for s in &shards[1..] {
        if s.info.config_hash != first.info.config_hash || s.info.quick != first.info.quick {
            return Err(Error::Input(format!(
                "{}: shard {} ran config hash {}{} but shard 1 {}{} (allowed: one config for every shard)",
                run_dir.display(),
                s.i,
                s.info.config_hash,
                if s.info.quick { " --quick" } else { "" },
                first.info.config_hash,
                if first.info.quick { " --quick" } else { "" }
            )));
        }
    }
    let exp = Experiment::parse(&first.info.config, &first.text)?;
    let exp = if first.info.quick { exp.quick() } else { exp };
    let plan = Plan::new(&exp, crate::plan::available_threads())?;
    let shard_of = shard::assign(&plan, n);
    let index: HashMap<&str, usize> = plan.configurations.iter().enumerate().map(|(i, c)| (c.id.as_str(), i)).collect();
    let mut seen: HashMap<(&str, u32), usize> = HashMap::new();
    for s in &shards {
        let file = s.dir.join(RUNS_CSV);
        for r in &s.rows {
            let Some(&config) = index.get(r.config_id.as_str()) else {
                return Err(Error::Input(format!(
                    "{}: configuration {} ({}) is not in the plan of {} (allowed: the plan's {} configurations)",
                    file.display(),
                    r.config_id,
                    r.series,
                    exp.path.display(),
                    plan.configurations.len()
                )));
            };
            if shard_of[config] != s.i - 1 {
                return Err(Error::Input(format!(
                    "{}: configuration {} ({}) belongs to shard {} of {n}, not {}",
                    file.display(),
                    r.config_id,
                    r.series,
                    shard_of[config] + 1,
                    s.i
                )));
            }
            if let Some(other) = seen.insert((r.config_id.as_str(), r.repetition), s.i) {
                return Err(Error::Input(format!(
                    "{}: duplicate row: configuration {} ({}) repetition {} (also in shard {other})",
                    file.display(),
                    r.config_id,
                    r.series,
                    r.repetition
                )));
            }
        }
        let absent = absent(&plan, &shard_of, s.i, &s.rows, &s.info.skipped);
        if let Some((id, rep)) = absent.first() {
            let series = &plan.configurations[index[id.as_str()]].series;
            return Err(Error::Input(format!(
                "{}: shard {} of {n} lacks {} of its {} planned rows (first: configuration {id} ({series}) repetition \
                 {rep}; allowed: complete shards: `harness slurm resubmit {}`)",
                s.dir.display(),
                s.i,
                absent.len(),
                planned(&plan, &shard_of, s.i).len(),
                run_dir.display()
            )));
        }
    }
    let rebuild = "rerun the odd shards with one build";
    agree(run_dir, &shards, column::git_commit, "commits", rebuild)?;
    agree(run_dir, &shards, column::cargo_lock, "Cargo.lock files", rebuild)?;
    // Not part of a point's key: shards on other pages would pool into one point.
    agree(
        run_dir,
        &shards,
        column::huge_pages,
        "pages",
        "rerun the odd shards with or without --huge-pages as the others",
    )?;
    let machines = machines(&shards);
    let described: Vec<String> = machines
        .iter()
        .map(|(id, (model, nodes, shards))| {
            let nodes = nodes.iter().cloned().collect::<Vec<_>>().join(", ");
            format!("{id} ({model}; nodes {nodes}; shards {})", list(shards))
        })
        .collect();
    if machines.len() > 1 && !allow_mixed_machines {
        return Err(Error::Input(format!(
            "{}: rows of {} machines: {} (allowed: one machine, or --allow-mixed-machines: times stay apart per machine)",
            run_dir.display(),
            machines.len(),
            described.join(", ")
        )));
    }

    let io = |p: &Path, e: std::io::Error| Error::Run(format!("{}: cannot write: {e}", p.display()));
    let runs = run_dir.join(RUNS_CSV);
    if runs.exists() {
        // An earlier merge (or a run into this folder) keeps its rows: they move aside, as before a run.
        let to = crate::run::move_aside(run_dir)?;
        note!("{}: the earlier rows moved to {}", run_dir.display(), to.display());
    }
    let mut log = RowLog::create(&runs).map_err(|e| io(&runs, e))?;
    let rows: usize = shards.iter().map(|s| s.rows.len()).sum();
    for r in shards.iter().flat_map(|s| &s.rows) {
        log.append(r).map_err(|e| io(&runs, e))?;
    }
    let copy = run_dir.join(CONFIG_COPY);
    std::fs::write(&copy, &first.text).map_err(|e| io(&copy, e))?;
    let jobs: BTreeSet<&str> =
        shards.iter().flat_map(|s| &s.rows).map(|r| r.slurm_job_id.as_str()).filter(|j| !j.is_empty()).collect();
    let mut note = format!("Merged from {n} shards by `harness merge` (whole scene cells per shard)");
    if !jobs.is_empty() {
        note.push_str(&format!("; Slurm jobs {}", jobs.into_iter().collect::<Vec<_>>().join(", ")));
    }
    note.push_str(&format!("; machines: {}.", described.join(", ")));
    let skipped: usize = shards.iter().map(|s| s.info.skipped.len()).sum();
    if skipped > 0 {
        note.push_str(&format!(" {skipped} configurations were skipped where their backend could not run."));
    }
    let warnings = if machines.len() > 1 {
        vec![format!(
            "this result set merges rows of {} different machines (`--allow-mixed-machines`): {}. Times of different \
             machines are never pooled into one point; speedups are taken within each machine and combined across \
             machines as a geometric mean (see Across machines). Compare absolute times only within one machine.",
            machines.len(),
            described.join(", ")
        )]
    } else {
        vec![]
    };
    say!("merged {rows} rows of {n} shards into {}", runs.display());
    crate::write_report_with(run_dir, &exp, vec![note], warnings).map(|_| ())
}
