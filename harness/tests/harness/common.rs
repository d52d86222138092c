//! Helpers shared by the harness's end-to-end tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use schema::{Named, PeerKind};
use tracer::accel::{AccelKind, Traversal};

/// The harness binary, run from the workspace root.
pub fn harness() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_harness"));
    c.current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap());
    c
}

/// An empty temporary folder `bvhlab-<file>-<pid>-<name>`, `<file>` the test file that asks for it (`run`, `slurm`,
/// …): the modules of this one test binary share a process id, so each names its folders apart.
#[track_caller]
pub fn temp(name: &str) -> PathBuf {
    let file = Path::new(std::panic::Location::caller().file()).file_stem().unwrap().to_string_lossy().into_owned();
    let d = std::env::temp_dir().join(format!("bvhlab-{file}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// What a finished command wrote to its standard error.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The accelerator names the tests' configs use: the list, the flat BVH, Embree, and the front-to-back traversal.
pub fn names() -> (&'static str, &'static str, &'static str, &'static str) {
    (AccelKind::List.name(), AccelKind::FlatBvh.name(), PeerKind::Embree.name(), Traversal::FrontToBack.name())
}
