//! Reading `runs.csv` into typed rows (`schema::Row`, the struct the harness writes), the polars frame
//! built from them column by column as the schema declares, and a plain per-row view.

use std::collections::HashMap;
use std::path::Path;
use std::sync::OnceLock;

use polars_core::prelude::*;
use schema::row::{COLUMNS, Kind};
use schema::{Cell, Row};

use crate::error::Error;

/// Setting columns (the schema's axes, in row order); a configuration is series + these.
pub static SETTINGS: std::sync::LazyLock<Vec<&'static str>> = std::sync::LazyLock::new(schema::row::setting_names);

/// The settings and `machine_id`: runs equal on these stand for one point (`schema::row::point_names`).
pub static POINT: std::sync::LazyLock<Vec<&'static str>> = std::sync::LazyLock::new(schema::row::point_names);

/// Index of each column in `schema::row::COLUMNS`.
pub(crate) fn index_of(column: &str) -> Option<usize> {
    static INDEX: OnceLock<HashMap<&'static str, usize>> = OnceLock::new();
    INDEX.get_or_init(|| COLUMNS.iter().enumerate().map(|(i, c)| (c.name, i)).collect()).get(column).copied()
}

/// One recorded repetition: the typed row, and every column as text and (numeric columns) as a number.
#[derive(Clone, Debug)]
pub struct Run {
    /// The row as recorded.
    pub row: Row,
    text: Vec<String>,
    num: Vec<f64>,
}

impl Run {
    fn new(row: Row) -> Run {
        let cells: Vec<Cell> = COLUMNS.iter().map(|c| row.cell(c.name).expect("declared column")).collect();
        let mut num: Vec<f64> = cells.iter().map(Cell::number).collect();
        // `threads` reads as a number of threads used (`all` resolved), as a figure axis or a claim needs it.
        if row.threads_used > 0 {
            num[index_of(schema::Axis::threads.key()).expect("declared column")] = f64::from(row.threads_used);
        }
        Run { text: cells.iter().map(|c| c.to_string()).collect(), num, row }
    }

    /// True when the run's setting columns take one of the allowed values for every filter entry
    /// (`threads = "all"` also matches rows recorded before `all` stayed symbolic, whose `threads` holds the
    /// logical cores of the machine that recorded them). A `threads` entry passes serial runs, to which thread
    /// counts do not apply: "rayon bands on all cores against serial" keeps its serial side.
    pub fn passes(&self, filter: &[(String, Vec<String>)]) -> bool {
        let threads = schema::Axis::threads.key();
        let threads_all = |column: &str, a: &str| {
            column == threads
                && schema::Threads::from_word(a)
                    .is_some_and(|t| f64::from(t.resolve(self.row.logical_cores as usize)) == self.num(column))
        };
        let serial = self.text(schema::Axis::strategy.key()) == tracer::executor::StrategyKind::Serial.name();
        filter.iter().all(|(column, allowed)| {
            (column == threads && serial) || allowed.iter().any(|a| a == self.text(column) || threads_all(column, a))
        })
    }

    /// A column's value as text (`""` for a column the schema does not declare).
    pub fn text(&self, column: &str) -> &str {
        index_of(column).map_or("", |i| self.text[i].as_str())
    }

    /// The text of the column at `index` of `schema::row::COLUMNS` (see [`index_of`]): no lookup by name.
    pub(crate) fn text_at(&self, index: usize) -> &str {
        &self.text[index]
    }

    /// A numeric column's value (NaN when not numeric or not declared).
    pub fn num(&self, column: &str) -> f64 {
        index_of(column).map_or(f64::NAN, |i| self.num[i])
    }

    /// The machine that ran it, as `cpu_model (machine_id)`.
    pub fn machine(&self) -> String {
        format!("{} ({})", self.text(schema::column::cpu_model), self.text(schema::column::machine_id))
    }

    /// The configuration id.
    pub fn config_id(&self) -> &str {
        &self.row.config_id
    }

    /// The series label.
    pub fn series(&self) -> &str {
        &self.row.series
    }
}

/// The rows of one run directory: the polars frame and the per-row view.
pub struct Rows {
    /// All rows that were timed, one column per schema column.
    pub frame: DataFrame,
    /// The same rows, one `Run` each, in file order.
    pub runs: Vec<Run>,
    /// Rows of configurations that failed validation (never timed; kept out of `frame` and `runs`).
    pub failed: Vec<Run>,
    /// The columns the file's header has: an older row format lacks the columns added since, which `frame` and
    /// `runs` hold at their defaults.
    pub recorded: std::collections::BTreeSet<String>,
}

impl Rows {
    /// Whether `column` exists and is numeric.
    pub fn is_numeric(&self, column: &str) -> bool {
        self.frame.schema().get(column).is_some_and(|dtype| dtype.is_primitive_numeric())
    }
}

/// Reads and checks `path` (a `runs.csv`).
pub fn read(path: &Path) -> Result<Rows, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
    let rows = schema::row::read_rows(&text).map_err(|e| match e.missing_column {
        Some(column) => Error::MissingColumn { path: path.into(), column: column.to_string() },
        None => Error::read(path, e),
    })?;
    if rows.is_empty() {
        return Err(Error::NoRows { path: path.into() });
    }
    let (failed, timed): (Vec<Row>, Vec<Row>) =
        rows.into_iter().partition(|r| r.validation == schema::ValidationStatus::Failed);
    let runs: Vec<Run> = timed.into_iter().map(Run::new).collect();
    let frame = frame(&runs).map_err(|e| Error::read(path, e))?;
    let header = text.lines().next().unwrap_or_default().split(',');
    let recorded = header.map(|c| c.trim().trim_matches('"').to_string()).collect();
    Ok(Rows { frame, runs, failed: failed.into_iter().map(Run::new).collect(), recorded })
}

/// The polars frame of `runs`: every schema column, typed as declared.
fn frame(runs: &[Run]) -> PolarsResult<DataFrame> {
    let columns = COLUMNS
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let name = c.name.into();
            match c.kind {
                Kind::Text => Column::new(name, runs.iter().map(|r| r.text[i].as_str()).collect::<Vec<_>>()),
                Kind::Int => Column::new(name, runs.iter().map(|r| r.num[i] as i64).collect::<Vec<_>>()),
                Kind::Float => Column::new(name, runs.iter().map(|r| r.num[i]).collect::<Vec<_>>()),
                Kind::Bool => Column::new(name, runs.iter().map(|r| r.text[i] == "true").collect::<Vec<_>>()),
            }
        })
        .collect();
    DataFrame::new(runs.len(), columns)
}
