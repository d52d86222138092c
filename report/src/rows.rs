//! Reading `runs.csv` (the row contract in ROWS.md) with polars, and a plain per-row view of it.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use polars::prelude::*;

use crate::error::Error;

/// Setting columns (ROWS.md: `scene` … `embree_isa`); a configuration is series + these.
pub const SETTINGS: [&str; 17] = [
    "scene",
    "objects",
    "seed",
    "accel",
    "split",
    "leaf_size",
    "sah_bins",
    "traversal",
    "strategy",
    "threads",
    "width",
    "height",
    "max_depth",
    "workload",
    "obvhs_build",
    "embree_build",
    "embree_isa",
];

/// Text columns added after the first row format; absent in older files.
const OPTIONAL_TEXT: [&str; 6] = ["obvhs_build", "embree_build", "embree_isa", "validation", "validated_against", "peer_info"];

/// Columns read as text even when every value looks like a number (hashes, commits, labels).
const TEXT: [&str; 16] = [
    "experiment",
    "config_id",
    "series",
    "scene",
    "accel",
    "split",
    "traversal",
    "strategy",
    "workload",
    "image_hash",
    "scene_fingerprint",
    "git_commit",
    "rustc",
    "cpu_model",
    "timestamp",
    "harness_version",
];

/// Integer columns.
const INTEGER: [&str; 15] = [
    "repetition",
    "objects",
    "seed",
    "leaf_size",
    "sah_bins",
    "threads",
    "width",
    "height",
    "max_depth",
    "rays",
    "tree_nodes",
    "tree_leaves",
    "tree_depth",
    "tree_bytes",
    "logical_cores",
];

/// Float columns.
const FLOAT: [&str; 11] = [
    "scene_s",
    "build_s",
    "trace_s",
    "encode_s",
    "total_s",
    "mrays_per_s",
    "nodes_per_ray",
    "box_tests_per_ray",
    "prim_tests_per_ray",
    "sah_cost",
    "load_avg_1m",
];

/// One recorded repetition: every column as text, numeric columns also as numbers.
#[derive(Clone, Debug)]
pub struct Run {
    text: BTreeMap<String, String>,
    num: BTreeMap<String, f64>,
}

impl Run {
    /// True when the run's setting columns take one of the allowed values for every filter entry.
    pub fn passes(&self, filter: &[(String, Vec<String>)]) -> bool {
        let threads_all = |column: &str, a: &str| column == "threads" && a == "all" && self.text(column) == self.text("logical_cores");
        filter.iter().all(|(column, allowed)| allowed.iter().any(|a| a == self.text(column) || threads_all(column, a)))
    }

    /// A column's value as text (`""` when absent or null).
    pub fn text(&self, column: &str) -> &str {
        self.text.get(column).map_or("", String::as_str)
    }

    /// A numeric column's value (NaN when absent, null or not numeric).
    pub fn num(&self, column: &str) -> f64 {
        self.num.get(column).copied().unwrap_or(f64::NAN)
    }

    /// The configuration id.
    pub fn config_id(&self) -> &str {
        self.text("config_id")
    }

    /// The series label.
    pub fn series(&self) -> &str {
        self.text("series")
    }
}

/// The rows of one run directory: the polars frame and the per-row view.
pub struct Rows {
    /// All rows, typed per ROWS.md.
    pub frame: DataFrame,
    /// The same rows, one `Run` each, in file order.
    pub runs: Vec<Run>,
    /// Rows of configurations that failed validation (never timed; kept out of `frame` and `runs`).
    pub failed: Vec<Run>,
}

impl Rows {
    /// Whether `column` exists and is numeric.
    pub fn is_numeric(&self, column: &str) -> bool {
        self.frame.schema().get(column).is_some_and(|dtype| dtype.is_primitive_numeric())
    }
}

/// Reads and checks `path` (a `runs.csv`).
pub fn read(path: &Path) -> Result<Rows, Error> {
    let header = read_header(path)?;
    for column in TEXT.iter().chain(&INTEGER).chain(&FLOAT).chain(&["git_dirty"]) {
        if !header.iter().any(|h| h == column) {
            return Err(Error::MissingColumn { path: path.into(), column: column.to_string() });
        }
    }
    let schema: Schema =
        header.iter().filter_map(|name| Some(Field::new(name.as_str().into(), dtype_of(name)?))).collect();
    let frame = CsvReadOptions::default()
        .with_has_header(true)
        .with_schema_overwrite(Some(Arc::new(schema)))
        .try_into_reader_with_file_path(Some(path.into()))
        .and_then(|reader| reader.finish())
        .map_err(|e| Error::read(path, e))?;
    if frame.height() == 0 {
        return Err(Error::NoRows { path: path.into() });
    }
    let mut frame = frame;
    for column in OPTIONAL_TEXT.iter().filter(|c| !header.iter().any(|h| h == *c)) {
        let filler = Column::new((*column).into(), vec!["-"; frame.height()]);
        frame.with_column(filler).map_err(|e| Error::read(path, e))?;
    }
    let (frame, failed) = if header.iter().any(|h| h == "validation") {
        let is_failed = frame.column("validation").and_then(|c| c.str().map(|s| s.equal("FAILED"))).map_err(|e| Error::read(path, e))?;
        let failed = frame.filter(&is_failed).and_then(|f| to_runs(&f)).map_err(|e| Error::read(path, e))?;
        (frame.filter(&!is_failed).map_err(|e| Error::read(path, e))?, failed)
    } else {
        (frame, Vec::new())
    };
    let runs = to_runs(&frame).map_err(|e| Error::read(path, e))?;
    Ok(Rows { frame, runs, failed })
}

/// The column names in the first line of the file.
fn read_header(path: &Path) -> Result<Vec<String>, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
    let first = text.lines().next().ok_or_else(|| Error::NoRows { path: path.into() })?;
    Ok(first.split(',').map(|name| name.trim().trim_matches('"').to_string()).collect())
}

/// The type ROWS.md gives a column; `None` for columns it does not know (inferred).
fn dtype_of(column: &str) -> Option<DataType> {
    if TEXT.contains(&column) || OPTIONAL_TEXT.contains(&column) {
        Some(DataType::String)
    } else if INTEGER.contains(&column) {
        Some(DataType::Int64)
    } else if FLOAT.contains(&column) {
        Some(DataType::Float64)
    } else if column == "mismatches" {
        Some(DataType::Int64)
    } else if column == "git_dirty" {
        Some(DataType::Boolean)
    } else {
        None
    }
}

/// Splits the frame into one `Run` per row.
fn to_runs(frame: &DataFrame) -> PolarsResult<Vec<Run>> {
    let mut runs = vec![Run { text: BTreeMap::new(), num: BTreeMap::new() }; frame.height()];
    for column in frame.columns() {
        let name = column.name().to_string();
        let as_text = column.cast(&DataType::String)?;
        for (run, value) in runs.iter_mut().zip(as_text.str()?.iter()) {
            run.text.insert(name.clone(), value.unwrap_or("").to_string());
        }
        if column.dtype().is_primitive_numeric() {
            let as_num = column.cast(&DataType::Float64)?;
            for (run, value) in runs.iter_mut().zip(as_num.f64()?.iter()) {
                run.num.insert(name.clone(), value.unwrap_or(f64::NAN));
            }
        }
    }
    Ok(runs)
}
