//! `harness reproduce results/NAME`: re-runs a committed result set from the commit its rows record (built as `ab`
//! builds its base), or with today's code (`--at HEAD`), on this machine, into
//! `results/NAME/reproductions/<date>-<machine_id>[-head][-quick]/`, and judges whether it reproduces
//! ([`report::reproduction`]): deterministic columns identical, claims and time ratios within the resolution. The
//! recorded rows are only read.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use report::distinct;
use report::reproduction::{self, Outcome, short_commit as short};

use crate::ab::build::{Build, Worktree, base_binary, git};
use crate::cli::{ReproduceArgs, ReproduceAt};
use crate::config::Experiment;
use crate::error::Error;
use crate::rows::read_log;
use crate::run::{CONFIG_COPY, RUNS_CSV, provenance};

/// The one commit and machine a result set was recorded with.
struct Origin {
    commit: String,
    machine: String,
    /// Whether the tree had uncommitted changes (then no commit holds the code that recorded the rows).
    dirty: bool,
    /// Whether the rows were timed on transparent huge pages (`huge_pages` `malloc` or `always`).
    huge_pages: bool,
}

/// Where a result set was recorded, or why it cannot be reproduced.
fn recorded_origin(dir: &Path) -> Result<Origin, Error> {
    let runs = dir.join(RUNS_CSV);
    let rows = read_log(&runs)?;
    if rows.is_empty() {
        return Err(Error::Input(format!("{}: no rows recorded (allowed: a result set with rows)", runs.display())));
    }
    let commits = distinct(rows.iter().map(|r| r.git_commit.clone()));
    let machines = distinct(rows.iter().map(|r| r.machine_id.clone()));
    if commits.len() > 1 {
        return Err(Error::Input(format!(
            "{}: git_commit: the rows mix {} commits ({}): a result set reproduces from one (allowed: rows of one commit)",
            runs.display(),
            commits.len(),
            commits.iter().map(|c| short(c)).collect::<Vec<_>>().join(", ")
        )));
    }
    if machines.len() > 1 {
        return Err(Error::Input(format!(
            "{}: machine_id: the rows mix {} machines ({}): their times cannot be one result (allowed: rows of one \
             machine)",
            runs.display(),
            machines.len(),
            machines.join(", ")
        )));
    }
    Ok(Origin {
        commit: commits[0].clone(),
        machine: machines[0].clone(),
        dirty: rows.iter().any(|r| r.git_dirty),
        huge_pages: rows.iter().any(|r| matches!(r.huge_pages.as_str(), "malloc" | "always")),
    })
}

/// Runs `cmd` (a `harness run`) on the pages the rows were recorded on: glibc's huge-page tunables set or removed (a
/// harness older than the `huge_pages` column keeps what it is given), and the flag that tells a harness which have
/// one, read from its `cli.rs` (`cli_source`): `--huge-pages`, or `--small-pages` where 6fa44aa and d131eb6 put them
/// on by default.
fn on_recorded_pages(cmd: &mut Command, cli_source: &str, huge: bool) {
    crate::pages::set_tunable(cmd, huge);
    if huge && cli_source.contains("pub huge_pages: bool") {
        cmd.arg("--huge-pages");
    } else if !huge && cli_source.contains("pub small_pages: bool") {
        cmd.arg("--small-pages");
    }
}

/// The result set's config as committed with its rows: `experiment.toml` as of the commit that last changed
/// `runs.csv` (a later commit may have added figures to it, which the recorded commit's harness would refuse to
/// read), or the file as it is where the rows are not committed as they are. Returns the text and where it is from.
fn config_as_recorded(root: &Path, dir: &Path) -> Result<(String, String), Error> {
    let working = || {
        std::fs::read_to_string(dir.join(CONFIG_COPY))
            .map(|text| (text, "it is in the result set (its rows are not committed as they are)".to_string()))
            .map_err(|e| Error::Input(format!("{}: cannot read: {e}", dir.join(CONFIG_COPY).display())))
    };
    let Ok(rel) = dir.strip_prefix(root) else { return working() };
    let (runs, config) = (rel.join(RUNS_CSV), rel.join(CONFIG_COPY));
    let (runs, config) = (runs.to_string_lossy(), config.to_string_lossy());
    let changed = git(root, &["status", "--porcelain", "--", &runs, &config]).unwrap_or_else(|_| "?".into());
    let commit = git(root, &["log", "-1", "--format=%H", "--", &runs]).unwrap_or_default();
    if !changed.is_empty() || commit.is_empty() {
        return working();
    }
    let text = git(root, &["show", &format!("{commit}:{config}")])?;
    Ok((text + "\n", format!("committed with the rows ({config} at {})", short(&commit))))
}

/// A folder name not yet taken under `parent`: `name`, else `name-2`, `name-3`, …
fn fresh(parent: &Path, name: &str) -> PathBuf {
    (1..)
        .map(|i| parent.join(if i == 1 { name.to_string() } else { format!("{name}-{i}") }))
        .find(|p| !p.exists())
        .expect("a free name")
}

/// `harness reproduce`.
pub fn run(args: &ReproduceArgs) -> Result<(), Error> {
    let dir = std::path::absolute(&args.dir).unwrap_or_else(|_| args.dir.clone());
    let config = dir.join(CONFIG_COPY);
    if !dir.join(RUNS_CSV).is_file() || !config.is_file() {
        return Err(Error::Input(format!(
            "{}: not a result set: it needs {RUNS_CSV} and {CONFIG_COPY} (allowed: a folder `harness run` wrote, e.g. \
             results/paper)",
            args.dir.display()
        )));
    }
    let Origin { commit, machine, dirty, huge_pages } = recorded_origin(&dir)?;
    let root = PathBuf::from(git(Path::new("."), &["rev-parse", "--show-toplevel"])?);
    if args.at == ReproduceAt::Recorded {
        let exists = Command::new("git")
            .current_dir(&root)
            .args(["cat-file", "-e", &format!("{commit}^{{commit}}")])
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !exists {
            return Err(Error::Input(format!(
                "{}: git_commit: {commit} is not a commit of this repository (allowed: a result set recorded at one \
                 of its commits; fetch the history, e.g. `git fetch --unshallow`; `--at HEAD` runs today's code)",
                dir.join(RUNS_CSV).display()
            )));
        }
        if dirty {
            return Err(Error::Input(format!(
                "{}: git_dirty: the rows were recorded with uncommitted changes, so no commit holds their code \
                 (allowed: rows of a clean tree; `--at HEAD` re-runs the config with today's code)",
                dir.join(RUNS_CSV).display()
            )));
        }
    }
    // Today's reading of the config: its claims and series are what the two row sets are judged by.
    let exp = Experiment::load(&config)?;
    let exp = if args.quick { exp.quick() } else { exp };

    let here = provenance::Provenance::collect();
    // The recorded commit's harness runs in a checkout of that commit: its rows record the commit (the harness reads
    // it from the folder it runs in), and the config's relative paths mean what they meant then.
    let mut checkout: Option<Worktree<'_>> = None;
    let (binary, at, cli_source) = match args.at {
        ReproduceAt::Recorded => {
            let build = Build::running()?;
            let binary = base_binary(&root, &build, &commit)?;
            let path = build.target.join("ab").join(format!("reproduce-{}-{}", short(&commit), std::process::id()));
            checkout = Some(Worktree::add(&root, path, &commit)?);
            let cli = git(&root, &["show", &format!("{commit}:harness/src/cli.rs")]).unwrap_or_default();
            (binary, format!("recorded commit {}", short(&commit)), cli)
        }
        ReproduceAt::Head => (
            std::env::current_exe().map_err(|e| Error::Run(format!("cannot find the harness executable: {e}")))?,
            format!(
                "HEAD ({}{})",
                short(&here.git_commit),
                if here.git_dirty { ", with uncommitted changes" } else { "" }
            ),
            include_str!("cli.rs").to_string(),
        ),
    };
    let date = provenance::timestamp_now().chars().take(10).collect::<String>();
    let name = format!(
        "{date}-{}{}{}",
        here.machine.machine_id,
        if args.at == ReproduceAt::Head { "-head" } else { "" },
        if args.quick { "-quick" } else { "" }
    );
    let out = match &args.out {
        Some(out) => std::path::absolute(out).unwrap_or_else(|_| out.clone()),
        None => fresh(&dir.join(reproduction::FOLDER), &name),
    };
    if out.join(RUNS_CSV).exists() {
        return Err(Error::Input(format!(
            "{}: --out already holds rows (allowed: a folder without {RUNS_CSV}; by default a new one is chosen)",
            out.display()
        )));
    }
    say!(
        "reproduce: {} (recorded at {} on {machine}) with the harness of {at}, into {}",
        args.dir.display(),
        short(&commit),
        out.display()
    );
    // The recorded commit's harness runs the config as committed with the rows, in its checkout.
    let run_config = match &checkout {
        Some(checkout) => {
            let (text, from) = config_as_recorded(&root, &dir)?;
            let rel = dir.strip_prefix(&root).unwrap_or(Path::new("results/reproduced"));
            let path = checkout.path.join(rel).join(CONFIG_COPY);
            std::fs::create_dir_all(path.parent().expect("a folder"))
                .and_then(|()| std::fs::write(&path, text))
                .map_err(|e| Error::Run(format!("{}: {e}", path.display())))?;
            say!("reproduce: the config as {from}");
            path
        }
        None => config.clone(),
    };
    let mut cmd = Command::new(&binary);
    cmd.current_dir(checkout.as_ref().map_or(root.as_path(), |c| c.path.as_path()))
        .arg("run")
        .arg(&run_config)
        .arg("--out")
        .arg(&out)
        .stdin(Stdio::null());
    if args.quick {
        cmd.arg("--quick");
    }
    on_recorded_pages(&mut cmd, &cli_source, huge_pages);
    let status = cmd.status().map_err(|e| Error::Run(format!("{}: {e}", binary.display())))?;
    if !status.success() {
        return Err(Error::Run(format!(
            "the harness of {at} could not run {} ({status}); nothing recorded was touched",
            config.display()
        )));
    }

    drop(checkout);
    let spec = exp.report_spec(vec![]);
    let result = reproduction::compare(&dir, &out, &spec).map_err(|e| Error::Run(e.to_string()))?;
    let how = vec![
        format!(
            "command: `harness reproduce {}{}{}` on {}",
            args.dir.display(),
            if args.at == ReproduceAt::Head { " --at HEAD" } else { "" },
            if args.quick { " --quick" } else { "" },
            provenance::timestamp_now()
        ),
        format!(
            "the harness of {at} ran `{}`{}",
            config.display(),
            if args.quick { " with its [quick] overrides" } else { "" }
        ),
    ];
    reproduction::write(&out, &result, &args.dir.display().to_string(), &how).map_err(|e| Error::Run(e.to_string()))?;
    // The result set's report lists its reproductions (its rows stay as they were).
    if dir.join("REPORT.md").is_file() {
        reproduction::update_report(&dir).map_err(|e| Error::Run(e.to_string()))?;
    }
    for c in &result.claims {
        say!("claim {:<15} {} (then {}, now {}): {}", c.outcome.word(), c.text, c.recorded, c.reproduced, c.reason);
    }
    say!(
        "deterministic columns: {} configurations compared, {} differences{}",
        result.configurations_compared,
        result.differences.len(),
        if result.not_comparable.is_empty() {
            String::new()
        } else {
            format!("; not comparable: {}", result.not_comparable.join("; "))
        }
    );
    for line in result.differences.iter().take(10) {
        say!("  differs: {line}");
    }
    let count = |o: Outcome| result.points.iter().filter(|p| p.outcome == o).count();
    say!(
        "time ratios: {} of {} reproduced, {} moved, {} not comparable (no interval on one side)",
        count(Outcome::Reproduced),
        result.points.len(),
        count(Outcome::NotReproduced),
        count(Outcome::NotComparable)
    );
    say!("reproduce: {} ({})", result.headline(), out.join(reproduction::MARKDOWN).display());
    let failed = if args.timings_for_information {
        !result.differences.is_empty()
    } else {
        result.outcome() == Outcome::NotReproduced
    };
    if failed {
        return Err(Error::Run(format!(
            "{} did not reproduce{} (see {})",
            args.dir.display(),
            if args.timings_for_information { ": its deterministic columns differ" } else { "" },
            out.join(reproduction::MARKDOWN).display()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(cli_source: &str, huge: bool) -> Vec<String> {
        let mut cmd = Command::new("harness");
        on_recorded_pages(&mut cmd, cli_source, huge);
        cmd.get_args().map(|a| a.to_string_lossy().into_owned()).collect()
    }

    #[test]
    fn the_recorded_harness_gets_the_flag_its_cli_has() {
        let today = include_str!("cli.rs");
        assert_eq!(flags(today, true), ["--huge-pages"]);
        assert!(flags(today, false).is_empty(), "small pages are the default");
        // 6fa44aa and d131eb6 put huge pages on unless told `--small-pages`.
        let on_by_default = "    /// ...\n    #[arg(long, global = true)]\n    pub small_pages: bool,\n";
        assert_eq!(flags(on_by_default, false), ["--small-pages"]);
        assert!(flags(on_by_default, true).is_empty());
        // Older harnesses have neither: the tunables alone.
        assert!(flags("", true).is_empty() && flags("", false).is_empty());
    }
}
