//! Rendering a [`CheckOutcome`]: a Markdown section for CI logs and the `check.json` document.

use std::fmt::Write as _;

use serde::Serialize;

use super::{CheckOutcome, CounterChange, Estimate, SpeedupComparison, SpeedupVerdict};
use crate::markdown::{cell, num};

impl CheckOutcome {
    /// A Markdown section for CI logs: overall result, counter table, speedup table (regressions first).
    pub fn markdown(&self) -> String {
        let mut md = String::from("## Regression check\n\n");
        let mode = if self.timings_for_information {
            "timings: compared for information only (the baseline may come from another machine); the gate is the exact counters"
        } else {
            "timings: single-thread speedups gate the check"
        };
        let _ = writeln!(md, "{mode}\n");
        let _ = writeln!(md, "**{}** — {}\n", if self.failed { "FAIL" } else { "PASS" }, self.reasons());
        counter_table(&mut md, self);
        if !self.missing.is_empty() {
            md.push_str("Configurations on one side only:\n\n");
            for m in &self.missing {
                let _ = writeln!(md, "- {}", m);
            }
            md.push('\n');
        }
        speedup_table(&mut md, &self.speedups);
        md
    }

    /// Why the check passed or failed, in one line.
    fn reasons(&self) -> String {
        let regressions: Vec<String> = self
            .speedups
            .iter()
            .filter(|s| s.gating && s.verdict == SpeedupVerdict::Regressed)
            .map(|s| format!("{} at {}", s.series, s.point))
            .collect();
        let mut reasons = Vec::new();
        if !regressions.is_empty() {
            reasons.push(format!("{} gating regression(s): {}", regressions.len(), regressions.join("; ")));
        }
        // Without a gating regression, the check fails exactly when these were not accepted.
        let accepted = if !self.failed {
            " (accepted)"
        } else if regressions.is_empty() {
            " (not accepted)"
        } else {
            ""
        };
        if !self.counter_changes.is_empty() {
            reasons.push(format!("{} counter change(s){accepted}", self.counter_changes.len()));
        }
        if !self.missing.is_empty() {
            reasons.push(format!("{} configuration(s) on one side only{accepted}", self.missing.len()));
        }
        if reasons.is_empty() {
            format!("no gating regression among {} speedup comparison(s); counters identical", self.speedups.len())
        } else {
            reasons.join("; ")
        }
    }

    /// Every measure as a pretty-printed JSON document (`check.json`): failed, common_configurations,
    /// speedups (value, lower, upper of old, new and ratio; verdict; gating), counter_changes, missing.
    /// Non-finite numbers are written as `null`.
    pub fn to_json(&self) -> String {
        let document = JsonOutcome {
            failed: self.failed,
            common_configurations: self.common,
            speedups: self.speedups.iter().map(JsonSpeedup::from).collect(),
            counter_changes: &self.counter_changes,
            missing: &self.missing,
        };
        let mut json = serde_json::to_string_pretty(&document).expect("a check outcome always serializes");
        json.push('\n');
        json
    }
}

/// The counter table, or a line saying every common configuration's counters are identical.
fn counter_table(md: &mut String, outcome: &CheckOutcome) {
    if outcome.counter_changes.is_empty() {
        let _ = writeln!(md, "counters: all {} configurations identical\n", outcome.common);
        return;
    }
    md.push_str("| configuration | column | old → new |\n|---|---|---|\n");
    for c in &outcome.counter_changes {
        let _ = writeln!(
            md,
            "| `{}` {}, {} | {} | {} → {} |",
            c.config_id,
            cell(&c.series),
            cell(&c.settings),
            c.column,
            cell(&c.old),
            cell(&c.new)
        );
    }
    md.push('\n');
}

/// The speedup table, regressions first, then improvements; nothing without speedups.
fn speedup_table(md: &mut String, speedups: &[SpeedupComparison]) {
    if speedups.is_empty() {
        return;
    }
    md.push_str(
        "| series | point | baseline speedup [95% CI] | new speedup [95% CI] | new/old [95% CI] | verdict | gates? |\n",
    );
    md.push_str("|---|---|---|---|---|---|---|\n");
    let mut rows: Vec<&SpeedupComparison> = speedups.iter().collect();
    rows.sort_by_key(|s| match s.verdict {
        SpeedupVerdict::Regressed => 0,
        SpeedupVerdict::Improved => 1,
        SpeedupVerdict::Unchanged => 2,
    });
    for s in rows {
        let verdict = match s.verdict {
            SpeedupVerdict::Regressed => "**regressed**",
            v => v.word(),
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} [{}, {}] | {} [{}, {}] | {} [{}, {}] | {} | {} |",
            cell(&s.series),
            cell(&s.point),
            num(s.old.value),
            num(s.old.lo),
            num(s.old.hi),
            num(s.new.value),
            num(s.new.lo),
            num(s.new.hi),
            num(s.ratio),
            num(s.lo),
            num(s.hi),
            verdict,
            if s.gating { "yes" } else { "no" }
        );
    }
    md.push('\n');
}

/// The `check.json` document.
#[derive(Serialize)]
struct JsonOutcome<'a> {
    failed: bool,
    common_configurations: usize,
    speedups: Vec<JsonSpeedup<'a>>,
    counter_changes: &'a [CounterChange],
    missing: &'a [String],
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
    gating: bool,
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
            gating: s.gating,
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

    #[test]
    fn json_keeps_its_keys_and_writes_non_finite_numbers_as_null() {
        let outcome = CheckOutcome {
            counter_changes: vec![CounterChange {
                config_id: "00ff".into(),
                series: "a \"quoted\"\tseries\n".into(),
                settings: "random-spheres objects 10".into(),
                column: "rays".into(),
                old: "1".into(),
                new: "2".into(),
            }],
            missing: vec!["only in run: x".into()],
            speedups: vec![SpeedupComparison {
                series: "tree".into(),
                point: "objects 10 (threads 1)".into(),
                old: Estimate { value: 2.0, lo: 1.5, hi: 2.5 },
                new: Estimate { value: f64::NAN, lo: f64::INFINITY, hi: f64::NEG_INFINITY },
                ratio: 0.5,
                lo: 0.25,
                hi: 0.75,
                verdict: SpeedupVerdict::Regressed,
                gating: true,
            }],
            common: 3,
            failed: true,
            timings_for_information: false,
        };
        let json = outcome.to_json();
        assert!(json.ends_with("}\n"), "{json}");
        let value: serde_json::Value = serde_json::from_str(&json).unwrap();
        let expected = serde_json::json!({
            "failed": true,
            "common_configurations": 3,
            "speedups": [{
                "series": "tree",
                "point": "objects 10 (threads 1)",
                "old": {"value": 2.0, "lower": 1.5, "upper": 2.5},
                "new": {"value": null, "lower": null, "upper": null},
                "ratio": {"value": 0.5, "lower": 0.25, "upper": 0.75},
                "verdict": "regressed",
                "gating": true
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
