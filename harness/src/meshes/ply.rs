//! PLY files (ASCII or binary) through `ply-rs-bw`: float x, y, z per vertex; faces as index lists, fanned into
//! triangles. A folder of PLY files is merged in sorted file-name order.

use std::fs::File;
use std::path::Path;

use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{ElementDef, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType};
use tracer::Vec3;
use tracer::scene::mesh::Mesh;

use crate::error::Error;

/// The names a face's index list goes by.
const FACE_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// One vertex or face of the payload: the properties the loader reads, the others ignored.
#[derive(Default)]
struct Element {
    xyz: [f32; 3],
    corners: Vec<u32>,
}

impl Element {
    fn coordinate(&mut self, name: &str, v: f32) -> PropertyAccessResult {
        match ["x", "y", "z"].iter().position(|&c| c == name) {
            Some(i) => {
                self.xyz[i] = v;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }

    fn list<T: TryInto<u32>>(&mut self, name: &str, v: Vec<T>) -> PropertyAccessResult {
        if !FACE_LISTS.contains(&name) {
            return PropertyAccessResult::Ignored;
        }
        // A negative index becomes u32::MAX and fails the range check.
        self.corners = v.into_iter().map(|i| i.try_into().unwrap_or(u32::MAX)).collect();
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for Element {
    fn new() -> Self {
        Self::default()
    }
    fn set_float(&mut self, name: &str, v: f32) -> PropertyAccessResult {
        self.coordinate(name, v)
    }
    fn set_double(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        self.coordinate(name, v as f32)
    }
    fn set_list_char(&mut self, name: &str, v: Vec<i8>) -> PropertyAccessResult {
        self.list(name, v)
    }
    fn set_list_uchar(&mut self, name: &str, v: Vec<u8>) -> PropertyAccessResult {
        self.list(name, v)
    }
    fn set_list_short(&mut self, name: &str, v: Vec<i16>) -> PropertyAccessResult {
        self.list(name, v)
    }
    fn set_list_ushort(&mut self, name: &str, v: Vec<u16>) -> PropertyAccessResult {
        self.list(name, v)
    }
    fn set_list_int(&mut self, name: &str, v: Vec<i32>) -> PropertyAccessResult {
        self.list(name, v)
    }
    fn set_list_uint(&mut self, name: &str, v: Vec<u32>) -> PropertyAccessResult {
        self.list(name, v)
    }
}

/// Whether `element` declares float or double x, y and z.
fn has_coordinates(element: &ElementDef) -> bool {
    let float = |t: &PropertyType| matches!(t, PropertyType::Scalar(ScalarType::Float | ScalarType::Double));
    ["x", "y", "z"].iter().all(|c| element.properties.get(*c).is_some_and(|p| float(&p.data_type)))
}

/// Whether `element` declares an integer index list under one of [`FACE_LISTS`].
fn has_index_list(element: &ElementDef) -> bool {
    FACE_LISTS.iter().any(|n| {
        element.properties.get(*n).is_some_and(|p| {
            matches!(p.data_type, PropertyType::List(_, ref t) if !matches!(t, ScalarType::Float | ScalarType::Double))
        })
    })
}

/// The triangles of the PLY file `path`; faces of more than three corners are fanned from their first.
pub fn load(path: &Path) -> Result<Mesh, Error> {
    let bad = |what: String| Error::Input(format!("{}: {what}", path.display()));
    let mut file = File::open(path).map_err(|e| bad(format!("cannot read: {e}")))?;
    let ply = Parser::<Element>::new()
        .read_ply(&mut file)
        .map_err(|e| bad(format!("not a readable PLY file: {}", super::first_line(&e))))?;
    let elements = &ply.header.elements;
    if !elements.get("vertex").is_some_and(has_coordinates) {
        return Err(bad("no vertex element with float x, y, z (allowed: property float|double x, y, z)".into()));
    }
    if !elements.get("face").is_some_and(has_index_list) {
        return Err(bad("no face element with an integer index list (allowed: vertex_indices or vertex_index)".into()));
    }
    let positions = ply.payload["vertex"].iter().map(|v| Vec3::from(v.xyz)).collect();
    let mut indices = Vec::new();
    for (n, face) in ply.payload["face"].iter().enumerate() {
        let c = &face.corners;
        if c.len() < 3 {
            return Err(bad(format!("face {n} has {} corners (allowed: 3 or more)", c.len())));
        }
        indices.extend((1..c.len() - 1).map(|k| [c[0], c[k], c[k + 1]]));
    }
    super::checked(Mesh { positions, indices }, path)
}

/// Every `.ply` file directly in `dir`, in sorted file-name order, merged into one mesh.
pub fn load_folder(dir: &Path) -> Result<Mesh, Error> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::Input(format!("{}: cannot list: {e}", dir.display())))?;
    let mut files: Vec<_> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x.eq_ignore_ascii_case("ply")))
        .collect();
    if files.is_empty() {
        return Err(Error::Input(format!("{}: no .ply files in this folder", dir.display())));
    }
    files.sort_by(|a, b| a.file_name().cmp(&b.file_name()));
    let mut mesh = Mesh::default();
    for f in &files {
        mesh.append(load(f)?);
    }
    Ok(mesh)
}
