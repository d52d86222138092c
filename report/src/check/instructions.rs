//! Instruction counts: `instructions.csv` of a run folder (written by `harness instructions`, which runs each
//! single-thread configuration under callgrind and counts the instructions of its build and of its trace), and
//! their comparison with a baseline's, the check's deterministic gate.
//!
//! An instruction count is the same on every run of a binary on a machine of one instruction set, so a fixed
//! threshold replaces the timings' intervals: a phase whose count grew by more than the threshold (default 2%)
//! regressed. It gates only when both sides were counted with the same compiler (`rustc`) and compiled target
//! features: another compiler generates other code, and the counts are then shown for information.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::Verdict;
use crate::error::Error;

/// The file in a run folder.
pub const FILE: &str = "instructions.csv";

/// One phase of one configuration, counted under callgrind: a row of `instructions.csv`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InstructionCount {
    /// The configuration id, as in `runs.csv`.
    pub config_id: String,
    /// The series label.
    pub series: String,
    /// Spheres of the scene.
    pub objects: u64,
    /// Image width the rays were made for (the configuration's, unless counted at another size).
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// `build` or `trace`.
    pub phase: String,
    /// Instructions executed in the phase (callgrind's `Ir`).
    pub instructions: u64,
    /// First-level data cache misses (reads and writes) of callgrind's simulated cache, when it was simulated.
    pub d1_misses: Option<u64>,
    /// Last-level cache misses (instruction and data) of the simulated cache, when it was simulated.
    pub ll_misses: Option<u64>,
    /// `rustc --version` of the compiler that built the counted binary.
    pub rustc: String,
    /// Target features the binary was compiled with (the `target_features` column; empty: the target's default).
    pub target_features: String,
    /// `valgrind --version`.
    pub valgrind: String,
    /// Commit of the counted tree.
    pub git_commit: String,
    /// Whether the tree had uncommitted changes.
    pub git_dirty: bool,
}

/// Writes `counts` as `path` (CSV with a header).
pub fn write(path: &Path, counts: &[InstructionCount]) -> Result<(), Error> {
    let mut writer = csv::Writer::from_path(path).map_err(|e| Error::write(path, e))?;
    for c in counts {
        writer.serialize(c).map_err(|e| Error::write(path, e))?;
    }
    writer.flush().map_err(|e| Error::write(path, e))
}

/// Reads an `instructions.csv`.
pub fn read(path: &Path) -> Result<Vec<InstructionCount>, Error> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| Error::read(path, e))?;
    reader.deserialize().collect::<Result<Vec<InstructionCount>, _>>().map_err(|e| Error::read(path, e))
}

/// One phase of one configuration counted on both sides.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InstructionComparison {
    /// The configuration id.
    pub config_id: String,
    /// The series label.
    pub series: String,
    /// Spheres of the scene.
    pub objects: u64,
    /// `build` or `trace`.
    pub phase: String,
    /// Baseline instructions.
    pub old: u64,
    /// Run instructions.
    pub new: u64,
    /// `new / old`.
    pub ratio: f64,
    /// Regressed (more than the threshold above 1), improved (as far below) or unchanged.
    #[serde(serialize_with = "verdict_word")]
    pub verdict: Verdict,
    /// Simulated D1 misses, baseline and run, where both were simulated.
    pub d1_misses: Option<(u64, u64)>,
    /// Simulated last-level misses, baseline and run, where both were simulated.
    pub ll_misses: Option<(u64, u64)>,
}

fn verdict_word<S: serde::Serializer>(v: &Verdict, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(v.word())
}

/// What the instruction counts showed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InstructionCheck {
    /// Whether a regression fails the check: both sides counted, by the same compiler with the same target
    /// features.
    pub gating: bool,
    /// One line: what was compared, with which threshold, or why not (or only for information).
    pub note: String,
    /// Largest relative growth that passes.
    pub threshold: f64,
    /// Every phase counted on both sides, regressions first.
    pub comparisons: Vec<InstructionComparison>,
    /// Phases counted on one side only (or at another image size), described.
    pub one_side: Vec<String>,
}

impl InstructionCheck {
    /// A gating regression.
    pub fn failed(&self) -> bool {
        self.gating && self.regressions().next().is_some()
    }

    /// The regressed phases.
    pub fn regressions(&self) -> impl Iterator<Item = &InstructionComparison> {
        self.comparisons.iter().filter(|c| c.verdict == Verdict::Regressed)
    }
}

/// Compares `run_dir`'s counts with `baseline_dir`'s, when both have [`FILE`]; `threshold` as in
/// [`super::CheckOptions::instruction_threshold`].
pub fn check(run_dir: &Path, baseline_dir: &Path, threshold: f64) -> Result<InstructionCheck, Error> {
    let (new_path, old_path) = (run_dir.join(FILE), baseline_dir.join(FILE));
    let absent = |which: &str| InstructionCheck {
        note: format!("not compared: the {which} has no {FILE} (`harness instructions CONFIG --out DIR` counts one)"),
        threshold,
        ..Default::default()
    };
    match (new_path.is_file(), old_path.is_file()) {
        (false, false) => return Ok(absent("run nor the baseline")),
        (false, true) => return Ok(absent("run")),
        (true, false) => return Ok(absent("baseline")),
        (true, true) => {}
    }
    Ok(compare_counts(&read(&new_path)?, &read(&old_path)?, threshold))
}

/// The comparison of two sets of counts (see [`check`]).
pub fn compare_counts(new: &[InstructionCount], old: &[InstructionCount], threshold: f64) -> InstructionCheck {
    let toolchain = |counts: &[InstructionCount]| -> BTreeSet<(String, String)> {
        counts.iter().map(|c| (c.rustc.clone(), c.target_features.clone())).collect()
    };
    let (new_tools, old_tools) = (toolchain(new), toolchain(old));
    let describe = |tools: &BTreeSet<(String, String)>| -> String {
        let parts: Vec<String> = tools
            .iter()
            .map(|(rustc, features)| {
                let features = if features.is_empty() { "the target's default" } else { features.as_str() };
                format!("{rustc}, target features {features}")
            })
            .collect();
        parts.join(" and ")
    };
    let gating = new_tools.len() == 1 && new_tools == old_tools;
    let valgrind =
        |counts: &[InstructionCount]| -> BTreeSet<String> { counts.iter().map(|c| c.valgrind.clone()).collect() };
    let (new_valgrind, old_valgrind) = (valgrind(new), valgrind(old));
    let mut note = if gating {
        format!(
            "gated: both counted with {}; a phase fails above +{}% instructions",
            describe(&new_tools),
            num_percent(threshold)
        )
    } else {
        format!(
            "for information only: the run was counted with {}, the baseline with {} (counts compare only from one \
             compiler and target features)",
            describe(&new_tools),
            describe(&old_tools)
        )
    };
    if new_valgrind != old_valgrind {
        let join = |s: &BTreeSet<String>| s.iter().cloned().collect::<Vec<_>>().join("+");
        note.push_str(&format!(" (valgrind: run {}, baseline {})", join(&new_valgrind), join(&old_valgrind)));
    }

    let key = |c: &InstructionCount| (c.config_id.clone(), c.phase.clone());
    let old_by: BTreeMap<_, &InstructionCount> = old.iter().map(|c| (key(c), c)).collect();
    let new_by: BTreeMap<_, &InstructionCount> = new.iter().map(|c| (key(c), c)).collect();
    let mut comparisons = Vec::new();
    let mut one_side = Vec::new();
    let label = |c: &InstructionCount| format!("{} {} objects {} {}", c.config_id, c.series, c.objects, c.phase);
    for c in old.iter().filter(|c| !new_by.contains_key(&key(c))) {
        one_side.push(format!("only in baseline: {}", label(c)));
    }
    for n in new {
        let Some(o) = old_by.get(&key(n)) else {
            one_side.push(format!("only in run: {}", label(n)));
            continue;
        };
        if (n.width, n.height) != (o.width, o.height) {
            one_side.push(format!(
                "{}: counted at {}×{} in the run, {}×{} in the baseline",
                label(n),
                n.width,
                n.height,
                o.width,
                o.height
            ));
            continue;
        }
        let ratio = n.instructions as f64 / o.instructions as f64;
        let verdict = if ratio > 1.0 + threshold {
            Verdict::Regressed
        } else if ratio < 1.0 - threshold {
            Verdict::Improved
        } else {
            Verdict::Unchanged
        };
        let both = |a: Option<u64>, b: Option<u64>| a.zip(b);
        comparisons.push(InstructionComparison {
            config_id: n.config_id.clone(),
            series: n.series.clone(),
            objects: n.objects,
            phase: n.phase.clone(),
            old: o.instructions,
            new: n.instructions,
            ratio,
            verdict,
            d1_misses: both(o.d1_misses, n.d1_misses),
            ll_misses: both(o.ll_misses, n.ll_misses),
        });
    }
    comparisons.sort_by_key(|c| c.verdict.rank()); // stable: the run's order within each verdict
    InstructionCheck { gating, note, threshold, comparisons, one_side }
}

/// A fraction as a percentage without trailing zeros (`0.02` → `2`, `0.025` → `2.5`).
fn num_percent(fraction: f64) -> String {
    let text = format!("{:.3}", fraction * 100.0);
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(config_id: &str, phase: &str, instructions: u64) -> InstructionCount {
        InstructionCount {
            config_id: config_id.into(),
            series: "tree".into(),
            objects: 1000,
            width: 64,
            height: 48,
            phase: phase.into(),
            instructions,
            d1_misses: None,
            ll_misses: Some(7),
            rustc: "rustc 1.95.0 (59807616e 2026-04-14)".into(),
            target_features: String::new(),
            valgrind: "valgrind-3.19.0".into(),
            git_commit: "0123".into(),
            git_dirty: false,
        }
    }

    #[test]
    fn counts_round_trip_through_csv() {
        let dir = std::env::temp_dir().join(format!("bvhlab-instructions-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(FILE);
        let counts = vec![count("00ff", "build", 12), count("00ff", "trace", 1 << 40)];
        write(&path, &counts).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.starts_with("config_id,series,objects,width,height,phase,instructions,d1_misses,ll_misses,"),
            "{text}"
        );
        assert_eq!(read(&path).unwrap(), counts);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn the_threshold_and_the_toolchain_decide() {
        let old = [count("a", "build", 1000), count("a", "trace", 1000)];
        let new = [count("a", "build", 1021), count("a", "trace", 1019)];
        let c = compare_counts(&new, &old, 0.02);
        assert!(c.gating && c.failed(), "{c:?}");
        assert_eq!(c.comparisons[0].phase, "build", "regressions first: {c:?}");
        assert_eq!(c.comparisons[0].verdict, Verdict::Regressed);
        assert_eq!(c.comparisons[1].verdict, Verdict::Unchanged);
        assert!(c.note.contains("above +2% instructions"), "{}", c.note);
        let faster = compare_counts(&[count("a", "build", 900)], &old, 0.02);
        assert!(!faster.failed() && faster.comparisons[0].verdict == Verdict::Improved);
        assert_eq!(faster.one_side, vec!["only in baseline: a tree objects 1000 trace".to_string()]);
        let other = [InstructionCount { rustc: "rustc 1.96.0".into(), ..new[0].clone() }];
        let info = compare_counts(&other, &old, 0.02);
        assert!(!info.gating && !info.failed() && info.regressions().count() == 1, "{info:?}");
        assert!(info.note.starts_with("for information only") && info.note.contains("rustc 1.96.0"), "{}", info.note);
    }
}
