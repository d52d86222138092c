//! Turns the rows of a run directory (`runs.csv`, see ROWS.md) into summaries, figures, claim
//! verdicts and a Markdown report.
//!
//! Stages: [`rows`] reads the CSV with polars; [`summary`] aggregates per configuration; [`pool`]
//! pools samples into points (seeds pooled) and matches series against each other; [`claims`] and
//! the figures work on those points; [`markdown`] writes REPORT.md. Intervals come from [`stats`]: the
//! median's distribution-free 95% interval, and a bootstrap seeded from fixed keys for a ratio of two independent
//! medians, so reports are reproducible.

pub mod check;
pub mod headline;
pub mod history;
pub mod spec;

mod claims;
mod error;
pub(crate) mod figures;
mod markdown;
mod pool;
pub mod reproduction;
mod rows;
pub mod site;
pub mod stats;
mod summary;

use std::fs::File;
use std::path::{Path, PathBuf};

use polars_core::prelude::DataFrame;
use polars_io::prelude::{CsvWriter, ParquetWriter, SerWriter};

pub use claims::ClaimResult;
pub use error::Error;
pub use pool::RoundRatios;
use spec::ReportSpec;

/// The distinct values of `values`, in order of appearance.
pub fn distinct<T: PartialEq>(values: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut out = Vec::new();
    for value in values {
        if !out.contains(&value) {
            out.push(value);
        }
    }
    out
}

/// The claims of `spec` that held in the rows of the run folder `recorded` and fail at every point in those of
/// `dir`: answers the code no longer gives ([`claims::lost`]).
pub fn lost_claims(recorded: &Path, dir: &Path, spec: &ReportSpec) -> Result<Vec<ClaimResult>, Error> {
    let then = claims::check_all(&rows::read(&recorded.join("runs.csv"))?, spec);
    let now = claims::check_all(&rows::read(&dir.join("runs.csv"))?, spec);
    Ok(claims::lost(&then, &now).into_iter().cloned().collect())
}

/// What `write` produced.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// One result per claim of the spec, in order.
    pub claims: Vec<ClaimResult>,
    /// Every file written.
    pub files: Vec<PathBuf>,
}

/// Rebuilds runs.parquet, summary.csv, summary.parquet, figures/*.svg|png and REPORT.md in `dir` from `dir/runs.csv`.
pub fn write(dir: &Path, spec: &ReportSpec) -> Result<Outcome, Error> {
    let runs_csv = dir.join("runs.csv");
    let rows = rows::read(&runs_csv)?;
    let mut files = Vec::new();

    let runs_parquet = dir.join("runs.parquet");
    write_parquet(&runs_parquet, &mut rows.frame.clone())?;
    files.push(runs_parquet);

    let summary_csv = dir.join("summary.csv");
    let mut summary = summary::summarise(&rows, spec).map_err(|e| Error::write(&summary_csv, e))?;
    write_csv(&summary_csv, &mut summary)?;
    files.push(summary_csv);
    let summary_parquet = dir.join("summary.parquet");
    write_parquet(&summary_parquet, &mut summary)?;
    files.push(summary_parquet);

    let claims = claims::check_all(&rows, spec);
    files.extend(figures::draw_all(dir, &rows, spec)?);

    let report = dir.join("REPORT.md");
    let text = markdown::report(&rows, spec, &claims) + &reproduction::report_section(dir)?;
    std::fs::write(&report, text).map_err(|e| Error::write(&report, e))?;
    files.push(report);
    Ok(Outcome { claims, files })
}

fn write_csv(path: &Path, frame: &mut DataFrame) -> Result<(), Error> {
    let file = File::create(path).map_err(|e| Error::write(path, e))?;
    CsvWriter::new(file).include_header(true).finish(frame).map_err(|e| Error::write(path, e))
}

fn write_parquet(path: &Path, frame: &mut DataFrame) -> Result<(), Error> {
    let file = File::create(path).map_err(|e| Error::write(path, e))?;
    ParquetWriter::new(file).finish(frame).map(|_| ()).map_err(|e| Error::write(path, e))
}
