//! The data-set cache: `$BVHLAB_DATA/NAME/` (else `~/.cache/bvhlab/meshes/NAME/`) holds the archive, its
//! unpacked files and `manifest.json`, which is written last: a data set is fetched when its manifest is there.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tracer::scene::mesh::Mesh;

use super::registry::{DataSet, Format};
use crate::error::Error;

/// The manifest's file name in a data set's folder.
pub const MANIFEST: &str = "manifest.json";
/// The folder the archive is unpacked into.
pub const UNPACKED: &str = "unpacked";

/// What was fetched and what it loaded as.
#[derive(Debug, Serialize, Deserialize)]
pub struct Manifest {
    /// The data set's name.
    pub name: String,
    /// The registry package.
    pub package: String,
    /// Its version.
    pub version: String,
    /// The command that downloaded it.
    pub command: String,
    /// The archive's file name.
    pub archive: String,
    /// Its SHA-256, as checked.
    pub sha256: String,
    /// The mesh's path inside the unpacked archive.
    pub inside: String,
    /// The license the package states.
    pub license: String,
    /// Triangles of the loaded mesh.
    pub triangles: usize,
    /// The loaded mesh's `Mesh::fingerprint`, 16 hex digits.
    pub fingerprint: String,
}

/// The cache's root folder: `$BVHLAB_DATA`, else `~/.cache/bvhlab/meshes`.
pub fn root() -> Result<PathBuf, Error> {
    if let Some(dir) = std::env::var_os("BVHLAB_DATA").filter(|d| !d.is_empty()) {
        return Ok(PathBuf::from(dir));
    }
    let home = std::env::var_os("HOME").filter(|h| !h.is_empty());
    let home =
        home.ok_or_else(|| Error::Input("neither BVHLAB_DATA nor HOME is set: no place for the mesh cache".into()))?;
    Ok(Path::new(&home).join(".cache/bvhlab/meshes"))
}

/// The manifest of `set` under `root`, or `None` when it is not fetched.
pub fn manifest(root: &Path, set: &DataSet) -> Result<Option<Manifest>, Error> {
    let path = root.join(set.name).join(MANIFEST);
    if !path.is_file() {
        return Ok(None);
    }
    let text =
        std::fs::read_to_string(&path).map_err(|e| Error::Input(format!("{}: cannot read: {e}", path.display())))?;
    let m =
        serde_json::from_str(&text).map_err(|e| Error::Input(format!("{}: not a manifest: {e}", path.display())))?;
    Ok(Some(m))
}

/// The mesh of the unpacked data set `set` in `dir` (its folder in the cache).
pub fn read_mesh(dir: &Path, set: &DataSet) -> Result<Mesh, Error> {
    let path = dir.join(UNPACKED).join(set.inside);
    match set.format {
        Format::Obj => super::obj::load(&path),
        Format::PlyFolder => super::ply::load_folder(&path),
        Format::JsArrays => super::js::load(&path),
    }
}

/// The mesh of the fetched data set `set` under `root`; one line naming `harness fetch NAME` when not fetched.
pub fn load(root: &Path, set: &DataSet) -> Result<Mesh, Error> {
    if manifest(root, set)?.is_none() {
        return Err(Error::Input(format!(
            "data set {} is not fetched (no {}): run `harness fetch {}`",
            set.name,
            root.join(set.name).join(MANIFEST).display(),
            set.name
        )));
    }
    read_mesh(&root.join(set.name), set)
}
