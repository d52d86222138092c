//! Sharded sweeps as a cluster runs them: `--shard env`, `slurm submit` and `resubmit` against a fake `sbatch`,
//! and `merge` refusing what must not be merged. The real one-node Slurm run is `.ci/slurm-test`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::{harness, stderr, temp};

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A config of milliseconds: 2 object counts × 2 seeds = 4 scene cells, 2 series, 2 repetitions.
const TINY: &str = "name = \"tiny\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nreference = \"list\"\nrepetitions = 2\n[sweep]\nobjects = [10, 20]\nseed = [1, 2]\n\
                    workload = \"primary\"\nwidth = 16\nheight = 12\n[[series]]\nlabel = \"list\"\naccel = \"list\"\n\
                    [[series]]\nlabel = \"flat\"\naccel = \"flat-bvh\"\n";

fn tiny(dir: &Path) -> PathBuf {
    let path = dir.join("tiny.toml");
    std::fs::write(&path, TINY).unwrap();
    path
}

/// Runs `harness run CONFIG --shard I/N --out RUN` (into `RUN/shard-I-of-N/`) for every shard.
fn run_shards(config: &Path, run: &Path, n: usize) {
    for i in 1..=n {
        let o =
            harness().arg("run").arg(config).args(["--shard", &format!("{i}/{n}"), "--out"]).arg(run).output().unwrap();
        assert!(o.status.success(), "shard {i}: {}", stderr(&o));
        assert!(run.join(format!("shard-{i}-of-{n}/runs.csv")).is_file(), "shard {i} ran into its shard folder");
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap().flatten() {
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target)
        } else {
            std::fs::copy(entry.path(), target).map(|_| ()).unwrap()
        }
    }
}

fn merge(run: &Path, extra: &[&str]) -> Output {
    harness().arg("merge").arg(run).args(extra).output().unwrap()
}

/// Exit 2, one line, naming `want`, and no merged runs.csv.
fn refused(o: &Output, run: &Path, want: &str) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "one line: {e}");
    assert!(e.contains(want), "{want:?} not in {e}");
    assert!(!run.join("runs.csv").exists(), "nothing written");
}

#[test]
fn shard_env_without_the_variables_is_one_line_exit_2_and_writes_nothing() {
    let dir = temp("env");
    let config = tiny(&dir);
    for (arg, want) in [
        ("env", "--shard env: SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT are not set"),
        ("env/3", "--shard env/3: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set"),
    ] {
        let o = harness()
            .arg("run")
            .arg(&config)
            .args(["--shard", arg, "--out"])
            .arg(dir.join("out"))
            .env_remove("SLURM_ARRAY_TASK_ID")
            .env_remove("SLURM_ARRAY_TASK_COUNT")
            .env_remove("JOB_COMPLETION_INDEX")
            .output()
            .unwrap();
        refused(&o, &dir, want);
        assert!(!dir.join("out").exists());
    }
    // A Kubernetes indexed Job: index 1 of 2 runs shard 2 and records it.
    let out = dir.join("k8s");
    let o = harness()
        .arg("run")
        .arg(&config)
        .args(["--shard", "env/2", "--out"])
        .arg(&out)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env("JOB_COMPLETION_INDEX", "1")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("shard-2-of-2/runs.csv")).unwrap();
    let rows = schema::row::read_rows(&text).unwrap();
    assert!(!rows.is_empty() && rows.iter().all(|r| r.shard == "2/2"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn dry_run_prints_both_scripts_and_writes_nothing() {
    let dir = temp("dry");
    let run = dir.join("run");
    let o = harness()
        .args(["slurm", "submit", "experiments/ci.toml", "--quick", "--shards", "2", "--max-parallel", "1"])
        .args(["--partition", "bench", "--time", "20", "--dry-run", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    let exe = env!("CARGO_BIN_EXE_harness");
    for want in [
        "#SBATCH --array=0-1%1",
        "#SBATCH --exclusive",
        // ci.toml's largest explicit thread count is 1 (serial); its rayon series' `all` takes the whole node.
        "#SBATCH --cpus-per-task=1",
        "#SBATCH --partition=bench",
        "#SBATCH --time=20",
        "#SBATCH --dependency=afterany:<ARRAY_JOB_ID>",
        "--shard env/2 --config-hash ",
        &format!("exec {exe} run "),
        &format!("exec {exe} merge {}", run.display()),
        &format!("#SBATCH --output={}/slurm/logs/shard-task-%a-job-%A.log", run.display()),
    ] {
        assert!(text.contains(want), "missing {want:?} in\n{text}");
    }
    let hash = text.split("--config-hash ").nth(1).unwrap().split(' ').next().unwrap();
    assert!(hash.len() == 16 && hash.chars().all(|c| c.is_ascii_hexdigit()), "{hash}");
    assert!(!run.exists(), "a dry run writes nothing");
    let o = harness()
        .args(["slurm", "submit", "experiments/ci.toml", "--quick", "--shards", "4", "--dry-run"])
        .output()
        .unwrap();
    refused(&o, &dir, "--shards 4: experiments/ci.toml has only 3 scene cells");
    let o = harness()
        .args(["slurm", "submit", "experiments/ci.toml", "--quick", "--shards", "2", "--no-exclusive", "--dry-run"])
        .output()
        .unwrap();
    assert!(o.status.success() && !stdout(&o).contains("--exclusive"), "{}", stdout(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A folder with fake `sbatch` (records its arguments, prints job ids 1001, 1002, …) and `squeue` (prints nothing).
fn fake_slurm(dir: &Path) -> String {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let sbatch = format!(
        "#!/bin/sh\nlog={log}\necho \"$@\" >> \"$log\"\nn=$(wc -l < \"$log\")\necho $((1000 + n))\n",
        log = dir.join("sbatch.log").display()
    );
    for (name, text) in [("sbatch", sbatch.as_str()), ("squeue", "#!/bin/sh\nexit 0\n")] {
        std::fs::write(bin.join(name), text).unwrap();
        Command::new("chmod").arg("+x").arg(bin.join(name)).status().unwrap();
    }
    format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default())
}

#[test]
fn submit_and_resubmit_against_a_fake_sbatch() {
    let dir = temp("submit");
    let (config, run) = (tiny(&dir), dir.join("run"));
    let path = fake_slurm(&dir);
    let submit = || {
        harness()
            .args(["slurm", "submit"])
            .arg(&config)
            .args(["--shards", "2", "--out"])
            .arg(&run)
            .env("PATH", &path)
            .output()
    };
    let o = submit().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("array job 1001 (2 shards, at most 2 at once)") && out.contains("merge job 1002"), "{out}");
    let calls = std::fs::read_to_string(dir.join("sbatch.log")).unwrap();
    let calls: Vec<&str> = calls.lines().collect();
    assert_eq!(
        calls,
        [
            format!("--parsable {}/slurm/job.sbatch", run.display()),
            format!("--parsable {}/slurm/merge.sbatch", run.display())
        ]
    );
    let job = std::fs::read_to_string(run.join("slurm/job.sbatch")).unwrap();
    assert!(job.contains("#SBATCH --array=0-1%2\n"), "{job}");
    let merge = std::fs::read_to_string(run.join("slurm/merge.sbatch")).unwrap();
    assert!(merge.contains("#SBATCH --dependency=afterany:1001\n"), "{merge}");
    let jobs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("slurm/jobs.json")).unwrap()).unwrap();
    assert_eq!(jobs["submissions"][0]["array_job_id"], "1001");
    assert_eq!(jobs["submissions"][0]["merge_job_id"], "1002");
    assert_eq!(jobs["options"]["shards"], 2);
    assert!(run.join("slurm/logs").is_dir());
    // Submitting twice into one folder is refused.
    let o = submit().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("already submitted"), "{}", stderr(&o));

    // Shard 1 ran to the end, shard 2 never started: only task 1 (shard 2) is submitted again.
    let o = harness().arg("run").arg(&config).args(["--shard", "1/2", "--out"]).arg(&run).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let o = harness().args(["slurm", "resubmit"]).arg(&run).env("PATH", &path).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("shard 2 of 2: 8 planned rows missing") && !out.contains("shard 1 of 2"), "{out}");
    assert!(out.contains("array job 1003 (shards 2)") && out.contains("merge job 1004"), "{out}");
    let job = std::fs::read_to_string(run.join("slurm/job.sbatch")).unwrap();
    assert!(job.contains("#SBATCH --array=1%2\n"), "{job}");
    let merge = std::fs::read_to_string(run.join("slurm/merge.sbatch")).unwrap();
    assert!(merge.contains("#SBATCH --dependency=afterany:1003\n"), "{merge}");
    let jobs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("slurm/jobs.json")).unwrap()).unwrap();
    assert_eq!(jobs["submissions"][1]["tasks"], serde_json::json!([1]));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn merge_equals_the_unsharded_run_and_refuses_bad_shards() {
    let dir = temp("merge");
    let config = tiny(&dir);
    let good = dir.join("good");
    run_shards(&config, &good, 3);
    let whole = dir.join("whole");
    let o = harness().arg("run").arg(&config).arg("--out").arg(&whole).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));

    let run = dir.join("merged");
    copy_dir(&good, &run);
    let o = merge(&run, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("merged 16 rows of 3 shards"), "{}", stdout(&o));
    assert!(run.join("REPORT.md").is_file() && run.join("summary.csv").is_file());
    let o = harness().arg("rows-diff").arg(&run).arg(&whole).arg("--ignore-timing").output().unwrap();
    assert!(o.status.success(), "{}{}", stdout(&o), stderr(&o));
    assert!(stdout(&o).contains("equal: 16 rows each"), "{}", stdout(&o));
    let o = harness().arg("rows-diff").arg(&run).arg(&whole).output().unwrap();
    assert_eq!(o.status.code(), Some(1), "timings differ between runs: {}", stdout(&o));

    // Each case: a fresh copy of the good shards, one thing broken.
    let case = |name: &str, breaks: &dyn Fn(&Path)| -> PathBuf {
        let run = dir.join(name);
        copy_dir(&good, &run);
        breaks(&run);
        run
    };
    let edit = |path: PathBuf, f: &dyn Fn(String) -> String| {
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, f(text)).unwrap();
    };
    let first_row = |run: &Path, i: usize| {
        std::fs::read_to_string(run.join(format!("shard-{i}-of-3/runs.csv")))
            .unwrap()
            .lines()
            .nth(1)
            .unwrap()
            .to_string()
    };

    let run = case("missing", &|r| std::fs::remove_dir_all(r.join("shard-2-of-3")).unwrap());
    refused(&merge(&run, &[]), &run, "shard 2 of 3 is missing");

    let run = case("duplicate", &|r| {
        let row = first_row(r, 1);
        edit(r.join("shard-1-of-3/runs.csv"), &|t| format!("{t}{row}\n"));
    });
    refused(&merge(&run, &[]), &run, "duplicate row");

    let run = case("wrong-shard", &|r| {
        let row = first_row(r, 1);
        edit(r.join("shard-2-of-3/runs.csv"), &|t| format!("{t}{row}\n"));
    });
    refused(&merge(&run, &[]), &run, "belongs to shard 1 of 3, not 2");

    let run = case("incomplete", &|r| {
        edit(r.join("shard-3-of-3/runs.csv"), &|t| {
            let mut lines: Vec<&str> = t.lines().collect();
            lines.pop();
            lines.join("\n") + "\n"
        })
    });
    refused(&merge(&run, &[]), &run, "shard 3 of 3 lacks 1 of its");

    let commit = |r: &Path| {
        schema::row::read_rows(&std::fs::read_to_string(r.join("shard-1-of-3/runs.csv")).unwrap()).unwrap()[0].clone()
    };
    let row = commit(&good);
    let run = case("commits", &|r| edit(r.join("shard-2-of-3/runs.csv"), &|t| t.replace(&row.git_commit, "0badc0de")));
    refused(&merge(&run, &[]), &run, "shards come from different commits");

    let run = case("pages", &|r| {
        edit(r.join("shard-2-of-3/runs.csv"), &|t| {
            let mut rows = schema::row::read_rows(&t).unwrap();
            rows.iter_mut().for_each(|row| row.huge_pages = "always".into());
            schema::row::header()
                + "\n"
                + &rows.iter().map(|row| schema::row::csv_line(row).unwrap()).collect::<String>()
        })
    });
    refused(&merge(&run, &[]), &run, "shards come from different pages: huge_pages");

    let run =
        case("machines", &|r| edit(r.join("shard-3-of-3/runs.csv"), &|t| t.replace(&row.machine_id, "0000deadbeef")));
    refused(&merge(&run, &[]), &run, "rows of 2 machines: ");
    let e = stderr(&merge(&run, &[]));
    assert!(e.contains("0000deadbeef (") && e.contains(&format!("{} (", row.machine_id)), "{e}");
    let o = merge(&run, &["--allow-mixed-machines"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let md = std::fs::read_to_string(run.join("REPORT.md")).unwrap();
    assert!(md.contains("> **Warning:** this result set merges rows of 2 different machines"), "{md}");
    assert!(md.contains("## Across machines"), "{md}");

    // A configuration skipped for want of its backend (Embree) on a node is not missing.
    let run = case("skipped", &|r| {
        let id = first_row(r, 1).split(',').nth(1).unwrap().to_string();
        edit(r.join("shard-1-of-3/runs.csv"), &|t| {
            t.lines().filter(|l| !l.contains(&id)).map(|l| format!("{l}\n")).collect()
        });
        refused(&merge(r, &[]), r, "shard 1 of 3 lacks 2 of its");
        edit(r.join("shard-1-of-3/shard.json"), &|t| t.replace("\"skipped\": []", &format!("\"skipped\": [\"{id}\"]")));
    });
    let o = merge(&run, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read_to_string(run.join("REPORT.md")).unwrap().contains("1 configurations were skipped"));

    let run = case("other-config", &|r| {
        edit(r.join("shard-2-of-3/experiment.toml"), &|t| t.replace("repetitions = 2", "repetitions = 3"))
    });
    refused(&merge(&run, &[]), &run, "differs from the");
    let _ = std::fs::remove_dir_all(&dir);
}
