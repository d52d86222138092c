//! A primitive's box and centroid, kept in the node's primitive order so that split loops read them in sequence.

use glam::Vec3;

use crate::geometry::Aabb;

/// The box and centroid of the primitive at the same position of the node's primitive ids.
#[derive(Clone, Copy, Debug)]
pub struct PrimRef {
    /// The primitive's box.
    pub bounds: Aabb,
    /// The primitive's centroid.
    pub centroid: Vec3,
}

/// Rewrites `refs` from the per-id `boxes` and `centroids` after a split rule reordered `prims` alone.
pub fn gather(refs: &mut [PrimRef], prims: &[u32], boxes: &[Aabb], centroids: &[Vec3]) {
    for (r, &p) in refs.iter_mut().zip(prims) {
        *r = PrimRef { bounds: boxes[p as usize], centroid: centroids[p as usize] };
    }
}
