//! Wavefront OBJ files through `tobj`: every model's faces, triangulated as fans, into one mesh.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use tracer::Vec3;
use tracer::scene::mesh::Mesh;

use crate::error::Error;

/// The triangles of every model in the OBJ file `path` (materials are not read).
pub fn load(path: &Path) -> Result<Mesh, Error> {
    let file = File::open(path).map_err(|e| Error::Input(format!("{}: cannot read: {e}", path.display())))?;
    let options =
        tobj::LoadOptions { triangulate: true, ignore_points: true, ignore_lines: true, ..Default::default() };
    let (models, _) = tobj::load_obj_buf(&mut BufReader::new(file), &options, |_| Ok(Default::default()))
        .map_err(|e| Error::Input(format!("{}: not a readable OBJ file: {e}", path.display())))?;
    let mut mesh = Mesh::default();
    for model in models {
        let m = model.mesh;
        let positions = m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let indices = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        mesh.append(super::checked(Mesh { positions, indices }, path)?);
    }
    Ok(mesh)
}
