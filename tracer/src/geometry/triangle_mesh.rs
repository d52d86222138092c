use glam::Vec3;

use super::Triangle;

/// Triangles over shared vertices: positions, and three indices into them per triangle (pbrt's `TriangleMesh`).
///
/// Indices rather than a soup of free triangles: two triangles that share an edge name the same two positions,
/// so the edge is bit-identical in both, which is what a watertight test needs to leave no gap between them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per triangle, the indices of its vertices `p0, p1, p2` in [`TriangleMesh::positions`].
    pub indices: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// The triangle with index `i`.
    pub fn triangle(&self, i: usize) -> Triangle {
        let [a, b, c] = self.indices[i].map(|k| self.positions[k as usize]);
        Triangle::new(a, b, c)
    }

    /// Every triangle, in index order.
    pub fn triangles(&self) -> impl ExactSizeIterator<Item = Triangle> + '_ {
        (0..self.indices.len()).map(|i| self.triangle(i))
    }
}
