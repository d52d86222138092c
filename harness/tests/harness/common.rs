//! Helpers shared by the harness's end-to-end tests.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The harness binary, run from the workspace root.
pub fn harness() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_harness"));
    c.current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap());
    c
}

/// An empty temporary folder `bvhlab-<suite>-<pid>-<name>`.
pub fn temp(suite: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("bvhlab-{suite}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
