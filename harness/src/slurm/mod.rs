//! Sweeps on a Slurm cluster: `harness slurm submit` writes and submits a job array (one shard per task, see
//! [`crate::plan::shard`]) and a merge job that runs `harness merge` when the array ends; `resubmit` runs again
//! only the shards that lack rows. `--shard env` ([`env`]) is how a task knows its shard.

pub mod env;
pub mod sbatch;
mod submit;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::Error;

pub use submit::{resubmit, submit};

/// The folder of job scripts, logs and `jobs.json` inside a run folder.
pub const SLURM_DIR: &str = "slurm";
/// What a shard folder records about its shard (written by `harness run --shard`).
pub const SHARD_JSON: &str = "shard.json";

/// 16 hex digits: FNV-1a 64 of a config's text.
pub fn config_hash(text: &str) -> String {
    format!("{:016x}", tracer::fingerprint::Fnv64::default().bytes(text.as_bytes()).finish())
}

/// `RUN_DIR/shard-I-of-N`.
pub fn shard_dir(run_dir: &Path, i: usize, n: usize) -> PathBuf {
    run_dir.join(format!("shard-{i}-of-{n}"))
}

/// `shard.json`: which shard of which config a shard folder holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardInfo {
    /// `[I, N]`, 1-based.
    pub shard: (usize, usize),
    /// The config as given to `harness run`, absolute.
    pub config: PathBuf,
    /// [`config_hash`] of its text.
    pub config_hash: String,
    /// Whether the config's [quick] overrides applied.
    pub quick: bool,
    /// Configurations of the shard skipped because their backend cannot run there (Embree absent, a SIMD kernel
    /// the CPU lacks): not planned rows.
    #[serde(default)]
    pub skipped: Vec<String>,
}

/// One submission of the array and its merge job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Submission {
    pub array_job_id: String,
    pub merge_job_id: String,
    /// The 0-based array tasks it ran (task a = shard a+1).
    pub tasks: Vec<usize>,
    /// RFC 3339 UTC.
    pub submitted: String,
}

/// `slurm/jobs.json`: the options of the jobs and every submission, first to last.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Jobs {
    pub options: sbatch::JobOptions,
    pub submissions: Vec<Submission>,
}

/// Reads `path` as JSON of `T`; errors name the file.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, Error> {
    let text =
        std::fs::read_to_string(path).map_err(|e| Error::Input(format!("{}: cannot read: {e}", path.display())))?;
    serde_json::from_str(&text)
        .map_err(|e| Error::Input(format!("{}: not a file this harness wrote: {e}", path.display())))
}

/// Writes `value` as pretty JSON to `path`.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), Error> {
    let text = serde_json::to_string_pretty(value).expect("plain data serializes");
    std::fs::write(path, text + "\n").map_err(|e| Error::Run(format!("{}: cannot write: {e}", path.display())))
}
