//! `harness validate`: the runs a config asks for and an estimate of their time. (Its refusals of bad configs are
//! tested beside `harness run`'s, in run.rs.)

use crate::common::{harness, stderr};

#[test]
fn validate_prints_runs_and_an_estimate() {
    let o = harness().args(["validate", "experiments/paper.toml"]).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.contains("configurations 174"), "{out}");
    assert!(
        out.contains("runs           at most 1566 recorded (9 repetitions each) + 0 warm-ups, order interleaved"),
        "{out}"
    );
    assert!(out.contains("estimate       ~"), "{out}");
}
