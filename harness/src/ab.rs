//! `harness ab`: the trustworthy comparison on a noisy machine. Builds another git revision in a worktree,
//! then times every configuration with both builds in one job, interleaved (A B, then B A, round after
//! round), each run in a fresh `harness worker` process, and reports each configuration's time ratio
//! new/old with a 95% bootstrap interval.

use std::path::{Path, PathBuf};
use std::process::Command;

use report::stats::{Estimate, ratio_ci, seed_for};

use crate::config::Experiment;
use crate::error::Error;
use crate::plan::Plan;
use crate::run::{self, worker};

/// What `harness ab` was asked.
pub struct AbRequest<'a> {
    pub base: &'a str,
    pub config: &'a Path,
    pub quick: bool,
    pub min_effect: f64,
}

fn git(root: &Path, args: &[&str]) -> Result<String, Error> {
    let out = Command::new("git").current_dir(root).args(args).output().map_err(|e| Error::Run(format!("git: {e}")))?;
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
    } else {
        Err(Error::Input(format!("git {}: {}", args.join(" "), String::from_utf8_lossy(&out.stderr).trim().lines().next().unwrap_or(""))))
    }
}

/// Builds `rev` in a worktree under `target/ab/` (its own target folder, so the running binary is never
/// replaced) and returns the path of its harness binary.
fn build_base(root: &Path, rev: &str) -> Result<PathBuf, Error> {
    let ab = root.join("target").join("ab");
    let tree = ab.join(format!("tree-{}", &rev[..12]));
    if !tree.join("Cargo.toml").is_file() {
        let _ = std::fs::remove_dir_all(&tree);
        git(root, &["worktree", "add", "--detach", "--force", tree.to_str().expect("utf-8 path"), rev])?;
    }
    eprintln!("ab: building {rev} in {}", tree.display());
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(&tree)
        .env("CARGO_TARGET_DIR", ab.join("target"))
        .args(["build", "--release", "-q", "-p", "harness"])
        .status()
        .map_err(|e| Error::Run(format!("cargo: {e}")))?;
    if !status.success() {
        return Err(Error::Run(format!("building {rev} failed")));
    }
    Ok(ab.join("target").join("release").join("harness"))
}

/// A configuration's samples from both builds.
struct Pair {
    old: Vec<f64>,
    new: Vec<f64>,
    same_output: bool,
}

/// Runs the comparison; fails (exit 1) on a significant single-thread regression beyond `min_effect`.
pub fn run(request: &AbRequest<'_>) -> Result<(), Error> {
    let exp = Experiment::load(request.config)?;
    let exp = if request.quick { exp.quick() } else { exp };
    let plan = Plan::new(&exp, crate::render::available_threads())?;
    let root = PathBuf::from(git(Path::new("."), &["rev-parse", "--show-toplevel"])?);
    let rev = git(&root, &["rev-parse", "--verify", &format!("{}^{{commit}}", request.base)])?;
    let old_bin = build_base(&root, &rev)?;
    let new_bin = std::env::current_exe().map_err(|e| Error::Run(format!("cannot find the harness executable: {e}")))?;
    let mut pairs: Vec<Pair> = plan.configurations.iter().map(|_| Pair { old: vec![], new: vec![], same_output: true }).collect();
    let rounds = exp.warmups + exp.repetitions;
    for round in 0..rounds {
        for (c, pair) in plan.configurations.iter().zip(&mut pairs) {
            let old_first = round % 2 == 0;
            let (first, second) = if old_first { (&old_bin, &new_bin) } else { (&new_bin, &old_bin) };
            let job = run::worker_request(&plan, c);
            let a = worker::time(first, Some(&root), &job)?;
            let b = worker::time(second, Some(&root), &job)?;
            let (old, new) = if old_first { (a, b) } else { (b, a) };
            pair.same_output &= old.output_hash == new.output_hash;
            if round >= exp.warmups {
                pair.old.push(old.trace_s);
                pair.new.push(new.trace_s);
            }
        }
        eprintln!("ab: round {}/{rounds} done", round + 1);
    }
    println!("## A/B: {} (new, this build) against {} (old, {})\n", exp.name, &rev[..12], request.base);
    println!("Trace time per configuration, new / old (below 1: faster), 95% bootstrap interval; {} rounds, interleaved.\n", exp.repetitions);
    println!("| series | settings | old median (s) | new median (s) | new / old [95% CI] | verdict | output |");
    println!("|---|---|---|---|---|---|---|");
    let mut regressed = false;
    for (c, pair) in plan.configurations.iter().zip(&pairs) {
        let e: Estimate = ratio_ci(&pair.new, &pair.old, seed_for(&c.id));
        let (slower, faster) = (e.lo > 1.0 && e.value > 1.0 + request.min_effect, e.hi < 1.0 && e.value < 1.0 - request.min_effect);
        let gating = c.settings.strategy().threads == 1;
        let verdict = match (slower, faster) {
            (true, _) if gating => "**regressed**",
            (true, _) => "slower (not gating: threads > 1)",
            (_, true) => "improved",
            _ => "unchanged",
        };
        regressed |= slower && gating;
        let s = &c.settings;
        println!(
            "| {} | {} objects {} {} | {:.6} | {:.6} | {:.3} [{:.3}, {:.3}] | {verdict} | {} |",
            c.series,
            schema::Named::name(s.scene),
            s.objects,
            s.strategy(),
            report::stats::median(&pair.old),
            report::stats::median(&pair.new),
            e.value,
            e.lo,
            e.hi,
            if pair.same_output { "same" } else { "differs" }
        );
    }
    if regressed {
        return Err(Error::Run("a single-thread configuration is significantly slower than the base revision".into()));
    }
    Ok(())
}
