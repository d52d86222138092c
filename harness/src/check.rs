//! `harness check`: compare a run with a stored baseline of the same experiment; exit 1 on a regression.
//!
//! The first line printed says which timing mode applied and why (`report::check::TimingMode`). A configuration
//! whose trace or build time is flagged as a regression (same machine only) is measured again before the check
//! fails: its runs are repeated — warm-ups and repetitions, validated first, as `harness run` does it, from the
//! run folder's config copy — into `RUN_DIR/confirm.csv` (never into runs.csv), and the check fails only if the
//! second measurement regressed too. The table shows both.

use std::path::{Path, PathBuf};

use report::check::{CheckOptions, compare};

use crate::config::Experiment;
use crate::error::Error;
use crate::plan::Plan;
use crate::run::{CONFIG_COPY, RUNS_CSV};

/// The file of a check's second measurements, in the run folder.
pub const CONFIRM_CSV: &str = "confirm.csv";

/// What `harness check` was asked.
pub struct CheckRequest<'a> {
    pub run_dir: &'a Path,
    pub baseline: &'a Path,
    pub options: CheckOptions,
    pub json: Option<PathBuf>,
    /// Measure flagged configurations again before failing on their times.
    pub confirm: bool,
}

/// Prints the comparison as Markdown, writes its JSON, and fails (exit 1) when the gate fails.
pub fn run(request: &CheckRequest<'_>) -> Result<(), Error> {
    for dir in [request.run_dir, request.baseline] {
        for f in [RUNS_CSV, CONFIG_COPY] {
            if !dir.join(f).is_file() {
                return Err(Error::Input(format!("{}: no {f} here (not a run folder)", dir.display())));
            }
        }
    }
    let exp = Experiment::load(&request.run_dir.join(CONFIG_COPY))?;
    let base = Experiment::load(&request.baseline.join(CONFIG_COPY))?;
    if exp.name != base.name {
        return Err(Error::Input(format!(
            "{}: experiment {:?} does not match the baseline's {:?} ({})",
            request.run_dir.display(),
            exp.name,
            base.name,
            request.baseline.display()
        )));
    }
    let spec = exp.report_spec(vec![]);
    let input = |e: report::Error| Error::Input(e.to_string());
    let mut outcome = compare(request.run_dir, request.baseline, &spec, &request.options).map_err(input)?;
    say!("{}", outcome.mode.line());
    let confirm_csv = request.run_dir.join(CONFIRM_CSV);
    let _ = std::fs::remove_file(&confirm_csv); // a file from an earlier check would be taken for this one's
    let flagged = outcome.to_confirm();
    if request.confirm && !flagged.is_empty() {
        let names: Vec<String> = outcome
            .times
            .iter()
            .filter(|t| t.flagged())
            .map(|t| format!("{} {} {}", t.series, t.settings, t.metric))
            .collect();
        say!(
            "measuring {} flagged configuration(s) again before failing ({}) into {}",
            flagged.len(),
            names.join("; "),
            confirm_csv.display()
        );
        measure_again(request.run_dir, &exp, &flagged, &confirm_csv)?;
        outcome.confirm(&confirm_csv, request.baseline, &request.options).map_err(input)?;
    }
    say!("{}", outcome.markdown());
    let json = request.json.clone().unwrap_or_else(|| request.run_dir.join("check.json"));
    std::fs::write(&json, outcome.to_json())
        .map_err(|e| Error::Run(format!("{}: cannot write: {e}", json.display())))?;
    say!("check: {}", json.display());
    if outcome.failed() {
        return Err(Error::Run("regression against the baseline (see the table above)".into()));
    }
    Ok(())
}

/// Runs configurations `ids` of the run folder's experiment again, as `harness run` does (the same sweep code,
/// filtered), and leaves their rows in `confirm_csv`.
///
/// The config copy is the text as written, so the run may have applied its `[quick]` overrides: the variant
/// whose plan holds every id with as many repetitions as the run recorded is taken (else the first holding them).
fn measure_again(run_dir: &Path, exp: &Experiment, ids: &[String], confirm_csv: &Path) -> Result<(), Error> {
    let runs = run_dir.join(RUNS_CSV);
    let text = std::fs::read_to_string(&runs).map_err(|e| Error::Input(format!("{}: {e}", runs.display())))?;
    let rows = schema::row::read_rows(&text).map_err(|e| Error::Input(format!("{}: {e}", runs.display())))?;
    let recorded = rows.iter().filter(|r| r.config_id == ids[0]).count() as u32;
    let cores = crate::plan::available_threads();
    let mut candidates = Vec::new();
    for variant in [exp.clone().quick(), exp.clone()] {
        let plan = Plan::new(&variant, cores)?;
        if ids.iter().all(|id| plan.configurations.iter().any(|c| &c.id == id)) {
            candidates.push((variant, plan));
        }
    }
    let pick = candidates
        .iter()
        .position(|(v, _)| (v.repetitions.min()..=v.repetitions.max()).contains(&recorded))
        .unwrap_or(0);
    let Some((variant, mut plan)) = candidates.into_iter().nth(pick) else {
        return Err(Error::Input(format!(
            "{}: the flagged configurations are not in the plan of {} (was it edited?)",
            run_dir.display(),
            run_dir.join(CONFIG_COPY).display()
        )));
    };
    plan.runs.retain(|r| ids.contains(&plan.configurations[r.config].id));
    let scratch = run_dir.join("confirm.tmp");
    let _ = std::fs::remove_dir_all(&scratch);
    crate::run::sweep(&variant, &plan, &scratch, crate::run::Existing::Replace)?;
    std::fs::rename(scratch.join(RUNS_CSV), confirm_csv)
        .map_err(|e| Error::Run(format!("{}: cannot write: {e}", confirm_csv.display())))?;
    let _ = std::fs::remove_dir_all(&scratch);
    Ok(())
}
