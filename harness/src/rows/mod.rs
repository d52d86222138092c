//! Recorded rows: one [`schema::Row`] per timed repetition, appended to `runs.csv` and flushed as each run
//! finishes.
//!
//! The column contract is `report/ROWS.md` (generated from the schema). A sweep killed at any point leaves
//! complete lines plus at most one partial last line; [`RowLog::resume`] cuts that line off and reports
//! which runs are done.

pub mod diff;

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::Path;

use schema::Row;
use schema::row::{csv_line, header, read_rows};

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
        let complete = text.rfind('\n').map_or(0, |i| i + 1);
        if complete < text.len() {
            file.set_len(complete as u64)?;
        }
        file.seek(SeekFrom::End(0))?;
        if text.lines().next().unwrap_or_default() != header() {
            return Err(io::Error::new(io::ErrorKind::InvalidData, "its header is not this harness's column list"));
        }
        let rows =
            read_rows(&text[..complete]).map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.to_string()))?;
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
}
