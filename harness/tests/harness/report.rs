//! `harness report --claims-against`: a claim that held in a recorded run and fails here fails the report.

use std::path::Path;

use crate::common::{harness, names, stderr, temp};

#[test]
fn report_claims_against_fails_naming_a_claim_that_held_there_and_fails_here_everywhere() {
    let (list, flat, ..) = names();
    let dir = temp("claims-against");
    let claim = "[[claim]]\ntext = \"the tree is faster than brute force\"\nkind = \"faster\"\nseries = \"tree\"\n\
                 than = \"brute\"\nfactor = 1.0\n";
    // The same claim over the same settings, recorded once with the BVH as `tree` and once with the list: at 20,000
    // spheres the two differ by two orders of magnitude, so a loaded machine cannot blur the verdicts.
    let record = |name: &str, tree: &str, brute: &str| {
        let cfg = dir.join(format!("{name}.toml"));
        std::fs::write(
            &cfg,
            format!("name = \"c\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nrepetitions = 6\n[sweep]\nobjects = 20000\nwidth = 48\nheight = 32\nworkload = \"primary\"\n\
                 [[series]]\nlabel = \"brute\"\naccel = \"{brute}\"\n[[series]]\nlabel = \"tree\"\naccel = \"{tree}\"\n{claim}"),
        )
        .unwrap();
        let out = dir.join(name);
        let o = harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };
    let (held, lost) = (record("held", flat, list), record("lost", list, flat));
    let against = |dir: &Path, recorded: &Path| {
        harness()
            .args(["report", dir.to_str().unwrap(), "--claims-against", recorded.to_str().unwrap()])
            .output()
            .unwrap()
    };
    let o = against(&lost, &held);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("claim lost: \"the tree is faster than brute force\""), "{}", stderr(&o));
    let o = against(&held, &lost);
    assert!(o.status.success(), "a claim that failed there and holds here is no loss: {}", stderr(&o));
    let o = against(&held, &dir.join("nothing"));
    assert_eq!(o.status.code(), Some(2), "not a run folder: {}", stderr(&o));
}
