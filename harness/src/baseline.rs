//! `harness baseline save`: store a run folder as a named baseline under `results/baselines/NAME/`.

use schema::column;
use std::path::{Path, PathBuf};

use crate::error::Error;
use crate::run::{CONFIG_COPY, RUNS_CSV};

/// Files a baseline keeps (the rest can be rebuilt with `harness report`; instructions.csv where `harness
/// instructions` counted the run).
const KEPT: &[&str] = &[RUNS_CSV, CONFIG_COPY, "summary.csv", "REPORT.md", report::check::instructions::FILE];

/// Where baselines live.
pub fn baselines_dir() -> PathBuf {
    PathBuf::from("results").join("baselines")
}

/// Copies `run_dir`'s rows, config, summary and report to `results/baselines/<name>/` (never over an
/// existing baseline unless `force`), with a note of where it came from.
pub fn save(run_dir: &Path, name: &str, force: bool) -> Result<PathBuf, Error> {
    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') {
        return Err(Error::Input(format!("baseline name {name:?} is not valid (allowed: letters, digits, '-', '_')")));
    }
    for f in [RUNS_CSV, CONFIG_COPY] {
        if !run_dir.join(f).is_file() {
            return Err(Error::Input(format!("{}: no {f} here (not a run folder)", run_dir.display())));
        }
    }
    let dest = baselines_dir().join(name);
    if dest.exists() && !force {
        return Err(Error::Input(format!("{}: baseline exists; use --force to replace it", dest.display())));
    }
    let io = |p: &Path, e: std::io::Error| Error::Run(format!("{}: {e}", p.display()));
    if dest.exists() {
        std::fs::remove_dir_all(&dest).map_err(|e| io(&dest, e))?;
    }
    std::fs::create_dir_all(&dest).map_err(|e| io(&dest, e))?;
    for f in KEPT.iter().filter(|f| run_dir.join(f).is_file()) {
        std::fs::copy(run_dir.join(f), dest.join(f)).map_err(|e| io(&dest.join(f), e))?;
    }
    let text = std::fs::read_to_string(run_dir.join(RUNS_CSV)).map_err(|e| io(&run_dir.join(RUNS_CSV), e))?;
    let rows = schema::row::read_rows(&text)
        .map_err(|e| Error::Input(format!("{}: {e}", run_dir.join(RUNS_CSV).display())))?;
    let field = |name: &str| rows.first().and_then(|r| r.cell(name)).map(|c| c.to_string()).unwrap_or_default();
    let note = format!(
        "# Baseline `{name}`\n\nSaved from `{}` by `harness baseline save`. Rows: {}. Recorded at commit {} (dirty: {}) on {} \
         ({} logical cores), {}.\n\nCompare a new run with it: `harness check <run dir> --baseline {}`.\n",
        run_dir.display(),
        rows.len(),
        field(column::git_commit),
        field(column::git_dirty),
        field(column::cpu_model),
        field(column::logical_cores),
        field(column::timestamp),
        dest.display()
    );
    std::fs::write(dest.join("BASELINE.md"), note).map_err(|e| io(&dest, e))?;
    Ok(dest)
}
