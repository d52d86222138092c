//! Rendering a [`CheckOutcome`]: a Markdown section for CI logs and the `check.json` document.

use std::fmt::Write as _;

use serde::Serialize;

use super::{
    CheckOutcome, CounterChange, Estimate, InstructionComparison, SpeedupComparison, TimeComparison, TimeRatio,
    TimingMode, Verdict,
};
use crate::markdown::{cell, num};

impl CheckOutcome {
    /// A Markdown section for CI logs: the timing mode, overall result, counter table, instruction counts, times
    /// (regressions first) and speedups.
    pub fn markdown(&self) -> String {
        let mut md = String::from("## Regression check\n\n");
        let _ = writeln!(md, "{}\n", self.mode.line());
        let _ = writeln!(md, "**{}** — {}\n", if self.failed() { "FAIL" } else { "PASS" }, self.reasons());
        counter_table(&mut md, self);
        if !self.missing.is_empty() {
            md.push_str("Configurations on one side only:\n\n");
            for m in &self.missing {
                let _ = writeln!(md, "- {}", m);
            }
            md.push('\n');
        }
        instruction_table(&mut md, self);
        time_table(&mut md, self);
        speedup_table(&mut md, &self.speedups);
        md
    }

    /// Why the check passed or failed, in one line.
    fn reasons(&self) -> String {
        let mut reasons = Vec::new();
        let instructions: Vec<String> = self
            .instructions
            .regressions()
            .map(|c| format!("{} objects {} {} {}", c.series, c.objects, c.phase, percent(c.ratio)))
            .collect();
        if self.instructions.failed() {
            reasons.push(format!(
                "{} instruction-count regression(s): {}",
                instructions.len(),
                instructions.join("; ")
            ));
        }
        let failing: Vec<String> = self.times.iter().filter(|t| t.fails()).map(describe_time).collect();
        let confirmed = self.times.iter().filter(|t| t.fails()).all(|t| t.confirmation.is_some());
        if !failing.is_empty() {
            let how = if confirmed { "confirmed by a second measurement" } else { "not measured again" };
            reasons.push(format!("{} time regression(s) {how}: {}", failing.len(), failing.join("; ")));
        }
        let cleared = self.times.iter().filter(|t| t.flagged() && !t.fails()).count();
        if cleared > 0 {
            reasons.push(format!("{cleared} time regression(s) of the first measurement not confirmed by the second"));
        }
        // Without another failure, the check fails exactly when these were not accepted.
        let other_failure = self.instructions.failed() || !failing.is_empty();
        let accepted = if self.accept_counter_changes {
            " (accepted)"
        } else if other_failure {
            ""
        } else {
            " (not accepted)"
        };
        if !self.counter_changes.is_empty() {
            reasons.push(format!("{} counter change(s){accepted}", self.counter_changes.len()));
        }
        if !self.missing.is_empty() {
            reasons.push(format!("{} configuration(s) on one side only{accepted}", self.missing.len()));
        }
        if reasons.is_empty() {
            let gated = self.times.iter().filter(|t| t.gating).count();
            let counted = if self.instructions.gating {
                format!(
                    "{} instruction counts within +{}%",
                    self.instructions.comparisons.len(),
                    self.instructions.threshold * 100.0
                )
            } else {
                "instruction counts not gating".to_string()
            };
            let times = match gated {
                0 => format!("{} phase times for information", self.times.len()),
                _ => format!("{gated} of {} phase times gated, none regressed", self.times.len()),
            };
            format!("{counted}; {times}; counters identical")
        } else {
            reasons.join("; ")
        }
    }

    /// Every measure as a pretty-printed JSON document (`check.json`): failed, timing_mode, common_configurations,
    /// instructions (gating, note, threshold, comparisons, one_side), times (per configuration and phase: the
    /// first measurement and the confirmation, each with old, new and ratio as value, lower, upper; verdicts;
    /// gating; fails), speedups (value, lower, upper of old, new and ratio; verdict), counter_changes, missing.
    /// Non-finite numbers are written as `null`.
    pub fn to_json(&self) -> String {
        let (mode, machine_id, boot_id, reason) = match &self.mode {
            TimingMode::SameMachine { machine_id, boot_id } => {
                ("same-machine", Some(machine_id.as_str()), Some(boot_id.as_str()), None)
            }
            TimingMode::Information { reason } => ("information", None, None, Some(reason.as_str())),
        };
        let document = JsonOutcome {
            failed: self.failed(),
            timing_mode: JsonMode { mode, machine_id, boot_id, reason, line: self.mode.line() },
            common_configurations: self.common,
            instructions: JsonInstructions {
                gating: self.instructions.gating,
                note: &self.instructions.note,
                threshold: self.instructions.threshold,
                comparisons: &self.instructions.comparisons,
                one_side: &self.instructions.one_side,
            },
            times: self.times.iter().map(JsonTime::from).collect(),
            speedups: self.speedups.iter().map(JsonSpeedup::from).collect(),
            counter_changes: &self.counter_changes,
            missing: &self.missing,
        };
        let mut json = serde_json::to_string_pretty(&document).expect("a check outcome always serializes");
        json.push('\n');
        json
    }
}

/// `series settings metric +3.1% time` of a time comparison (the confirmation's change when there is one; +: the
/// run took longer).
fn describe_time(t: &TimeComparison) -> String {
    let ratio = t.confirmation.as_ref().map_or(t.first.ratio.value, |c| c.ratio.value);
    format!("{} {} {} {} time", t.series, t.settings, t.metric, percent(ratio))
}

/// A ratio and its interval as signed percentage changes, e.g. `+3.1% [+1.0%, +5.2%]`.
fn percent_interval(e: &Estimate) -> String {
    format!("{} [{}, {}]", percent(e.value), percent(e.lo), percent(e.hi))
}

/// A ratio as a signed percentage change, e.g. `+3.1%`.
fn percent(ratio: f64) -> String {
    format!("{:+.1}%", (ratio - 1.0) * 100.0)
}

/// A table's configuration cell: its id, series and settings.
fn configuration(id: &str, series: &str, settings: &str) -> String {
    format!("`{id}` {}, {}", cell(series), cell(settings))
}

/// Writes one table row of `cells`.
fn row(md: &mut String, cells: &[&str]) {
    md.push('|');
    for c in cells {
        let _ = write!(md, " {c} |");
    }
    md.push('\n');
}

/// The counter table, or a line saying every common configuration's counters are identical.
fn counter_table(md: &mut String, outcome: &CheckOutcome) {
    if outcome.counter_changes.is_empty() {
        let _ = writeln!(md, "counters: all {} configurations identical\n", outcome.common);
        return;
    }
    md.push_str("| configuration | column | old → new |\n|---|---|---|\n");
    for c in &outcome.counter_changes {
        let change = format!("{} → {}", cell(&c.old), cell(&c.new));
        row(md, &[&configuration(&c.config_id, &c.series, &c.settings), &c.column, &change]);
    }
    md.push('\n');
}

/// The instruction-count line and table (regressions first), and phases counted on one side only.
fn instruction_table(md: &mut String, outcome: &CheckOutcome) {
    let check = &outcome.instructions;
    let _ = writeln!(md, "instructions: {}\n", check.note);
    if !check.comparisons.is_empty() {
        let misses = check.comparisons.iter().any(|c| c.d1_misses.is_some() || c.ll_misses.is_some());
        md.push_str("| configuration | phase | baseline instructions | run instructions | change | verdict |");
        md.push_str(if misses { " D1 misses old → new | LL misses old → new |\n" } else { "\n" });
        md.push_str(if misses { "|---|---|---|---|---|---|---|---|\n" } else { "|---|---|---|---|---|---|\n" });
        for c in &check.comparisons {
            let _ = write!(
                md,
                "| `{}` {} objects {} | {} | {} | {} | {} | {} |",
                c.config_id,
                cell(&c.series),
                c.objects,
                c.phase,
                c.old,
                c.new,
                percent(c.ratio),
                instruction_verdict(c, check.gating)
            );
            if misses {
                let pair = |p: Option<(u64, u64)>| p.map_or("—".to_string(), |(o, n)| format!("{o} → {n}"));
                let _ = write!(md, " {} | {} |", pair(c.d1_misses), pair(c.ll_misses));
            }
            md.push('\n');
        }
        md.push('\n');
    }
    if !check.one_side.is_empty() {
        md.push_str("Phases counted on one side only:\n\n");
        for m in &check.one_side {
            let _ = writeln!(md, "- {}", cell(m));
        }
        md.push('\n');
    }
}

fn instruction_verdict(c: &InstructionComparison, gating: bool) -> &'static str {
    match (c.verdict, gating) {
        (Verdict::Regressed, true) => "**regressed**",
        (v, _) => v.word(),
    }
}

/// The phase-time table, failures first, then other regressions, improvements.
fn time_table(md: &mut String, outcome: &CheckOutcome) {
    if outcome.times.is_empty() {
        return;
    }
    md.push_str(
        "| configuration | phase | threads | baseline median [95% CI] | run median [95% CI] | time change [95% CI] \
         (+ = slower) | verdict | gates? | measured again: median, time change [95% CI], verdict |\n",
    );
    md.push_str("|---|---|---|---|---|---|---|---|---|\n");
    let mut rows: Vec<&TimeComparison> = outcome.times.iter().collect();
    rows.sort_by_key(|t| (!t.fails(), t.first.verdict.rank()));
    let interval = |e: &Estimate| format!("{} [{}, {}]", num(e.value), num(e.lo), num(e.hi));
    for t in rows {
        let verdict = |r: &TimeRatio| match r.verdict {
            Verdict::Regressed if t.gating => "**regressed**",
            v => v.word(),
        };
        let again = t.confirmation.as_ref().map_or_else(
            || if t.flagged() { "not measured again".to_string() } else { "—".to_string() },
            |c| format!("{}, {}, {}", num(c.new.value), percent_interval(&c.ratio), verdict(c)),
        );
        row(
            md,
            &[
                &configuration(&t.config_id, &t.series, &t.settings),
                t.metric,
                &cell(&t.threads),
                &interval(&t.first.old),
                &interval(&t.first.new),
                &percent_interval(&t.first.ratio),
                verdict(&t.first),
                if t.gating { "yes" } else { "no" },
                &again,
            ],
        );
    }
    md.push('\n');
}

/// The speedup table (for information), regressions first, then improvements; nothing without speedups.
fn speedup_table(md: &mut String, speedups: &[SpeedupComparison]) {
    if speedups.is_empty() {
        return;
    }
    md.push_str("Speedups over the reference series (for information; the phase times above gate):\n\n");
    md.push_str(
        "| series | point | baseline speedup [95% CI] | new speedup [95% CI] | speedup change [95% CI] (+ = \
         faster) | verdict |\n",
    );
    md.push_str("|---|---|---|---|---|---|\n");
    let mut rows: Vec<&SpeedupComparison> = speedups.iter().collect();
    rows.sort_by_key(|s| s.verdict.rank());
    for s in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} [{}, {}] | {} [{}, {}] | {} [{}, {}] | {} |",
            cell(&s.series),
            cell(&s.point),
            num(s.old.value),
            num(s.old.lo),
            num(s.old.hi),
            num(s.new.value),
            num(s.new.lo),
            num(s.new.hi),
            percent(s.ratio),
            percent(s.lo),
            percent(s.hi),
            s.verdict.word()
        );
    }
    md.push('\n');
}

/// The `check.json` document.
#[derive(Serialize)]
struct JsonOutcome<'a> {
    failed: bool,
    timing_mode: JsonMode<'a>,
    common_configurations: usize,
    instructions: JsonInstructions<'a>,
    times: Vec<JsonTime<'a>>,
    speedups: Vec<JsonSpeedup<'a>>,
    counter_changes: &'a [CounterChange],
    missing: &'a [String],
}

/// `timing_mode`.
#[derive(Serialize)]
struct JsonMode<'a> {
    /// `same-machine` or `information`.
    mode: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    machine_id: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    boot_id: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    reason: Option<&'a str>,
    line: String,
}

/// `instructions`.
#[derive(Serialize)]
struct JsonInstructions<'a> {
    gating: bool,
    note: &'a str,
    threshold: f64,
    comparisons: &'a [InstructionComparison],
    one_side: &'a [String],
}

/// One entry of `times`.
#[derive(Serialize)]
struct JsonTime<'a> {
    config_id: &'a str,
    series: &'a str,
    settings: &'a str,
    threads: &'a str,
    metric: &'a str,
    gating: bool,
    first: JsonTimeRatio,
    confirmation: Option<JsonTimeRatio>,
    fails: bool,
}

impl<'a> From<&'a TimeComparison> for JsonTime<'a> {
    fn from(t: &'a TimeComparison) -> Self {
        JsonTime {
            config_id: &t.config_id,
            series: &t.series,
            settings: &t.settings,
            threads: &t.threads,
            metric: t.metric,
            gating: t.gating,
            first: t.first.into(),
            confirmation: t.confirmation.map(Into::into),
            fails: t.fails(),
        }
    }
}

/// Medians and ratio of one measurement.
#[derive(Serialize)]
struct JsonTimeRatio {
    old: JsonEstimate,
    new: JsonEstimate,
    ratio: JsonEstimate,
    verdict: &'static str,
}

impl From<TimeRatio> for JsonTimeRatio {
    fn from(r: TimeRatio) -> Self {
        JsonTimeRatio { old: r.old.into(), new: r.new.into(), ratio: r.ratio.into(), verdict: r.verdict.word() }
    }
}

/// One entry of `speedups`.
#[derive(Serialize)]
struct JsonSpeedup<'a> {
    series: &'a str,
    point: &'a str,
    old: JsonEstimate,
    new: JsonEstimate,
    ratio: JsonEstimate,
    verdict: &'static str,
}

impl<'a> From<&'a SpeedupComparison> for JsonSpeedup<'a> {
    fn from(s: &'a SpeedupComparison) -> Self {
        JsonSpeedup {
            series: &s.series,
            point: &s.point,
            old: s.old.into(),
            new: s.new.into(),
            ratio: Estimate { value: s.ratio, lo: s.lo, hi: s.hi }.into(),
            verdict: s.verdict.word(),
        }
    }
}

/// A value with its interval; serde_json writes non-finite numbers as `null`.
#[derive(Serialize)]
struct JsonEstimate {
    value: f64,
    lower: f64,
    upper: f64,
}

impl From<Estimate> for JsonEstimate {
    fn from(e: Estimate) -> Self {
        JsonEstimate { value: e.value, lower: e.lo, upper: e.hi }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::{InstructionCheck, TimeComparison};

    #[test]
    fn json_keeps_its_keys_and_writes_non_finite_numbers_as_null() {
        let e = |value, lo, hi| Estimate { value, lo, hi };
        let outcome = CheckOutcome {
            mode: TimingMode::SameMachine { machine_id: "3f2a00000000".into(), boot_id: "0b007".into() },
            counter_changes: vec![CounterChange {
                config_id: "00ff".into(),
                series: "a \"quoted\"\tseries\n".into(),
                settings: "random-spheres objects 10".into(),
                column: "rays".into(),
                old: "1".into(),
                new: "2".into(),
            }],
            missing: vec!["only in run: x".into()],
            instructions: InstructionCheck { note: "not compared".into(), threshold: 0.02, ..Default::default() },
            times: vec![TimeComparison {
                config_id: "00ff".into(),
                series: "tree".into(),
                settings: "random-spheres objects 10".into(),
                threads: "1".into(),
                metric: "trace_s",
                first: TimeRatio {
                    old: e(1.0, 0.9, 1.1),
                    new: e(1.5, 1.4, 1.6),
                    ratio: e(1.5, 1.3, 1.7),
                    verdict: Verdict::Regressed,
                },
                gating: true,
                confirmation: Some(TimeRatio {
                    old: e(1.0, 0.9, 1.1),
                    new: e(1.0, 0.95, 1.05),
                    ratio: e(1.0, 0.9, 1.1),
                    verdict: Verdict::Unchanged,
                }),
            }],
            speedups: vec![SpeedupComparison {
                series: "tree".into(),
                point: "objects 10 (threads 1)".into(),
                old: e(2.0, 1.5, 2.5),
                new: e(f64::NAN, f64::INFINITY, f64::NEG_INFINITY),
                ratio: 0.5,
                lo: 0.25,
                hi: 0.75,
                verdict: Verdict::Regressed,
            }],
            common: 3,
            accept_counter_changes: false,
        };
        let json = outcome.to_json();
        assert!(json.ends_with("}\n"), "{json}");
        let value: serde_json::Value = serde_json::from_str(&json).unwrap();
        let expected = serde_json::json!({
            "failed": true,
            "timing_mode": {
                "mode": "same-machine",
                "machine_id": "3f2a00000000",
                "boot_id": "0b007",
                "line": outcome.mode.line()
            },
            "common_configurations": 3,
            "instructions": {"gating": false, "note": "not compared", "threshold": 0.02, "comparisons": [], "one_side": []},
            "times": [{
                "config_id": "00ff",
                "series": "tree",
                "settings": "random-spheres objects 10",
                "threads": "1",
                "metric": "trace_s",
                "gating": true,
                "first": {
                    "old": {"value": 1.0, "lower": 0.9, "upper": 1.1},
                    "new": {"value": 1.5, "lower": 1.4, "upper": 1.6},
                    "ratio": {"value": 1.5, "lower": 1.3, "upper": 1.7},
                    "verdict": "regressed"
                },
                "confirmation": {
                    "old": {"value": 1.0, "lower": 0.9, "upper": 1.1},
                    "new": {"value": 1.0, "lower": 0.95, "upper": 1.05},
                    "ratio": {"value": 1.0, "lower": 0.9, "upper": 1.1},
                    "verdict": "unchanged"
                },
                "fails": false
            }],
            "speedups": [{
                "series": "tree",
                "point": "objects 10 (threads 1)",
                "old": {"value": 2.0, "lower": 1.5, "upper": 2.5},
                "new": {"value": null, "lower": null, "upper": null},
                "ratio": {"value": 0.5, "lower": 0.25, "upper": 0.75},
                "verdict": "regressed"
            }],
            "counter_changes": [{
                "config_id": "00ff",
                "series": "a \"quoted\"\tseries\n",
                "settings": "random-spheres objects 10",
                "column": "rays",
                "old": "1",
                "new": "2"
            }],
            "missing": ["only in run: x"]
        });
        assert_eq!(value, expected, "{json}");
    }
}
