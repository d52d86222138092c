//! `harness instructions` under valgrind on a tiny config: counts of both phases, the same on a second count,
//! and `harness check` gating on them. Skipped without valgrind, unless `BVHLAB_REQUIRE_VALGRIND=1` (CI).

use std::path::Path;
use std::process::{Command, Output};

use crate::common::{harness, temp};

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Whether valgrind can run here; panics when it cannot but `BVHLAB_REQUIRE_VALGRIND=1` requires it.
fn valgrind_present() -> bool {
    let present = Command::new("valgrind").arg("--version").output().is_ok_and(|o| o.status.success());
    if !present && std::env::var("BVHLAB_REQUIRE_VALGRIND").is_ok_and(|v| v == "1") {
        panic!("BVHLAB_REQUIRE_VALGRIND=1 but valgrind is not installed (apt-get install valgrind)");
    }
    if !present {
        eprintln!("skipped: valgrind is not installed (set BVHLAB_REQUIRE_VALGRIND=1 to require it)");
    }
    present
}

/// (config_id, series, phase, instructions) of an instructions.csv.
fn counts(dir: &Path) -> Vec<(String, String, String, u64)> {
    let text = std::fs::read_to_string(dir.join("instructions.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("{name} in {header:?}"));
    let (id, series, phase, ir) = (col("config_id"), col("series"), col("phase"), col("instructions"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[id].to_string(), f[series].to_string(), f[phase].to_string(), f[ir].parse().unwrap())
        })
        .collect()
}

#[test]
fn instruction_counts_repeat_exactly_and_gate_the_check() {
    if !valgrind_present() {
        return;
    }
    let dir = temp("tiny");
    let config = dir.join("tiny.toml");
    std::fs::write(
        &config,
        "name = \"tiny\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nreference = \"list\"\nrepetitions = 3\n[sweep]\nobjects = 60\nwidth = 16\nheight = 12\n\
         workload = \"primary\"\nstrategy = \"serial\"\n\
         [[series]]\nlabel = \"list\"\naccel = \"list\"\n\
         [[series]]\nlabel = \"flat\"\naccel = \"flat-bvh\"\n\
         [[series]]\nlabel = \"flat-rayon\"\naccel = \"flat-bvh\"\nstrategy = \"rayon-bands\"\nthreads = 2\n",
    )
    .unwrap();
    let (run, again) = (dir.join("run"), dir.join("again"));
    let o = harness().args(["run", config.to_str().unwrap(), "--out", run.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    for out in [&run, &again] {
        let o = harness()
            .args(["instructions", config.to_str().unwrap(), "--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", text(&o));
        assert!(text(&o).contains("not counted (more than one thread): flat-rayon objects 60"), "{}", text(&o));
    }
    let first = counts(&run);
    let phases: Vec<(&str, &str)> = first.iter().map(|(_, s, p, _)| (s.as_str(), p.as_str())).collect();
    assert_eq!(phases, [("list", "build"), ("list", "trace"), ("flat", "build"), ("flat", "trace")]);
    assert!(first.iter().all(|c| c.3 > 0), "{first:?}");
    // 192 rays × 60 sphere tests for the list, far fewer for the tree.
    assert!(first[1].3 > 192 * 60 * 10 && first[1].3 > 2 * first[3].3, "{first:?}");
    assert_eq!(first, counts(&again), "a second count of the same binary is identical");
    assert!(run.join("callgrind").join(format!("{}-trace.callgrind", first[1].0)).is_file());

    // A run checked against itself: the same machine, instruction counts gated, passes.
    let check = |baseline: &Path| {
        harness()
            .args(["check", run.to_str().unwrap(), "--baseline", baseline.to_str().unwrap(), "--no-confirm"])
            .output()
            .unwrap()
    };
    let o = check(&run);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.starts_with("timing mode: same machine (machine_id "), "{out}");
    assert!(out.contains("instructions: gated: both counted with rustc"), "{out}");

    // A baseline that executed 5% fewer instructions in the list's trace: the run regressed.
    let baseline = dir.join("baseline");
    std::fs::create_dir_all(&baseline).unwrap();
    for f in ["runs.csv", "experiment.toml"] {
        std::fs::copy(run.join(f), baseline.join(f)).unwrap();
    }
    let list_trace = first[1].3.to_string();
    let fewer = ((first[1].3 as f64) / 1.05).round() as u64;
    let csv = std::fs::read_to_string(run.join("instructions.csv")).unwrap().replace(&list_trace, &fewer.to_string());
    std::fs::write(baseline.join("instructions.csv"), csv).unwrap();
    let o = check(&baseline);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("1 instruction-count regression(s): list objects 60 trace +5.0%"), "{}", text(&o));
    let _ = std::fs::remove_dir_all(dir);
}
