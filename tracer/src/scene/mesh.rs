//! A triangle mesh as plain data: shared vertex positions and triangles indexing them.

use glam::Vec3;

use crate::fingerprint::Fnv64;
use crate::geometry::{Aabb, Triangle};

/// Vertex positions and the triangles over them (three indices into `positions` each).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles, as indices into `positions`.
    pub indices: Vec<[u32; 3]>,
}

impl Mesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The triangle with index `i`.
    pub fn triangle(&self, i: usize) -> Triangle {
        let [a, b, c] = self.indices[i].map(|k| self.positions[k as usize]);
        Triangle::new(a, b, c)
    }

    /// Every triangle, in index order.
    pub fn triangles(&self) -> impl ExactSizeIterator<Item = Triangle> + '_ {
        (0..self.indices.len()).map(|i| self.triangle(i))
    }

    /// Bounds of all vertex positions.
    pub fn bounds(&self) -> Aabb {
        self.positions.iter().fold(Aabb::EMPTY, |mut b, &p| {
            b.grow(p);
            b
        })
    }

    /// Appends `other`'s vertices and triangles after this mesh's (its indices shifted accordingly).
    pub fn append(&mut self, other: Mesh) {
        let offset = self.positions.len() as u32;
        self.positions.extend(other.positions);
        self.indices.extend(other.indices.iter().map(|t| t.map(|i| i + offset)));
    }

    /// Stable hash of the positions and triangles, in order.
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv64::default();
        h.u32(self.positions.len() as u32);
        for p in &self.positions {
            h.f32(p.x).f32(p.y).f32(p.z);
        }
        h.u32(self.indices.len() as u32);
        for t in &self.indices {
            h.u32(t[0]).u32(t[1]).u32(t[2]);
        }
        h.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle(z: f32) -> Mesh {
        Mesh { positions: vec![Vec3::new(0.0, 0.0, z), Vec3::X, Vec3::Y], indices: vec![[0, 1, 2]] }
    }

    #[test]
    fn append_shifts_indices_and_bounds_cover_both() {
        let mut m = triangle(0.0);
        m.append(triangle(-2.0));
        assert_eq!(m.triangle_count(), 2);
        assert_eq!(m.indices[1], [3, 4, 5]);
        assert_eq!(m.bounds().min, Vec3::new(0.0, 0.0, -2.0));
        assert_eq!(m.bounds().max, Vec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn fingerprint_sees_positions_and_order() {
        let (a, b) = (triangle(0.0), triangle(1.0));
        assert_eq!(a.fingerprint(), triangle(0.0).fingerprint());
        assert_ne!(a.fingerprint(), b.fingerprint());
        let mut flipped = a.clone();
        flipped.indices[0] = [0, 2, 1];
        assert_ne!(a.fingerprint(), flipped.fingerprint());
    }
}
