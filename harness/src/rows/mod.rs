//! Recorded rows: one [`schema::Row`] per timed repetition, appended to `runs.csv` and flushed as each run
//! finishes.
//!
//! The column contract is `report/ROWS.md` (generated from the schema). A sweep killed at any point leaves
//! complete lines plus at most one partial last line: [`read_log`] (and so `merge`, `rows-diff` and `reproduce`)
//! leaves that line out, [`RowLog::resume`] cuts it off the file and reports which runs are done.

pub mod diff;

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::Path;

use schema::Row;
use schema::row::{ReadError, csv_line, header, read_rows};

use crate::error::Error;

/// `text` up to its last line end: the complete lines of a row log (a sweep killed mid-write leaves a partial
/// last line).
fn complete_lines(text: &str) -> &str {
    &text[..text.rfind('\n').map_or(0, |i| i + 1)]
}

/// The rows of a `runs.csv` text, a partial last line (a killed run) left out.
fn parse_log(text: &str) -> Result<Vec<Row>, ReadError> {
    read_rows(complete_lines(text))
}

/// The rows of the `runs.csv` at `path`, a partial last line (a killed run) left out; the file is only read.
pub fn read_log(path: &Path) -> Result<Vec<Row>, Error> {
    let text =
        std::fs::read_to_string(path).map_err(|e| Error::Input(format!("{}: cannot read: {e}", path.display())))?;
    parse_log(&text).map_err(|e| Error::Input(format!("{}: {e}", path.display())))
}

/// The append-only row log of one run folder.
pub struct RowLog {
    file: File,
}

impl RowLog {
    /// Starts a new log at `path` (replacing any old one) with the header line.
    pub fn create(path: &Path) -> io::Result<Self> {
        let mut file = File::create(path)?;
        file.write_all(format!("{}\n", header()).as_bytes())?;
        file.flush()?;
        Ok(Self { file })
    }

    /// Opens an existing log for appending: drops a partial last line, checks the header, and returns the rows
    /// already recorded.
    pub fn resume(path: &Path) -> io::Result<(Self, Vec<Row>)> {
        let mut file = OpenOptions::new().read(true).write(true).open(path)?;
        let mut text = String::new();
        file.read_to_string(&mut text)?;
        let complete = complete_lines(&text).len();
        if complete < text.len() {
            file.set_len(complete as u64)?;
        }
        file.seek(SeekFrom::End(0))?;
        if text.lines().next().unwrap_or_default() != header() {
            return Err(io::Error::new(io::ErrorKind::InvalidData, "its header is not this harness's column list"));
        }
        let rows = parse_log(&text).map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.to_string()))?;
        Ok((Self { file }, rows))
    }

    /// Appends one row as a single write, then flushes.
    pub fn append(&mut self, row: &Row) -> io::Result<()> {
        self.file.write_all(csv_line(row)?.as_bytes())?;
        self.file.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resume_drops_a_partial_line_and_lists_done_runs() {
        let dir = std::env::temp_dir().join(format!("bvhlab-rows-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("runs.csv");
        let mut log = RowLog::create(&path).unwrap();
        let settings = schema::Settings { threads: schema::Threads::Count(1), ..Default::default() }.normalized();
        let mut row =
            Row { config_id: "abc".into(), repetition: 2, series: "say \"hi\", twice".into(), ..Row::of(&settings) };
        log.append(&row).unwrap();
        drop(log);
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(b"exp,def,series,0,random-sph").unwrap(); // killed mid-line
        drop(f);
        let (mut log, done) = RowLog::resume(&path).unwrap();
        let done: Vec<(&str, u32)> = done.iter().map(|r| (r.config_id.as_str(), r.repetition)).collect();
        assert_eq!(done, [("abc", 2)]);
        row.config_id = "def".into();
        log.append(&row).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 3);
        let rows = read_rows(&text).unwrap();
        assert_eq!(rows[1], row, "quotes and commas round-trip");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn read_log_drops_a_partial_last_line_as_resume_does() {
        let dir = std::env::temp_dir().join(format!("bvhlab-rows-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("runs.csv");
        let mut log = RowLog::create(&path).unwrap();
        let settings = schema::Settings { threads: schema::Threads::Count(1), ..Default::default() }.normalized();
        let row = Row { config_id: "abc".into(), repetition: 1, ..Row::of(&settings) };
        log.append(&row).unwrap();
        drop(log);
        let whole = std::fs::read_to_string(&path).unwrap();
        let killed = format!("{whole}{}", &csv_line(&Row { config_id: "def".into(), ..row.clone() }).unwrap()[..40]);
        std::fs::write(&path, &killed).unwrap();

        assert_eq!(complete_lines(&killed), whole);
        assert_eq!(read_log(&path).unwrap(), std::slice::from_ref(&row), "the partial line is left out");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), killed, "read_log only reads");
        let (_, resumed) = RowLog::resume(&path).unwrap();
        assert_eq!(resumed, std::slice::from_ref(&row), "resume keeps the same rows");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), whole, "resume cuts the partial line off the file");
        assert_eq!(read_log(&path).unwrap(), [row], "nothing to leave out then");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
