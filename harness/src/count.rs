//! `harness instructions`: counts the instructions each single-thread configuration of an experiment executes
//! in its build and in its trace, under callgrind, into `instructions.csv` of the run folder: the input of the
//! deterministic gate of `harness check` (see `report::check::instructions`).
//!
//! Each configuration is one `harness worker` process under `valgrind --tool=callgrind`, asked to time the
//! configuration once over the worker protocol (its JSON request on stdin). Collection is off at the start
//! (`--collect-atstart=no`) and toggled on while the thread that builds or traces is inside the phase functions
//! `bvhlab_phase_build` and `bvhlab_phase_trace` of `backend::workload` (`--toggle-collect`: callgrind toggles per
//! thread, on entering and on leaving), and a dump is written when each is left (`--dump-after`), so the dumps
//! hold exactly one phase each: the scene, the ray set, the pool and the process's start are never counted.
//! Callgrind matches these options against demangled names with `*`/`?` wildcards, and two options with the
//! same pattern text overwrite each other's setting, so the toggles and the dumps use different patterns.
//!
//! Counted: the tracer's structures and obvhs at one thread (serial, or one thread of a pool). Not counted:
//! Embree (its own library and threads), configurations of more than one thread (their other threads' work is
//! not collected), and `mpsc-threads` (its band runs in a thread it spawns). Counts are the same on every run of
//! one binary; they change with the compiler and its target features (recorded on every row).

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use report::check::instructions::{self, InstructionCount};
use tracer::executor::StrategyKind;

use crate::backend;
use crate::config::Experiment;
use crate::error::Error;
use crate::plan::{self, Configuration, Plan};
use crate::run::provenance::Provenance;
use crate::run::trial::Timing;
use crate::run::{CONFIG_COPY, worker_request};

/// The phases counted, with the name of the function each runs in (`run::trial`).
const PHASES: [(&str, &str); 2] = [("build", "bvhlab_phase_build"), ("trace", "bvhlab_phase_trace")];

/// The simulated caches of `--cache-sim` (size, associativity, line), fixed so the misses do not depend on the
/// machine's own caches: 32 KiB 8-way L1s and an 8 MiB 16-way last level, 64-byte lines.
const CACHES: [&str; 3] = ["--I1=32768,8,64", "--D1=32768,8,64", "--LL=8388608,16,64"];

/// What `harness instructions` was asked.
pub struct CountRequest<'a> {
    pub config: &'a Path,
    pub quick: bool,
    /// The run folder to write to (default: `results/<name>/`, or `results/<name>-quick/` with `quick`).
    pub out: Option<PathBuf>,
    /// Also simulate caches (D1 and last-level misses); about 1.3–2.2× slower.
    pub cache_sim: bool,
    /// Count at this image size instead of each configuration's own (recorded on every row).
    pub image: Option<(u32, u32)>,
    /// Valgrind processes at once.
    pub jobs: usize,
}

/// Whether a configuration's phases run in the one thread callgrind follows: `None` if counted, else why not.
pub(crate) fn uncountable(c: &Configuration) -> Option<&'static str> {
    let s = &c.settings;
    if backend::of(s.accel).own_threads(s) {
        Some("the backend's own threads")
    } else if s.strategy == StrategyKind::MpscThreads {
        Some("mpsc-threads")
    } else if s.strategy().threads > 1 {
        Some("more than one thread")
    } else {
        None
    }
}

/// Counts every countable configuration of the experiment and writes `instructions.csv`.
pub fn run(request: &CountRequest<'_>) -> Result<(), Error> {
    let exp = Experiment::load(request.config)?;
    let exp = if request.quick { exp.quick() } else { exp };
    let mut plan = Plan::new(&exp, crate::plan::available_threads())?;
    plan.skip_unavailable(&exp.path.display().to_string(), false)?;
    let valgrind = valgrind_version()?;
    let dir = request.out.clone().unwrap_or_else(|| crate::run::default_dir(&exp, request.quick));
    let io = |what: &str, p: &Path, e: std::io::Error| Error::Run(format!("{}: cannot {what}: {e}", p.display()));
    let copy = dir.join(CONFIG_COPY);
    match std::fs::read_to_string(&copy) {
        Ok(text) if text != exp.text => {
            return Err(Error::Input(format!(
                "{}: holds a run of another config than {}; count into another folder (--out)",
                dir.display(),
                exp.path.display()
            )));
        }
        Ok(_) => {}
        Err(_) => {
            std::fs::create_dir_all(&dir).map_err(|e| io("create", &dir, e))?;
            std::fs::write(&copy, &exp.text).map_err(|e| io("write", &copy, e))?;
        }
    }
    let dumps = dir.join("callgrind");
    let _ = std::fs::remove_dir_all(&dumps);
    std::fs::create_dir_all(&dumps).map_err(|e| io("create", &dumps, e))?;

    let mut skipped: BTreeMap<&str, Vec<String>> = BTreeMap::new();
    let mut todo: Vec<&Configuration> = Vec::new();
    for c in plan.runnable() {
        match uncountable(c) {
            Some(why) => skipped.entry(why).or_default().push(format!("{} objects {}", c.series, c.settings.objects)),
            None => todo.push(c),
        }
    }
    for (why, configs) in &skipped {
        note!("not counted ({why}): {}", configs.join(", "));
    }
    if todo.is_empty() {
        return Err(Error::Input(format!("{}: no single-thread configuration to count", exp.path.display())));
    }
    let exe = std::env::current_exe().map_err(|e| Error::Run(format!("cannot find the harness executable: {e}")))?;
    let provenance = Provenance::collect();
    let started = Instant::now();
    let how = How { image: request.image, cache_sim: request.cache_sim };
    let results = count_each(&exe, &plan, &todo, how, &dumps, request.jobs);
    let mut counts = Vec::new();
    for (c, result) in todo.iter().zip(results) {
        let (phases, _) = result?;
        counts.extend(phases.map(|(phase, ir, misses)| InstructionCount {
            config_id: c.id.clone(),
            series: c.series.clone(),
            objects: c.settings.objects,
            width: image_settings(c, request.image).width,
            height: image_settings(c, request.image).height,
            phase: phase.to_string(),
            instructions: ir,
            d1_misses: misses.map(|m| m.0),
            ll_misses: misses.map(|m| m.1),
            rustc: provenance.rustc.clone(),
            target_features: provenance.machine.target_features.clone(),
            valgrind: valgrind.clone(),
            git_commit: provenance.git_commit.clone(),
            git_dirty: provenance.git_dirty,
        }));
    }
    let path = dir.join(instructions::FILE);
    instructions::write(&path, &counts).map_err(|e| Error::Run(e.to_string()))?;
    say!(
        "instructions: {} phases of {} configurations counted in {:.0} s with {valgrind}{}: {}",
        counts.len(),
        todo.len(),
        started.elapsed().as_secs_f64(),
        if request.cache_sim { " (simulated caches)" } else { "" },
        path.display()
    );
    Ok(())
}

/// How configurations are counted: at their own image size or `image`, with or without simulated caches.
#[derive(Clone, Copy, Debug)]
pub(crate) struct How {
    pub image: Option<(u32, u32)>,
    pub cache_sim: bool,
}

/// One configuration's counted phases and the worker's answer (its answer hash and tree statistics).
pub(crate) type Counted = Result<(PhaseCounts, Timing), Error>;

/// Counts each of `todo` with the harness binary `exe` (its `worker`), `jobs` valgrind processes at once, longest
/// first; the results in `todo`'s order, each printed as it finishes.
pub(crate) fn count_each(
    exe: &Path,
    plan: &Plan,
    todo: &[&Configuration],
    how: How,
    dumps: &Path,
    jobs: usize,
) -> Vec<Counted> {
    // Longest first, so the jobs finish together.
    let cores = crate::plan::available_threads();
    let mut order: Vec<usize> = (0..todo.len()).collect();
    let estimate = |i: usize| plan::estimate_seconds(&image_settings(todo[i], how.image), cores);
    order.sort_by(|a, b| estimate(*b).total_cmp(&estimate(*a)));
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Counted>>> = Mutex::new((0..todo.len()).map(|_| None).collect());
    let job = || {
        loop {
            let n = next.fetch_add(1, Ordering::SeqCst);
            let Some(&i) = order.get(n) else { break };
            let c = todo[i];
            let t = Instant::now();
            let counted = count_one(exe, plan, c, how, dumps);
            match &counted {
                Ok(([(_, build, _), (_, trace, _)], _)) => note!(
                    "counted {} objects {}: build {build} trace {trace} instructions ({:.1} s)",
                    c.series,
                    c.settings.objects,
                    t.elapsed().as_secs_f64()
                ),
                Err(e) => note!("FAILED {} objects {}: {e}", c.series, c.settings.objects),
            }
            results.lock().expect("no job panics")[i] = Some(counted);
        }
    };
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, todo.len().max(1)) {
            scope.spawn(job);
        }
    });
    results.into_inner().expect("no job panics").into_iter().map(|r| r.expect("every configuration ran")).collect()
}

/// The settings a configuration is counted with (at `image`, when given).
fn image_settings(c: &Configuration, image: Option<(u32, u32)>) -> schema::Settings {
    let mut s = c.settings.clone();
    if let Some((width, height)) = image {
        (s.width, s.height) = (width, height);
    }
    s
}

/// `valgrind --version`, or why valgrind cannot be used.
pub fn valgrind_version() -> Result<String, Error> {
    let missing = |why: String| {
        Error::Input(format!(
            "valgrind is needed to count instructions ({why}); Debian/Ubuntu: apt-get install valgrind"
        ))
    };
    let out = Command::new("valgrind").arg("--version").output().map_err(|e| missing(e.to_string()))?;
    if !out.status.success() {
        return Err(missing(format!("`valgrind --version` exited with {}", out.status)));
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// Instructions, and (with a cache simulation) D1 and last-level misses, of each phase.
pub(crate) type PhaseCounts = [(&'static str, u64, Option<(u64, u64)>); 2];

/// Runs one configuration in a worker under callgrind; returns its phases' counts. The dumps stay in `dumps`
/// as `<config id>-<phase>.callgrind` (for `callgrind_annotate`).
fn count_one(exe: &Path, plan: &Plan, c: &Configuration, how: How, dumps: &Path) -> Counted {
    let mut worker = worker_request(plan, c);
    worker.settings = image_settings(c, how.image);
    worker.sample_s = 0.0; // one pass: instruction counts are per pass, and callgrind's clock is not the machine's
    let out = dumps.join(format!("{}.callgrind", c.id));
    let mut cmd = Command::new("valgrind");
    cmd.arg("--tool=callgrind")
        .arg(format!("--callgrind-out-file={}", out.display()))
        .arg("--collect-atstart=no")
        .args(PHASES.iter().map(|(_, f)| format!("--toggle-collect=*{f}*")))
        .args(PHASES.iter().map(|(_, f)| format!("--dump-after=*::{f}*")));
    if how.cache_sim {
        cmd.arg("--cache-sim=yes").args(CACHES);
    }
    cmd.arg(exe).arg("worker").stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped());
    let fail = |why: String| Error::Run(format!("{} objects {}: callgrind: {why}", c.series, c.settings.objects));
    let mut child = cmd.spawn().map_err(|e| fail(format!("cannot start valgrind: {e}")))?;
    let json = crate::run::worker::request_line(&worker);
    {
        let mut stdin = child.stdin.take().expect("piped");
        writeln!(stdin, "{json}").map_err(|e| fail(format!("cannot send the request: {e}")))?;
    } // end of input: the worker answers and exits
    let output = child.wait_with_output().map_err(|e| fail(e.to_string()))?;
    let answered = String::from_utf8_lossy(&output.stdout);
    let timing = match serde_json::from_str::<Timing>(answered.trim()) {
        Ok(timing) if output.status.success() => timing,
        _ => {
            let stderr = String::from_utf8_lossy(&output.stderr);
            let last: Vec<&str> = stderr.lines().filter(|l| !l.starts_with("==")).collect();
            return Err(fail(format!("the worker failed ({}): {}", output.status, last.join(" ").trim())));
        }
    };
    // Dumps `out.1`, `out.2`, … in the order the phases ended; `out` itself is the (empty) final dump.
    let mut found: Vec<Option<DumpTotals>> = vec![None; PHASES.len()];
    for part in 1.. {
        let path = PathBuf::from(format!("{}.{part}", out.display()));
        let Ok(text) = std::fs::read_to_string(&path) else { break };
        let (trigger, events) = parse_dump(&text).map_err(|why| fail(format!("{}: {why}", path.display())))?;
        let Some(p) = PHASES.iter().position(|(_, f)| trigger.contains(&format!("::{f}"))) else {
            return Err(fail(format!("{}: unexpected dump trigger {trigger:?}", path.display())));
        };
        if found[p].is_some() {
            return Err(fail(format!("{} ran more than once in one request", PHASES[p].1)));
        }
        found[p] = Some(events);
        let kept = dumps.join(format!("{}-{}.callgrind", c.id, PHASES[p].0));
        std::fs::rename(&path, &kept).map_err(|e| fail(format!("{}: {e}", kept.display())))?;
    }
    let _ = std::fs::remove_file(&out);
    let mut counts: PhaseCounts = [("", 0, None); 2];
    for (p, (phase, function)) in PHASES.iter().enumerate() {
        let Some((ir, misses)) = found[p] else {
            return Err(fail(format!(
                "no dump after {function} (is the binary stripped of its symbols, or was the function inlined?)"
            )));
        };
        counts[p] = (phase, ir, misses);
    }
    Ok((counts, timing))
}

/// A callgrind dump's instructions and, with a cache simulation, its (D1 misses, last-level misses).
type DumpTotals = (u64, Option<(u64, u64)>);

/// The trigger and the totals of a callgrind dump: `Ir`, and with a cache simulation D1 misses (`D1mr + D1mw`)
/// and last-level misses (`ILmr + DLmr + DLmw`).
fn parse_dump(text: &str) -> Result<(String, DumpTotals), String> {
    let line = |key: &str| text.lines().find_map(|l| l.strip_prefix(key)).map(str::trim);
    let trigger = line("desc: Trigger:").ok_or("no trigger")?.to_string();
    let events: Vec<&str> = line("events:").ok_or("no events line")?.split_whitespace().collect();
    let totals = line("summary:").or_else(|| line("totals:")).ok_or("no summary line")?;
    let values: Vec<u64> = totals
        .split_whitespace()
        .map(|v| v.parse().map_err(|_| format!("bad total {v:?}")))
        .collect::<Result<_, _>>()?;
    let event = |name: &str| events.iter().position(|e| *e == name).map(|i| values.get(i).copied().unwrap_or(0));
    let ir = event("Ir").ok_or("no Ir event")?;
    let misses = match (event("D1mr"), event("D1mw"), event("ILmr"), event("DLmr"), event("DLmw")) {
        (Some(a), Some(b), Some(c), Some(d), Some(e)) => Some((a + b, c + d + e)),
        _ => None,
    };
    Ok((trigger, (ir, misses)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dumps_are_read_with_and_without_a_cache_simulation() {
        let plain = "version: 1\ncreator: callgrind-3.19.0\npart: 1\ndesc: Trigger: --dump-after=harness::backend::workload::bvhlab_phase_build\n\
                     events: Ir\nsummary: 587159\n\nfl=x\n\ntotals: 587159\n";
        assert_eq!(
            parse_dump(plain).unwrap(),
            ("--dump-after=harness::backend::workload::bvhlab_phase_build".to_string(), (587_159, None))
        );
        let cached = "desc: Trigger: --dump-after=harness::backend::workload::bvhlab_phase_trace\n\
                      events: Ir Dr Dw I1mr D1mr D1mw ILmr DLmr DLmw\n\
                      summary: 1352098363 92225131 26051 30 7702976 7925 30 1 385\n";
        assert_eq!(parse_dump(cached).unwrap().1, (1_352_098_363, Some((7_702_976 + 7925, 30 + 1 + 385))));
        assert!(parse_dump("events: Ir\nsummary: 1\n").unwrap_err().contains("trigger"));
    }
}
