//! Triangle meshes: OBJ and PLY files, folders of PLY files, and the data sets `harness fetch` caches.

mod cache;
mod fetch;
mod js;
mod obj;
mod ply;
pub mod registry;
#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::path::Path;
use std::sync::{Arc, Mutex};

use tracer::Vec3;
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

/// The mesh of an `.obj` or `.ply` file, or of a folder of `.ply` files; one without a triangle is bad input.
pub fn load_path(path: &Path) -> Result<Mesh, Error> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    let mesh = match ext.as_deref() {
        _ if path.is_dir() => ply::load_folder(path),
        Some("obj") => obj::load(path),
        Some("ply") => ply::load(path),
        _ => Err(Error::Input(format!(
            "{}: not a mesh (allowed: an .obj or .ply file, a folder of .ply files)",
            path.display()
        ))),
    }?;
    if mesh.indices.is_empty() {
        return Err(Error::Input(format!(
            "{}: no triangles (allowed: a mesh of at least one triangle: faces of an .obj, a .ply's face element)",
            path.display()
        )));
    }
    Ok(mesh)
}

/// Triangles of `mesh` with zero area (two corners the same, or all three on one line), in f64 so that a tiny
/// triangle does not count. They stay in the mesh, as every backend gets it; no ray hits them.
pub fn degenerate(mesh: &Mesh) -> usize {
    let at = |i: u32| {
        let p = mesh.positions[i as usize];
        [f64::from(p.x), f64::from(p.y), f64::from(p.z)]
    };
    let zero_area = |&[a, b, c]: &[u32; 3]| {
        let (a, b, c) = (at(a), at(b), at(c));
        let (u, v) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
        let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        n == [0.0; 3]
    };
    mesh.indices.iter().filter(|t| zero_area(t)).count()
}

/// The load summary of the mesh the `mesh` setting names: `SOURCE: N triangles (D degenerate), fingerprint F`.
pub fn summary(source: &str) -> Result<String, Error> {
    let mesh = load_source(source)?;
    Ok(format!(
        "{source}: {} triangles ({} degenerate), fingerprint {:016x}",
        mesh.triangle_count(),
        degenerate(&mesh),
        mesh.fingerprint()
    ))
}

/// The data sets whose up axis is z (the sionna-rt city scenes, Mitsuba scenes with z up); every other mesh, and
/// every file, is taken as y up.
pub const Z_UP: &[&str] = &["san-francisco", "munich", "florence", "etoile"];

/// The up axis of the mesh the `mesh` setting names ([`Z_UP`]; a tiling's is its model's).
pub fn up_axis(source: &str) -> Vec3 {
    let model = tiling(source).map_or(source, |(model, _)| model);
    if Z_UP.contains(&model) { Vec3::Z } else { Vec3::Y }
}

/// True when the `mesh` setting names a file or folder rather than a data set.
pub fn is_path(source: &str) -> bool {
    source.contains(['/', '\\']) || source.contains('.')
}

/// Most copies a tiling may ask for (`munich*256` is 10 M triangles).
pub const MAX_COPIES: u32 = 1024;

/// `MODEL*N`: the model (a data set name or a path) and the copy count `N` of a tiling; `None` for a plain source.
/// The count is not checked here ([`load_source`] refuses one out of range).
fn tiling(source: &str) -> Option<(&str, &str)> {
    let (model, copies) = source.rsplit_once('*')?;
    (!copies.is_empty() && copies.bytes().all(|c| c.is_ascii_digit())).then_some((model, copies))
}

/// Triangles of the mesh `source` names without loading it: a data set's registered count (times a tiling's
/// copies); `None` for a file or folder.
pub fn triangles(source: &str) -> Option<usize> {
    let (model, copies) = match tiling(source) {
        Some((model, copies)) => (model, copies.parse::<usize>().ok()?),
        None => (source, 1),
    };
    let set = registry::DATA_SETS.iter().find(|d| d.name == model)?;
    Some(set.triangles * copies)
}

/// The mesh the `mesh` setting names — the fetched data set `source`, the file or folder at that path, or `MODEL*N`:
/// `N` copies of either laid out as a city of varied blocks ([`tracer::scene::mesh::Mesh::tiled`]) — loaded once
/// per process.
pub fn load_source(source: &str) -> Result<Arc<Mesh>, Error> {
    static LOADED: Mutex<Option<HashMap<String, Arc<Mesh>>>> = Mutex::new(None);
    if let Some(mesh) = LOADED.lock().unwrap().get_or_insert_with(HashMap::new).get(source) {
        return Ok(mesh.clone());
    }
    let mesh = Arc::new(if let Some((model, copies)) = tiling(source) {
        let copies = copies.parse::<u32>().ok().filter(|n| (1..=MAX_COPIES).contains(n)).ok_or_else(|| {
            Error::Input(format!(
                "{source}: {copies} copies (allowed: MODEL*N with N from 1 to {MAX_COPIES}, e.g. munich*64)"
            ))
        })?;
        load_source(model)?.tiled(copies, up_axis(model))
    } else if is_path(source) {
        let path = Path::new(source);
        if !path.exists() {
            return Err(Error::Input(format!(
                "{source}: no such mesh file (allowed: a data set name or an .obj/.ply path)"
            )));
        }
        load_path(path)?
    } else {
        let Ok(set) = DataSet::named(source) else {
            let names: Vec<_> = registry::DATA_SETS.iter().map(|d| d.name).collect();
            return Err(Error::Input(format!(
                "unknown data set {source:?} (allowed: {}, an .obj/.ply file, a folder of .ply files, or MODEL*N: N copies of one)",
                names.join(", ")
            )));
        };
        cache::load(&cache::root()?, set)?
    });
    LOADED.lock().unwrap().get_or_insert_with(HashMap::new).insert(source.to_string(), mesh.clone());
    Ok(mesh)
}

/// `mesh` if every position is finite and every index is a vertex of it, else one line naming `path` and the first
/// bad vertex or triangle. Every backend, ours and the peers alike, gets only meshes checked here.
fn checked(mesh: Mesh, path: &Path) -> Result<Mesh, Error> {
    if let Some(k) = mesh.positions.iter().position(|p| !p.is_finite()) {
        let p = mesh.positions[k];
        return Err(Error::Input(format!(
            "{}: vertex {k} is not finite ({}, {}, {}) (allowed: finite x, y, z)",
            path.display(),
            p.x,
            p.y,
            p.z
        )));
    }
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
