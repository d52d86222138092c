//! The run folder: where a run is recorded, its row log opened, continued (`--resume`) or replaced, and an earlier
//! run moved aside into `previous/` (no recorded row is lost).

use std::path::Path;

use schema::Row;

use crate::config::Experiment;
use crate::error::Error;
use crate::rows::RowLog;

/// File names inside a run folder.
pub const RUNS_CSV: &str = "runs.csv";
pub const CONFIG_COPY: &str = "experiment.toml";

/// Where a run of `exp` is recorded unless told otherwise: `results/<name>/`, or `results/<name>-quick/` for the
/// config's quick form.
pub fn default_dir(exp: &Experiment, quick: bool) -> std::path::PathBuf {
    std::path::PathBuf::from("results").join(if quick { format!("{}-quick", exp.name) } else { exp.name.clone() })
}

/// What a run does with a folder that already holds recorded rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Existing {
    /// Move the earlier run aside into `previous/` (the default: no recorded row is lost).
    MoveAside,
    /// Continue it (`--resume`): skip the runs already recorded.
    Resume,
    /// Replace it (`--force`): its rows are deleted.
    Replace,
}

/// The folder an earlier run moves into when a new run starts in its folder; older ones become `previous-1`,
/// `previous-2`, … in the order they were recorded.
pub const PREVIOUS: &str = "previous";

/// True for the entries of a run folder that belong to other runs and stay where they are when the folder's own
/// run moves aside: earlier runs, shard folders (each moves its own run aside) and Slurm job files.
fn belongs_to_other_runs(name: &str) -> bool {
    name == PREVIOUS
        || name.strip_prefix("previous-").is_some_and(|n| n.parse::<u32>().is_ok())
        || (name.starts_with("shard-") && name.contains("-of-"))
        || name == crate::slurm::SLURM_DIR
}

/// Moves the run recorded in `dir` (its rows, config copy, summaries, figures, report and counts) into
/// `dir/previous/`, after renaming an existing `previous/` to the next free `previous-K`. Returns the folder the
/// rows moved to.
pub fn move_aside(dir: &Path) -> Result<std::path::PathBuf, Error> {
    let io = |what: &str, p: &Path, e: std::io::Error| Error::Run(format!("{}: cannot {what}: {e}", p.display()));
    let previous = dir.join(PREVIOUS);
    if previous.exists() {
        let older = (1..).map(|k| dir.join(format!("{PREVIOUS}-{k}"))).find(|p| !p.exists()).expect("a free name");
        std::fs::rename(&previous, &older).map_err(|e| io("move aside", &previous, e))?;
    }
    std::fs::create_dir(&previous).map_err(|e| io("create", &previous, e))?;
    let entries = std::fs::read_dir(dir).map_err(|e| io("read", dir, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| io("read", dir, e))?;
        if belongs_to_other_runs(&entry.file_name().to_string_lossy()) {
            continue;
        }
        let to = previous.join(entry.file_name());
        std::fs::rename(entry.path(), &to).map_err(|e| io("move aside", &entry.path(), e))?;
    }
    Ok(previous)
}

/// Opens the row log in `dir`. A folder holding rows is continued ([`Existing::Resume`], when made by the same
/// config text), replaced ([`Existing::Replace`]) or, by default, moved aside first ([`move_aside`]). Returns the
/// rows already recorded (those of a continued log).
pub(super) fn open_log(exp: &Experiment, dir: &Path, existing: Existing) -> Result<(RowLog, Vec<Row>), Error> {
    let runs = dir.join(RUNS_CSV);
    let copy = dir.join(CONFIG_COPY);
    let io = |what: &str, p: &Path, e: std::io::Error| Error::Input(format!("{}: cannot {what}: {e}", p.display()));
    if runs.exists() {
        match existing {
            Existing::Resume => {
                let recorded = std::fs::read_to_string(&copy).map_err(|e| io("read", &copy, e))?;
                if recorded != exp.text {
                    return Err(Error::Input(format!(
                        "{}: was recorded with a different config than {}; run without --resume to move it aside \
                         into {PREVIOUS}/ and start over",
                        dir.display(),
                        exp.path.display()
                    )));
                }
                return RowLog::resume(&runs).map_err(|e| io("resume", &runs, e));
            }
            Existing::MoveAside => {
                let to = move_aside(dir)?;
                note!(
                    "{}: the earlier run's rows moved to {} (--force replaces them instead)",
                    dir.display(),
                    to.display()
                );
            }
            Existing::Replace => {}
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| io("create", dir, e))?;
    std::fs::write(&copy, &exp.text).map_err(|e| io("write", &copy, e))?;
    Ok((RowLog::create(&runs).map_err(|e| io("create", &runs, e))?, Vec::new()))
}

/// Refuses to continue rows timed on other pages than this process's: `huge_pages` is not part of a point's
/// key (older rows say `-`, recorded before the column, when every run used 4-KiB pages), so a resumed run that
/// switched `--huge-pages` on or off would pool both into one point.
pub(super) fn refuse_mixed_pages(dir: &Path, recorded: &[Row], pages: &str) -> Result<(), Error> {
    let spelled = |p: &str| if p == "-" { "no" } else { p }.to_string();
    match recorded.iter().map(|r| spelled(&r.huge_pages)).find(|p| *p != spelled(pages)) {
        Some(theirs) => Err(Error::Input(format!(
            "{}: huge_pages: its rows were timed with `{theirs}` and this run has `{pages}`; resume with{} \
             --huge-pages (allowed: the pages its rows were timed on), or run without --resume to start over",
            dir.join(RUNS_CSV).display(),
            if theirs == "no" { "out" } else { "" }
        ))),
        None => Ok(()),
    }
}
