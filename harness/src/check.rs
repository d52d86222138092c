//! `harness check`: compare a run with a stored baseline of the same experiment; exit 1 on a regression.

use std::path::{Path, PathBuf};

use report::check::{CheckOptions, compare};

use crate::config::Experiment;
use crate::error::Error;
use crate::run::{CONFIG_COPY, RUNS_CSV};

/// What `harness check` was asked.
pub struct CheckRequest<'a> {
    pub run_dir: &'a Path,
    pub baseline: &'a Path,
    pub options: CheckOptions,
    pub json: Option<PathBuf>,
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
    let outcome = compare(request.run_dir, request.baseline, &spec, &request.options).map_err(|e| Error::Input(e.to_string()))?;
    println!("{}", outcome.markdown());
    let json = request.json.clone().unwrap_or_else(|| request.run_dir.join("check.json"));
    std::fs::write(&json, outcome.to_json()).map_err(|e| Error::Run(format!("{}: cannot write: {e}", json.display())))?;
    println!("check: {}", json.display());
    if outcome.failed {
        return Err(Error::Run("regression against the baseline (see the table above)".into()));
    }
    Ok(())
}
