//! `harness baseline save` and `harness check` against the baseline saved: never overwritten without `--force`, a
//! run checked against its own baseline passes, a missing run or a run of another config is refused.

use std::path::Path;
use std::process::Command;

use crate::common::{harness, names, stderr, temp};

#[test]
fn baseline_save_and_check_bad_input() {
    let (list, flat, ..) = names();
    let dir = temp("baseline");
    let cfg = dir.join("b.toml");
    std::fs::write(&cfg, format!("name = \"b\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nreference = \"brute\"\nrepetitions = 3\n[sweep]\nobjects = 200\nwidth = 32\nheight = 24\nworkload = \"primary\"\n[[series]]\nlabel = \"brute\"\naccel = \"{list}\"\n[[series]]\nlabel = \"tree\"\naccel = \"{flat}\"\n")).unwrap();
    let run_dir = dir.join("run");
    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", run_dir.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    // Baselines go to results/baselines/NAME relative to the working directory: use the temp dir as one.
    let save = |force: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_harness"));
        c.current_dir(&dir).args(["baseline", "save", run_dir.to_str().unwrap(), "b-test"]);
        if force {
            c.arg("--force");
        }
        c.output().unwrap()
    };
    assert!(save(false).status.success());
    assert!(dir.join("results/baselines/b-test/runs.csv").is_file());
    assert!(
        std::fs::read_to_string(dir.join("results/baselines/b-test/BASELINE.md"))
            .unwrap()
            .contains("Recorded at commit")
    );
    let o = save(false);
    assert_eq!(o.status.code(), Some(2), "never overwrite without --force");
    assert!(stderr(&o).contains("baseline exists; use --force"));
    assert!(save(true).status.success());

    let baseline = dir.join("results/baselines/b-test");
    let check = |run: &Path, base: &Path| {
        harness().args(["check", run.to_str().unwrap(), "--baseline", base.to_str().unwrap()]).output().unwrap()
    };
    let o = check(&run_dir, &baseline);
    assert!(
        o.status.success(),
        "a run checked against its own baseline passes: {}{}",
        String::from_utf8_lossy(&o.stdout),
        stderr(&o)
    );
    assert!(run_dir.join("check.json").is_file());
    let o = check(&dir.join("nowhere"), &baseline);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("nowhere: no runs.csv here"), "{}", stderr(&o));
    let other = dir.join("other");
    std::fs::write(
        dir.join("o.toml"),
        "name = \"other\"\nrepetitions = 1\nwarmups = 0\nsample_ms = 0\nprocesses = 1\n[sweep]\nobjects = 10\nwidth = 8\nheight = 8\nworkload = \"primary\"\n",
    )
    .unwrap();
    assert!(
        harness()
            .args(["run", dir.join("o.toml").to_str().unwrap(), "--out", other.to_str().unwrap()])
            .output()
            .unwrap()
            .status
            .success()
    );
    let o = check(&other, &baseline);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("does not match the baseline"), "{}", stderr(&o));
}
