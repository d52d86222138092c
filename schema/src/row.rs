//! Columns as metadata, cells, configuration ids, and `runs.csv` as the csv crate reads and writes it.

use std::fmt;
use std::io;

use tracer::fingerprint::Fnv64;

pub use crate::columns::COLUMNS;
use crate::columns::{REPLACED, Replaced, Row, Settings};

/// A column's type in rows and frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Text (names, hashes, labels).
    Text,
    /// A signed integer.
    Int,
    /// A float.
    Float,
    /// `true` / `false`.
    Bool,
}

/// What a column is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Which experiment, configuration, series and repetition the row is.
    Identity,
    /// A setting of the configuration (an axis).
    Setting,
    /// A timing or throughput: varies between repetitions.
    Metric,
    /// Deterministic: the same in every repetition and on every machine (work counters, tree statistics, hashes).
    Counter,
    /// Where and how the row was recorded.
    Provenance,
    /// The outcome of validating the backend before timing.
    Validation,
}

/// One column of `runs.csv`.
#[derive(Clone, Copy, Debug)]
pub struct Column {
    /// Header name.
    pub name: &'static str,
    /// Type.
    pub kind: Kind,
    /// What it is for.
    pub role: Role,
    /// Unit (empty for names and counts).
    pub unit: &'static str,
    /// Meaning, one line.
    pub doc: &'static str,
    /// The row format the column was added in (1: the first); older files lack it and read as its default.
    pub added: u32,
}

impl Column {
    /// The column called `name`.
    pub fn named(name: &str) -> Option<&'static Column> {
        COLUMNS.iter().find(|c| c.name == name)
    }

    /// True for numeric columns.
    pub fn is_numeric(&self) -> bool {
        matches!(self.kind, Kind::Int | Kind::Float)
    }
}

/// The names of the columns with `role`, in row order.
pub fn names_of(role: Role) -> Vec<&'static str> {
    COLUMNS.iter().filter(|c| c.role == role).map(|c| c.name).collect()
}

/// The setting columns, in row order (a configuration is a series plus these).
pub fn setting_names() -> Vec<&'static str> {
    names_of(Role::Setting)
}

/// The deterministic columns, compared exactly between runs and carried into summaries.
pub fn counter_names() -> Vec<&'static str> {
    names_of(Role::Counter)
}

/// The columns a plot's y or a claim may use: float metrics and numeric counters (e.g. `tree_bytes`).
pub fn plottable_names() -> Vec<&'static str> {
    COLUMNS
        .iter()
        .filter(|c| matches!(c.kind, Kind::Float | Kind::Int) && matches!(c.role, Role::Metric | Role::Counter))
        .map(|c| c.name)
        .collect()
}

/// The columns that must be equal for two runs of one series to stand for the same configuration on the
/// same machine: every setting, and `machine_id` (timings of different machines are never pooled).
pub fn point_names() -> Vec<&'static str> {
    let mut names = setting_names();
    names.push("machine_id");
    names
}

/// The key of a seed pool: series plus every [`point_names`] column except `seed` (runs that differ only in
/// the seed stand for the same point).
pub fn pool_key(series: &str, text: impl Fn(&str) -> String) -> Vec<String> {
    let mut key = vec![series.to_string()];
    key.extend(point_names().into_iter().filter(|c| *c != "seed").map(text));
    key
}

/// One value of a row.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// Text.
    Text(String),
    /// An integer.
    Int(i64),
    /// A float.
    Float(f64),
    /// A boolean.
    Bool(bool),
}

impl Cell {
    /// The value as a number (NaN for text).
    pub fn number(&self) -> f64 {
        match self {
            Cell::Int(i) => *i as f64,
            Cell::Float(x) => *x,
            Cell::Bool(_) | Cell::Text(_) => f64::NAN,
        }
    }
}

impl fmt::Display for Cell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Cell::Text(s) => f.write_str(s),
            Cell::Int(i) => write!(f, "{i}"),
            Cell::Float(x) => write!(f, "{x}"),
            Cell::Bool(b) => write!(f, "{b}"),
        }
    }
}

/// The Rust type of a non-setting column.
pub trait MeasureType {
    /// Its type in rows and frames.
    const KIND: Kind;
    /// The value as a cell.
    fn cell(&self) -> Cell;
}

/// A named choice recorded as a measure (`validation`, `wrong_side`): its name.
macro_rules! named_measure {
    ($($t:ty),*) => {$(
        impl MeasureType for $t {
            const KIND: Kind = Kind::Text;
            fn cell(&self) -> Cell {
                Cell::Text(crate::Named::name(*self).to_string())
            }
        }
    )*};
}

named_measure!(crate::names::ValidationStatus, crate::names::WrongSide);

impl MeasureType for String {
    const KIND: Kind = Kind::Text;
    fn cell(&self) -> Cell {
        Cell::Text(self.clone())
    }
}

impl MeasureType for bool {
    const KIND: Kind = Kind::Bool;
    fn cell(&self) -> Cell {
        Cell::Bool(*self)
    }
}

impl MeasureType for f64 {
    const KIND: Kind = Kind::Float;
    fn cell(&self) -> Cell {
        Cell::Float(*self)
    }
}

impl MeasureType for Option<f64> {
    const KIND: Kind = Kind::Float;
    fn cell(&self) -> Cell {
        Cell::Float(self.unwrap_or(f64::NAN))
    }
}

macro_rules! integer_measure {
    ($($t:ty),*) => {$(
        impl MeasureType for $t {
            const KIND: Kind = Kind::Int;
            fn cell(&self) -> Cell {
                Cell::Int(*self as i64)
            }
        }
    )*};
}

integer_measure!(u32, u64, usize);

/// A float measure rounded to a number of decimal places (non-finite and absent values unchanged).
pub trait Round {
    /// The value rounded to `decimals` places.
    fn round_to(self, decimals: usize) -> Self;
}

impl Round for f64 {
    fn round_to(self, decimals: usize) -> f64 {
        if self.is_finite() { format!("{self:.decimals$}").parse().unwrap_or(self) } else { self }
    }
}

impl Round for Option<f64> {
    fn round_to(self, decimals: usize) -> Option<f64> {
        self.map(|x| x.round_to(decimals))
    }
}

/// The stable id of a configuration: 16 hex digits of FNV-1a over the series label and the setting cells
/// ([`Settings::id_cells`]).
pub fn config_id(series: &str, settings: &Settings) -> String {
    let mut h = Fnv64::default();
    h.bytes(series.as_bytes()).bytes(b"\x1f");
    for cell in settings.id_cells() {
        h.bytes(cell.to_string().as_bytes()).bytes(b"\x1f");
    }
    format!("{:016x}", h.finish())
}

/// The header line of `runs.csv` (no line end).
pub fn header() -> String {
    COLUMNS.iter().map(|c| c.name).collect::<Vec<_>>().join(",")
}

/// `row` as one CSV line with its line end.
pub fn csv_line(row: &Row) -> io::Result<String> {
    let mut writer = csv::WriterBuilder::new().has_headers(false).from_writer(Vec::new());
    writer.serialize(row).map_err(io::Error::other)?;
    let bytes = writer.into_inner().map_err(|e| io::Error::other(e.to_string()))?;
    String::from_utf8(bytes).map_err(io::Error::other)
}

/// A `runs.csv` text that could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadError {
    /// 1-based line, when known.
    pub line: Option<u64>,
    /// The column the header lacks, when that is what is wrong.
    pub missing_column: Option<&'static str>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "line {l}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

/// Reads every row of a `runs.csv` text. Columns are matched by name: columns this version does not know
/// are ignored, columns added after a file was recorded (`added` in the declaration) take their default, columns
/// later formats replaced ([`REPLACED`]) set their replacements, and the settings are normalized; every other
/// column must be there.
pub fn read_rows(text: &str) -> Result<Vec<Row>, ReadError> {
    let mut reader = csv::ReaderBuilder::new().has_headers(true).from_reader(text.as_bytes());
    let error = |line, message: String| ReadError { line, missing_column: None, message };
    let header = reader.headers().map_err(|e| error(Some(1), e.to_string()))?.clone();
    if let Some(c) = COLUMNS.iter().find(|c| c.added <= 1 && !header.iter().any(|h| h == c.name)) {
        return Err(ReadError {
            missing_column: Some(c.name),
            ..error(Some(1), format!("missing column {:?}", c.name))
        });
    }
    let replaced: Vec<(usize, &Replaced)> =
        REPLACED.iter().filter_map(|r| header.iter().position(|h| h == r.key).map(|i| (i, r))).collect();
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| error(e.position().map(|p| p.line()), e.to_string()))?;
        let line = record.position().map(|p| p.line());
        let mut row: Row = record.deserialize(Some(&header)).map_err(|e| error(line, e.to_string()))?;
        let mut settings = row.settings();
        for (i, r) in &replaced {
            (r.read)(&mut settings, &record[*i]);
        }
        row.set_settings(&settings.normalized());
        rows.push(row);
    }
    Ok(rows)
}
