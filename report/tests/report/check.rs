//! `report::check` on synthetic rows: seeded noise around fixed medians, deterministic counters, instruction
//! counts, one machine or two.

use crate::common;

use std::path::PathBuf;

use report::check::instructions::{self, InstructionCount};
use report::check::{self, CheckOptions, SpeedupVerdict, TimingMode, Verdict};
use report::spec::ReportSpec;
use schema::{Accel, Row, Settings, Workload};
use serde_json::Value;
use tracer::accel::{AccelKind, Split, Traversal};
use tracer::rays::RayKind;
use tracer::rng::SplitMix64;

/// (label, accelerator); "brute" is the reference; the trees use binned SAH, front-to-back.
const SERIES: [(&str, AccelKind); 3] =
    [("brute", AccelKind::List), ("tree", AccelKind::Bvh), ("flat", AccelKind::FlatBvh)];
const OBJECTS: [u64; 2] = [100, 1000];
const SEEDS: [u64; 2] = [1, 2];
const REPETITIONS: u32 = 10;
/// Relative standard deviation of the timing noise.
const NOISE: f64 = 0.05;
/// The machine of the generated rows unless a test names another.
const MACHINE: &str = "3f2a00c0ffee";
/// The boot of the generated rows unless a test names another.
const BOOT: &str = "4e5d2b08-d3c9-47de-8a4c-2142f521c75b";

/// What differs between generated runs.
struct Gen<'a> {
    experiment: &'a str,
    /// Seeds the timing noise.
    noise_seed: u64,
    /// `trace_s` of this series is multiplied by the factor.
    slowdown: Option<(&'a str, f64)>,
    /// `nodes_per_ray` of (series, objects, seed) is replaced.
    nodes_per_ray: Option<(&'a str, u64, u64, f64)>,
    /// Object counts generated.
    objects: &'a [u64],
    /// `machine_id` of every row.
    machine: &'a str,
    /// `build_s` of this series is multiplied by the factor.
    build_slowdown: Option<(&'a str, f64)>,
    /// `load_avg_1m` of every row (2 logical cores).
    load: f64,
    /// `boot_id` of every row.
    boot: &'a str,
}

impl Default for Gen<'_> {
    fn default() -> Self {
        Gen {
            experiment: "synthetic",
            noise_seed: 1,
            slowdown: None,
            nodes_per_ray: None,
            objects: &OBJECTS,
            machine: MACHINE,
            build_slowdown: None,
            load: 0.5,
            boot: BOOT,
        }
    }
}

fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xCBF2_9CE4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01B3))
}

/// The settings of one synthetic configuration: serial primary rays at 64×48.
fn settings(accel: AccelKind, objects: u64, seed: u64) -> Settings {
    let split = Some(Split::BinnedSah);
    let traversal = Some(Traversal::FrontToBack);
    let (width, height, workload) = (64, 48, Workload::Rays(RayKind::Primary));
    Settings {
        accel: Accel::Ours(accel),
        objects,
        seed,
        split,
        traversal,
        width,
        height,
        workload,
        ..Settings::default()
    }
    .normalized()
}

/// The runs.csv text: 3 series × object counts × 2 seeds × 10 repetitions, all serial (threads 1).
fn runs_csv(g: &Gen) -> String {
    let mut rng = SplitMix64::new(g.noise_seed);
    let mut out = format!("{}\n", schema::row::header());
    for (label, accel) in SERIES {
        let tree = accel != AccelKind::List;
        for &objects in g.objects {
            for seed in SEEDS {
                let base = match accel {
                    AccelKind::List => objects as f64 * 1e-4,
                    AccelKind::Bvh => (objects as f64).log2() * 1e-3,
                    AccelKind::FlatBvh | AccelKind::WideBvh => (objects as f64).log2() * 0.8e-3,
                };
                let factor = g.slowdown.filter(|(s, _)| *s == label).map_or(1.0, |(_, f)| f);
                let base_nodes = if tree { (objects as f64).log2() * 2.5 } else { 0.0 };
                let nodes = match g.nodes_per_ray {
                    Some((s, o, sd, v)) if (s, o, sd) == (label, objects, seed) => v,
                    _ => base_nodes,
                };
                let tree_nodes = if tree { objects / 2 } else { 0 };
                for rep in 0..REPETITIONS {
                    let trace_s = base * factor * (1.0 + NOISE * rng.normal());
                    let build_factor = g.build_slowdown.filter(|(s, _)| *s == label).map_or(1.0, |(_, f)| f);
                    let build_s = if tree { objects as f64 * 1e-6 * build_factor } else { 0.0 };
                    let rays = 3072;
                    let row = Row {
                        experiment: g.experiment.into(),
                        config_id: format!("{:016x}", fnv(&format!("{label}|{objects}|{seed}"))),
                        series: label.into(),
                        repetition: rep,
                        build_s: Some(build_s),
                        trace_s: Some(trace_s),
                        total_s: Some(build_s + trace_s),
                        rays,
                        mrays_per_s: Some(rays as f64 / trace_s / 1e6),
                        nodes_per_ray: nodes,
                        box_tests_per_ray: base_nodes * 2.0,
                        prim_tests_per_ray: if tree { 3.5 } else { objects as f64 },
                        tree_nodes,
                        tree_leaves: tree_nodes / 2,
                        tree_depth: if tree { 12 } else { 0 },
                        tree_bytes: tree_nodes * 32,
                        sah_cost: if tree { 20.5 } else { objects as f64 },
                        image_hash: format!("{:016x}", fnv(&format!("{objects}|{seed}|image"))),
                        scene_fingerprint: format!("{:016x}", fnv(&format!("{objects}|{seed}|scene"))),
                        git_commit: "0123456789012345678901234567890123456789".into(),
                        rustc: "rustc 1.91.0 (f8297e351 2025-10-28)".into(),
                        cpu_model: "Test CPU, 2 cores".into(),
                        logical_cores: 2,
                        load_avg_1m: g.load,
                        timestamp: "2025-11-22T03:00:00Z".into(),
                        harness_version: "0.1.0".into(),
                        validation: schema::ValidationStatus::Exact,
                        validated_against: AccelKind::List.name().into(),
                        machine_id: g.machine.into(),
                        boot_id: g.boot.into(),
                        ..Row::of(&settings(accel, objects, seed))
                    };
                    out.push_str(&schema::row::csv_line(&row).unwrap());
                }
            }
        }
    }
    out
}

/// A fresh directory under the system temp dir holding `runs` as runs.csv (none when `runs` is None).
fn run_dir(name: &str, runs: Option<&str>) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bvhlab-check-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    if let Some(runs) = runs {
        std::fs::write(dir.join("runs.csv"), runs).unwrap();
    }
    dir
}

fn spec() -> ReportSpec {
    common::spec("synthetic", "brute", &SERIES.map(|s| s.0))
}

/// Compares `new` (as the run) against `old` (as the baseline).
fn compare(name: &str, new: &Gen, old: &Gen, options: &CheckOptions) -> Result<check::CheckOutcome, report::Error> {
    compare_counted(name, (new, None), (old, None), options)
}

/// The instruction counts of every configuration of [`runs_csv`] (`trace` scaled by `factor`), counted by `rustc`.
fn counts(factor: f64, rustc: &str) -> Vec<InstructionCount> {
    let mut out = Vec::new();
    for (label, accel) in SERIES {
        for objects in OBJECTS {
            for seed in SEEDS {
                for (phase, base) in [
                    ("build", objects * 900),
                    ("trace", 3072 * if accel == AccelKind::List { objects * 40 } else { 700 }),
                ] {
                    out.push(InstructionCount {
                        config_id: format!("{:016x}", fnv(&format!("{label}|{objects}|{seed}"))),
                        series: label.into(),
                        objects,
                        width: 64,
                        height: 48,
                        phase: phase.into(),
                        instructions: if phase == "trace" { (base as f64 * factor).round() as u64 } else { base },
                        d1_misses: None,
                        ll_misses: None,
                        rustc: rustc.into(),
                        target_features: String::new(),
                        valgrind: "valgrind-3.19.0".into(),
                        git_commit: "0123456789012345678901234567890123456789".into(),
                        git_dirty: false,
                    });
                }
            }
        }
    }
    out
}

const RUSTC: &str = "rustc 1.95.0 (59807616e 2026-04-14)";

/// Compares `new` (as the run) against `old` (as the baseline), each with its instruction counts when given.
fn compare_counted(
    name: &str,
    new: (&Gen, Option<&[InstructionCount]>),
    old: (&Gen, Option<&[InstructionCount]>),
    options: &CheckOptions,
) -> Result<check::CheckOutcome, report::Error> {
    let run = run_dir(&format!("{name}-run"), Some(&runs_csv(new.0)));
    let baseline = run_dir(&format!("{name}-baseline"), Some(&runs_csv(old.0)));
    for (dir, counts) in [(&run, new.1), (&baseline, old.1)] {
        if let Some(counts) = counts {
            instructions::write(&dir.join(instructions::FILE), counts).unwrap();
        }
    }
    let outcome = check::compare(&run, &baseline, &spec(), options);
    let _ = std::fs::remove_dir_all(run);
    let _ = std::fs::remove_dir_all(baseline);
    outcome
}

/// The time comparisons of `series`' trace times.
fn traces<'a>(outcome: &'a check::CheckOutcome, series: &'a str) -> impl Iterator<Item = &'a check::TimeComparison> {
    outcome.times.iter().filter(move |t| t.series == series && t.metric == "trace_s")
}

#[test]
fn injected_slowdown_is_flagged() {
    let old = Gen { noise_seed: 11, ..Gen::default() };
    let new = Gen { noise_seed: 12, slowdown: Some(("tree", 1.3)), ..Gen::default() };
    let outcome = compare("slow", &new, &old, &CheckOptions::default()).unwrap();
    println!("{}", outcome.markdown());
    assert_eq!(outcome.mode, TimingMode::SameMachine { machine_id: MACHINE.into(), boot_id: BOOT.into() });
    assert!(outcome.failed());
    assert!(outcome.counter_changes.is_empty() && outcome.missing.is_empty(), "{outcome:?}");
    assert_eq!(outcome.common, 12);
    // Every configuration's trace and build time; builds under 0.1 ms (the list's 0 s; 1e-4 s at 100 objects)
    // are too short to gate.
    assert_eq!(outcome.times.len(), 24, "{:?}", outcome.times);
    assert_eq!(outcome.times.iter().filter(|t| t.gating).count(), 12 + 2 * 2);
    for t in &outcome.times {
        assert_eq!(
            t.gating,
            t.metric == "trace_s" || (t.series != "brute" && t.settings.contains("objects 1000")),
            "{t:?}"
        );
        let tree_trace = t.series == "tree" && t.metric == "trace_s";
        assert_eq!(t.first.verdict == Verdict::Regressed, tree_trace, "{t:?}");
        if tree_trace {
            assert!((t.first.ratio.value - 1.3).abs() < 0.12 && t.first.ratio.lo > 1.0, "{t:?}");
            assert!(t.fails() && t.confirmation.is_none(), "not measured again: fails");
        }
    }
    assert_eq!(outcome.to_confirm().len(), 4, "two object counts × two seeds of the tree");
    // Speedups: two series besides the reference, two object counts each (seeds pooled), for information.
    assert_eq!(outcome.speedups.len(), 4, "{:?}", outcome.speedups);
    for s in &outcome.speedups {
        assert!(s.point.starts_with("objects ") && s.point.contains("threads 1"), "{s:?}");
        assert!(s.lo <= s.ratio && s.ratio <= s.hi, "{s:?}");
        let expected = if s.series == "tree" { SpeedupVerdict::Regressed } else { SpeedupVerdict::Unchanged };
        assert_eq!(s.verdict, expected, "{s:?}");
    }
    // A slowdown below the minimum effect is not a regression even when significant.
    let slight = Gen { noise_seed: 14, slowdown: Some(("tree", 1.03)), ..Gen::default() };
    let small = compare("slight", &slight, &old, &CheckOptions::default()).unwrap();
    assert!(!small.failed(), "{}", small.markdown());
    assert!(traces(&small, "tree").any(|t| t.first.ratio.lo > 1.0), "significant: {}", small.markdown());
    // A faster series is an improvement and passes.
    let faster = Gen { noise_seed: 12, slowdown: Some(("flat", 1.0 / 1.5)), ..Gen::default() };
    let improved = compare("faster", &faster, &old, &CheckOptions::default()).unwrap();
    assert!(!improved.failed());
    assert!(traces(&improved, "flat").all(|t| t.first.verdict == Verdict::Improved));
}

#[test]
fn a_slower_reference_series_fails_on_one_machine_and_informs_across_two() {
    let old = Gen { noise_seed: 51, ..Gen::default() };
    let new = Gen { noise_seed: 52, slowdown: Some(("brute", 1.2)), ..Gen::default() };
    let same = compare("slow-reference", &new, &old, &CheckOptions::default()).unwrap();
    let md = same.markdown();
    println!("{md}");
    assert!(same.failed(), "{md}");
    assert!(traces(&same, "brute").all(|t| t.gating && t.first.verdict == Verdict::Regressed && t.fails()));
    assert!(same.times.iter().filter(|t| t.series != "brute").all(|t| !t.fails()));
    // The speedups over the slower reference rose: the old gate called this an improvement.
    assert!(same.speedups.iter().all(|s| s.verdict == SpeedupVerdict::Improved), "{:?}", same.speedups);
    assert!(md.contains("timing mode: same machine (machine_id 3f2a00c0ffee, boot 4e5d2b08)"), "{md}");
    assert!(md.contains("4 time regression(s) not measured again: brute random-spheres objects"), "{md}");

    // The same rows from another machine: compared, never gating.
    let elsewhere = Gen { noise_seed: 52, slowdown: Some(("brute", 1.2)), machine: "700eca0cc822", ..Gen::default() };
    let other = compare("slow-reference-elsewhere", &elsewhere, &old, &CheckOptions::default()).unwrap();
    let md = other.markdown();
    assert!(!other.failed(), "{md}");
    let TimingMode::Information { reason } = &other.mode else { panic!("{:?}", other.mode) };
    assert_eq!(reason, "run on machine 700eca0cc822, baseline on machine 3f2a00c0ffee");
    assert!(md.contains("timing mode: information only: run on machine 700eca0cc822, baseline on machine"), "{md}");
    assert!(
        other.times.iter().all(|t| !t.gating) && traces(&other, "brute").all(|t| t.first.verdict == Verdict::Regressed)
    );
    assert_eq!(other.speedups.len(), 4, "speedups are compared across machines too");
    assert!(other.to_confirm().is_empty());
    // Rows without a machine (recorded before machine_id) are never taken for one machine.
    let unknown = Gen { machine: "", ..elsewhere };
    let old_unknown = Gen { machine: "", ..old };
    let none = compare("slow-reference-unknown", &unknown, &old_unknown, &CheckOptions::default()).unwrap();
    assert!(!none.failed() && !none.mode.gates_times(), "{:?}", none.mode);
    assert!(none.mode.line().contains("an unrecorded machine"), "{}", none.mode.line());
    // The same hardware facts in another boot (another VM of the same kind reads the same): for information.
    let rebooted = Gen {
        boot: "9c1f0e77-0000-4000-8000-000000000000",
        ..Gen { noise_seed: 52, slowdown: Some(("brute", 1.2)), ..Gen::default() }
    };
    let boot = compare("slow-reference-rebooted", &rebooted, &old, &CheckOptions::default()).unwrap();
    assert!(!boot.failed() && !boot.mode.gates_times(), "{}", boot.markdown());
    assert_eq!(
        boot.mode.line(),
        "timing mode: information only: same hardware facts (machine_id 3f2a00c0ffee) but the run is from boot \
         9c1f0e77, the baseline from boot 4e5d2b08: virtual machines of one kind share every fact machine_id hashes, \
         so times gate only within one boot; gating instruction counts and work counters"
    );
    // A baseline recorded before boot_id (the committed CI baseline): for information.
    let old_unbooted = Gen { boot: "", ..Gen { noise_seed: 51, ..Gen::default() } };
    let unbooted = compare("slow-reference-unbooted", &new, &old_unbooted, &CheckOptions::default()).unwrap();
    assert!(
        !unbooted.failed() && unbooted.mode.line().contains("the baseline from no recorded boot"),
        "{}",
        unbooted.mode.line()
    );
    // A run measured at a load more than 1 above the baseline's (2.0 against 0.5) is compared for information;
    // at 1.5 it still gates.
    let busier = Gen { load: 1.5, ..Gen { noise_seed: 52, slowdown: Some(("brute", 1.2)), ..Gen::default() } };
    assert!(compare("slow-reference-busier", &busier, &old, &CheckOptions::default()).unwrap().failed());
    let overloaded = Gen { load: 2.0, ..busier };
    let busy = compare("slow-reference-busy", &overloaded, &old, &CheckOptions::default()).unwrap();
    assert!(!busy.failed() && !busy.mode.gates_times(), "{}", busy.markdown());
    assert!(
        busy.mode.line().starts_with(
            "timing mode: information only: same machine (3f2a00c0ffee), but the run was measured at a median \
             1-minute load of 2.00, more than 1 above the baseline's 0.50"
        ),
        "{}",
        busy.mode.line()
    );
}

#[test]
fn build_times_gate_beyond_their_own_minimum_effect() {
    let old = Gen { noise_seed: 81, ..Gen::default() };
    let builds = |factor: f64| {
        let new = Gen { noise_seed: 82, build_slowdown: Some(("flat", factor)), ..Gen::default() };
        let outcome = compare(&format!("build-{factor}"), &new, &old, &CheckOptions::default()).unwrap();
        let flat: Vec<Verdict> = outcome
            .times
            .iter()
            .filter(|t| t.series == "flat" && t.metric == "build_s" && t.gating)
            .map(|t| t.first.verdict)
            .collect();
        assert_eq!(flat.len(), 2, "the 1000-object builds gate (1 ms); the 100-object ones are too short");
        (outcome.failed(), flat)
    };
    // 20% slower builds are within the drift of builds between runs (min_effect_build 30%); 50% is not.
    assert_eq!(builds(1.2), (false, vec![Verdict::Unchanged; 2]));
    assert_eq!(builds(1.5), (true, vec![Verdict::Regressed; 2]));
    let strict = CheckOptions { min_effect_build: 0.1, ..CheckOptions::default() };
    let new = Gen { noise_seed: 82, build_slowdown: Some(("flat", 1.2)), ..Gen::default() };
    assert!(compare("build-strict", &new, &old, &strict).unwrap().failed());
}

#[test]
fn a_flagged_time_fails_only_when_measured_again_slower() {
    let old = Gen { noise_seed: 61, ..Gen::default() };
    let new = Gen { noise_seed: 62, slowdown: Some(("tree", 1.3)), ..Gen::default() };
    let run = run_dir("confirm-run", Some(&runs_csv(&new)));
    let baseline = run_dir("confirm-baseline", Some(&runs_csv(&old)));
    let options = CheckOptions::default();
    let first = check::compare(&run, &baseline, &spec(), &options).unwrap();
    assert_eq!(first.to_confirm().len(), 4);
    // Measured again at the baseline's speed: a passing check that shows both measurements.
    let confirm = run.join("confirm.csv");
    std::fs::write(&confirm, runs_csv(&Gen { noise_seed: 63, ..Gen::default() })).unwrap();
    let mut cleared = first.clone();
    cleared.confirm(&confirm, &baseline, &options).unwrap();
    let md = cleared.markdown();
    println!("{md}");
    assert!(!cleared.failed(), "{md}");
    assert!(
        traces(&cleared, "tree")
            .all(|t| t.flagged() && t.confirmation.is_some_and(|c| c.verdict == Verdict::Unchanged))
    );
    assert!(md.contains("4 time regression(s) of the first measurement not confirmed by the second"), "{md}");
    assert!(md.contains("| **regressed** | yes | "), "the first measurement stays in the table: {md}");
    let json: Value = serde_json::from_str(&cleared.to_json()).unwrap();
    let flagged: Vec<&Value> =
        json["times"].as_array().unwrap().iter().filter(|t| t["first"]["verdict"] == "regressed").collect();
    assert_eq!(flagged.len(), 4);
    assert!(flagged.iter().all(|t| t["confirmation"]["verdict"] == "unchanged" && t["fails"] == false), "{json}");
    // Measured again just as slow: it fails, confirmed.
    std::fs::write(&confirm, runs_csv(&Gen { noise_seed: 64, slowdown: Some(("tree", 1.3)), ..Gen::default() }))
        .unwrap();
    let mut confirmed = first.clone();
    confirmed.confirm(&confirm, &baseline, &options).unwrap();
    assert!(confirmed.failed());
    assert!(
        confirmed.markdown().contains("4 time regression(s) confirmed by a second measurement"),
        "{}",
        confirmed.markdown()
    );
    let _ = std::fs::remove_dir_all(run);
    let _ = std::fs::remove_dir_all(baseline);
}

#[test]
fn instruction_counts_gate_above_the_threshold_from_one_compiler() {
    let (old, new) = (Gen { noise_seed: 71, ..Gen::default() }, Gen { noise_seed: 72, ..Gen::default() });
    let base = counts(1.0, RUSTC);
    let check = |name: &str, counts: &[InstructionCount], machine: &str| {
        let new = Gen { machine, ..Gen { noise_seed: 72, ..Gen::default() } };
        compare_counted(name, (&new, Some(counts)), (&old, Some(&base)), &CheckOptions::default()).unwrap()
    };
    // +3% instructions in every trace: fails, on any machine (timings there are for information).
    let more = check("counts-more", &counts(1.03, RUSTC), "700eca0cc822");
    let md = more.markdown();
    println!("{md}");
    assert!(more.failed() && more.instructions.gating, "{md}");
    assert_eq!(more.instructions.regressions().count(), 12, "{md}");
    assert!(more.instructions.regressions().all(|c| c.phase == "trace" && (c.ratio - 1.03).abs() < 1e-6));
    assert!(
        more.instructions.comparisons.iter().filter(|c| c.phase == "build").all(|c| c.verdict == Verdict::Unchanged)
    );
    assert!(md.contains("12 instruction-count regression(s): brute objects 100 trace +3.0%"), "{md}");
    assert!(md.contains("instructions: gated: both counted with rustc 1.95.0"), "{md}");
    assert!(!more.mode.gates_times());
    // +1%: passes.
    let little = check("counts-little", &counts(1.01, RUSTC), MACHINE);
    assert!(!little.failed() && little.instructions.gating, "{}", little.markdown());
    assert_eq!(little.instructions.comparisons.len(), 24);
    // Another compiler: +3% is shown, for information.
    let other = check("counts-rustc", &counts(1.03, "rustc 1.96.0 (00000000 2026-06-01)"), MACHINE);
    let md = other.markdown();
    assert!(!other.failed() && !other.instructions.gating, "{md}");
    assert!(md.contains("instructions: for information only: the run was counted with rustc 1.96.0"), "{md}");
    assert_eq!(other.instructions.regressions().count(), 12);
    // Counts on one side only: not compared, said so.
    let one = compare_counted("counts-one-side", (&new, None), (&old, Some(&base)), &CheckOptions::default()).unwrap();
    assert!(!one.failed() && one.instructions.comparisons.is_empty());
    assert!(one.instructions.note.contains("the run has no instructions.csv"), "{}", one.instructions.note);
    // Counts made at another commit than the run's rows are compared, and the note says so.
    let stale: Vec<InstructionCount> = counts(1.0, RUSTC)
        .into_iter()
        .map(|c| InstructionCount { git_commit: "fedcba9876543210".into(), ..c })
        .collect();
    let noted = check("counts-stale", &stale, MACHINE);
    assert!(!noted.failed(), "{}", noted.markdown());
    assert!(
        noted
            .instructions
            .note
            .ends_with("(note: the run's counts were made at commit fedcba987654, its rows at 012345678901)"),
        "{}",
        noted.instructions.note
    );
    assert!(!little.instructions.note.contains("note:"), "{}", little.instructions.note);
    // A stricter threshold catches +1%.
    let strict = CheckOptions { instruction_threshold: 0.005, ..CheckOptions::default() };
    let little =
        compare_counted("counts-strict", (&new, Some(&counts(1.01, RUSTC))), (&old, Some(&base)), &strict).unwrap();
    assert!(little.failed(), "{}", little.markdown());
}

#[test]
fn same_distribution_is_rarely_flagged() {
    let trials = 100;
    // The trials are independent: one thread per core takes every n-th.
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
    let (flagged, significant) = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                scope.spawn(move || {
                    let (mut flagged, mut significant) = (0, 0);
                    for t in (w..trials).step_by(workers as usize) {
                        let old = Gen { noise_seed: 1000 + 2 * t, ..Gen::default() };
                        let new = Gen { noise_seed: 1001 + 2 * t, ..Gen::default() };
                        let outcome = compare(&format!("null-{t}"), &new, &old, &CheckOptions::default()).unwrap();
                        assert!(outcome.counter_changes.is_empty() && outcome.missing.is_empty());
                        assert_eq!(outcome.speedups.len(), 4);
                        assert_eq!(outcome.times.len(), 24);
                        flagged += outcome.failed() as usize;
                        significant +=
                            outcome.times.iter().any(|t| t.first.ratio.hi < 1.0 || t.first.ratio.lo > 1.0) as usize;
                    }
                    (flagged, significant)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
    });
    println!("false alarms: {flagged} of {trials} trials flagged; {significant} trials had some interval excluding 1");
    assert!(flagged <= 5, "{flagged} of {trials} same-distribution trials flagged");
}

#[test]
fn changed_counter_is_flagged_unless_accepted() {
    let old = Gen { noise_seed: 21, ..Gen::default() };
    let new = Gen { noise_seed: 22, nodes_per_ray: Some(("tree", 1000, 2, 99.5)), ..Gen::default() };
    let outcome = compare("counter", &new, &old, &CheckOptions::default()).unwrap();
    assert!(outcome.failed());
    assert_eq!(outcome.counter_changes.len(), 1, "{:?}", outcome.counter_changes);
    let change = &outcome.counter_changes[0];
    assert_eq!((change.series.as_str(), change.column.as_str()), ("tree", "nodes_per_ray"));
    assert_eq!(change.old.parse::<f64>().unwrap(), 1000f64.log2() * 2.5);
    assert_eq!(change.new, "99.5");
    assert_eq!(change.settings, "random-spheres objects 1000 seed 2");
    assert_eq!(change.config_id, format!("{:016x}", fnv("tree|1000|2")));
    assert!(outcome.times.iter().all(|t| !t.fails()));
    let md = outcome.markdown();
    assert!(md.contains("FAIL") && md.contains("nodes_per_ray") && md.contains("→ 99.5"), "{md}");

    let accept = CheckOptions { accept_counter_changes: true, ..CheckOptions::default() };
    let accepted = compare("counter-accepted", &new, &old, &accept).unwrap();
    assert!(!accepted.failed());
    assert_eq!(accepted.counter_changes, outcome.counter_changes);
    assert!(accepted.markdown().contains("PASS"));

    // A configuration on one side only is listed and fails the check unless accepted.
    let fewer = Gen { noise_seed: 23, objects: &[100], ..Gen::default() };
    let partial = compare("missing", &fewer, &old, &CheckOptions::default()).unwrap();
    assert!(partial.failed());
    assert_eq!(partial.missing.len(), 6, "{:?}", partial.missing);
    assert!(partial.missing.iter().all(|m| m.starts_with("only in baseline") && m.contains("objects 1000")));
    assert_eq!(partial.speedups.len(), 2);
    assert!(!compare("missing-accepted", &fewer, &old, &accept).unwrap().failed());
}

#[test]
fn mismatches_are_one_line_errors_naming_the_file() {
    let old = Gen::default();
    let other = Gen { experiment: "other", ..Gen::default() };
    let err = compare("experiments", &other, &old, &CheckOptions::default()).unwrap_err().to_string();
    assert!(err.contains("experiments do not match: run is other, baseline is synthetic"), "{err}");
    assert!(err.contains("runs.csv") && !err.contains('\n'), "{err}");

    let big = Gen { objects: &[10_000], ..Gen::default() };
    let err = compare("disjoint", &big, &old, &CheckOptions::default()).unwrap_err().to_string();
    assert!(err.contains("no configuration in common") && err.contains("runs.csv") && !err.contains('\n'), "{err}");

    let empty = run_dir("no-runs", None);
    let baseline = run_dir("no-runs-baseline", Some(&runs_csv(&old)));
    for (run, base) in [(&empty, &baseline), (&baseline, &empty)] {
        let err = check::compare(run, base, &spec(), &CheckOptions::default()).unwrap_err().to_string();
        let missing = empty.join("runs.csv");
        assert!(err.contains(&missing.display().to_string()) && !err.contains('\n'), "{err}");
    }
    let _ = std::fs::remove_dir_all(empty);
    let _ = std::fs::remove_dir_all(baseline);
}

#[test]
fn without_reference_no_speedups_are_compared() {
    let old = Gen { noise_seed: 31, ..Gen::default() };
    let new = Gen { noise_seed: 32, slowdown: Some(("tree", 1.3)), ..Gen::default() };
    let run = run_dir("noref-run", Some(&runs_csv(&new)));
    let baseline = run_dir("noref-baseline", Some(&runs_csv(&old)));
    let spec = ReportSpec { reference: None, ..spec() };
    let outcome = check::compare(&run, &baseline, &spec, &CheckOptions::default()).unwrap();
    assert!(outcome.speedups.is_empty(), "{outcome:?}");
    assert!(outcome.failed() && traces(&outcome, "tree").all(|t| t.fails()), "times still gate");
    assert!(outcome.markdown().contains("counters: all 12 configurations identical"));
    let _ = std::fs::remove_dir_all(run);
    let _ = std::fs::remove_dir_all(baseline);
}

#[test]
fn markdown_and_json_list_every_measure() {
    let old = Gen { noise_seed: 41, ..Gen::default() };
    let new = Gen {
        noise_seed: 42,
        slowdown: Some(("tree", 1.3)),
        nodes_per_ray: Some(("flat", 100, 1, 7.25)),
        ..Gen::default()
    };
    let outcome = compare("output", &new, &old, &CheckOptions::default()).unwrap();
    let md = outcome.markdown();
    println!("{md}");
    assert!(md.starts_with("## Regression check\n\ntiming mode: same machine"), "{md}");
    assert!(md.contains("FAIL") && md.contains("**regressed**"), "{md}");
    // Failing times come first in the time table.
    let times: Vec<&str> = md.lines().filter(|l| l.contains("_s | ")).collect();
    assert_eq!(times.len(), 24, "{md}");
    assert!(
        times[..4].iter().all(|r| r.contains(" tree, ") && r.contains("**regressed** | yes | not measured again")),
        "{md}"
    );
    assert!(times[4..].iter().all(|r| !r.contains("regressed")), "{md}");
    // Regressions come first in the speedup table.
    let rows: Vec<&str> = md.lines().filter(|l| l.contains("| objects ")).collect();
    assert_eq!(rows.len(), 4, "{md}");
    assert!(rows[0].starts_with("| tree |") && rows[0].ends_with("| regressed |"), "{md}");
    assert!(
        rows[1].starts_with("| tree |") && rows[3].starts_with("| flat |") && rows[3].contains("unchanged"),
        "{md}"
    );

    let json = outcome.to_json();
    println!("{json}");
    let value: Value = serde_json::from_str(&json).unwrap_or_else(|e| panic!("invalid JSON ({e}):\n{json}"));
    assert_eq!(value.get("failed"), Some(&Value::Bool(true)));
    assert_eq!(value["timing_mode"]["mode"], "same-machine");
    assert_eq!(value["timing_mode"]["machine_id"], MACHINE);
    let Some(Value::Array(speedups)) = value.get("speedups") else { panic!("{json}") };
    assert_eq!(speedups.len(), outcome.speedups.len());
    for (s, c) in speedups.iter().zip(&outcome.speedups) {
        for measure in ["old", "new", "ratio"] {
            let m = s.get(measure).unwrap_or_else(|| panic!("{measure} in {json}"));
            for key in ["value", "lower", "upper"] {
                assert!(m.get(key).is_some_and(Value::is_number), "{measure}.{key} in {json}");
            }
        }
        assert_eq!(s["ratio"]["lower"].as_f64(), Some(c.lo));
        assert_eq!(s.get("verdict"), Some(&Value::String(c.verdict.word().into())));
    }
    let Some(Value::Array(times)) = value.get("times") else { panic!("{json}") };
    assert_eq!(times.len(), outcome.times.len());
    for (j, t) in times.iter().zip(&outcome.times) {
        assert_eq!(j["first"]["ratio"]["lower"].as_f64(), Some(t.first.ratio.lo).filter(|v| v.is_finite()));
        assert_eq!(j["first"]["old"]["value"].as_f64(), Some(t.first.old.value));
        assert_eq!((j["gating"].as_bool(), j["fails"].as_bool()), (Some(t.gating), Some(t.fails())));
        assert_eq!(j["confirmation"], Value::Null);
    }
    let Some(Value::Array(changes)) = value.get("counter_changes") else { panic!("{json}") };
    assert_eq!(changes.len(), 1);
    assert_eq!(changes[0].get("new"), Some(&Value::String("7.25".into())));
    assert_eq!(value.get("missing"), Some(&Value::Array(vec![])));
}

#[test]
fn timings_for_information_never_fail_but_counters_still_do() {
    let old = Gen { noise_seed: 41, ..Gen::default() };
    let slow = Gen { noise_seed: 42, slowdown: Some(("tree", 1.3)), ..Gen::default() };
    let info = CheckOptions { timings_for_information: true, ..CheckOptions::default() };
    let outcome = compare("info-slow", &slow, &old, &info).unwrap();
    assert!(!outcome.failed(), "a 30% slowdown is reported, not gated: {}", outcome.markdown());
    assert!(traces(&outcome, "tree").all(|t| t.first.verdict == Verdict::Regressed && !t.gating));
    assert!(outcome.to_confirm().is_empty());
    assert_eq!(
        outcome.mode.line(),
        "timing mode: information only: forced by --timings-for-information; gating instruction counts and work counters"
    );
    let counter = Gen { noise_seed: 43, nodes_per_ray: Some(("tree", 1000, 2, 99.5)), ..Gen::default() };
    assert!(compare("info-counter", &counter, &old, &info).unwrap().failed(), "counters still gate");
}
