//! A primitive's box and centroid in SIMD lanes, kept in the node's primitive order so that split loops read them
//! in sequence.
//!
//! Unions here are SSE min/max where [`Aabb::union`] is `f32::min`/`max` per lane: the same values for finite
//! inputs (a box's extremes do not depend on the order or the instruction, short of a tie between -0 and +0).

use glam::{Vec3, Vec3A, Vec3Swizzles};

use crate::geometry::Aabb;

/// The box and centroid of the primitive at the same position of the node's primitive ids.
#[derive(Clone, Copy, Debug)]
pub struct PrimRef {
    /// The primitive's box.
    pub bounds: Box3A,
    /// The primitive's centroid.
    pub centroid: Vec3A,
}

impl PrimRef {
    /// The reference of a primitive with box `b` and centroid `c`.
    #[inline]
    pub fn new(b: &Aabb, c: Vec3) -> Self {
        PrimRef { bounds: Box3A { min: b.min.into(), max: b.max.into() }, centroid: c.into() }
    }
}

/// An axis-aligned box in SIMD lanes; the empty box has `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug)]
pub struct Box3A {
    /// Lower corner.
    pub min: Vec3A,
    /// Upper corner.
    pub max: Vec3A,
}

impl Box3A {
    /// The box containing nothing.
    pub const EMPTY: Box3A = Box3A { min: Vec3A::INFINITY, max: Vec3A::NEG_INFINITY };

    /// Grows the box to contain `b`.
    #[inline(always)]
    pub fn add(&mut self, b: &Box3A) {
        self.min = self.min.min(b.min);
        self.max = self.max.max(b.max);
    }

    /// Grows the box to contain `p`.
    #[inline(always)]
    pub fn grow(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// [`Aabb::surface_area`] of the same box, by the same operations: `2 * ((x*y + y*z) + z*x)`, zero when empty.
    #[inline(always)]
    pub fn surface_area(&self) -> f32 {
        if self.min.cmpgt(self.max).any() {
            return 0.0;
        }
        let e = self.max - self.min;
        let p = e * e.yzx();
        2.0 * (p.x + p.y + p.z)
    }

    /// The same box as an [`Aabb`].
    #[inline(always)]
    pub fn aabb(&self) -> Aabb {
        Aabb { min: self.min.into(), max: self.max.into() }
    }
}

/// Rewrites `refs` from the per-id `boxes` and `centroids` after a split rule reordered `prims` alone.
pub fn gather(refs: &mut [PrimRef], prims: &[u32], boxes: &[Aabb], centroids: &[Vec3]) {
    for (r, &p) in refs.iter_mut().zip(prims) {
        *r = PrimRef::new(&boxes[p as usize], centroids[p as usize]);
    }
}
