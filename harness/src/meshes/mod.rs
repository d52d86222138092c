//! Triangle meshes: OBJ and PLY files, folders of PLY files, and the data sets `harness fetch` caches.

mod cache;
mod fetch;
mod js;
mod obj;
mod ply;
pub mod registry;
#[cfg(test)]
mod tests;

use std::path::Path;

use tracer::scene::mesh::Mesh;

use crate::error::Error;
use registry::DataSet;

pub use fetch::list;

/// The mesh of the fetched data set `name`; not fetched: one line naming `harness fetch NAME` (exit 2).
pub fn load(name: &str) -> Result<Mesh, Error> {
    cache::load(&cache::root()?, DataSet::named(name)?)
}

/// Fetches the data set `name` into the cache (once; later calls say it is there).
pub fn fetch(name: &str) -> Result<(), Error> {
    fetch::fetch(&cache::root()?, DataSet::named(name)?).map(|_| ())
}

/// The mesh of an `.obj` or `.ply` file, or of a folder of `.ply` files.
pub fn load_path(path: &Path) -> Result<Mesh, Error> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        _ if path.is_dir() => ply::load_folder(path),
        Some("obj") => obj::load(path),
        Some("ply") => ply::load(path),
        _ => Err(Error::Input(format!(
            "{}: not a mesh (allowed: an .obj or .ply file, a folder of .ply files)",
            path.display()
        ))),
    }
}

/// `mesh` if every index is a vertex of it, else one line naming `path` and the first bad triangle.
fn checked(mesh: Mesh, path: &Path) -> Result<Mesh, Error> {
    let n = mesh.positions.len();
    match mesh.indices.iter().position(|t| t.iter().any(|&i| i as usize >= n)) {
        None => Ok(mesh),
        Some(k) => Err(Error::Input(format!(
            "{}: triangle {k} indexes vertices {:?} (allowed: 0 to {}, the file has {n} vertices)",
            path.display(),
            mesh.indices[k],
            n.saturating_sub(1)
        ))),
    }
}

/// The first line of a library's error message (some span several).
fn first_line(e: &dyn std::fmt::Display) -> String {
    e.to_string().lines().next().unwrap_or_default().to_string()
}
