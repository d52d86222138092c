//! A primitive's sphere in one SIMD register, kept in the node's primitive order so that split loops read it in
//! sequence: 16 bytes a primitive, where a stored box and centroid took 48. Its box is computed when read, by the
//! operations of [`Sphere::bounds`], so it has the same bits.
//!
//! Unions here are SSE min/max where [`Aabb::union`] is `f32::min`/`max` per lane: the same values for finite
//! inputs (a box's extremes do not depend on the order or the instruction, short of a tie between -0 and +0).

use glam::{Vec3A, Vec3Swizzles, Vec4};

use crate::geometry::{Aabb, Sphere};

/// The sphere of the primitive at the same position of the node's primitive ids: center in x, y, z, radius in w.
#[derive(Clone, Copy, Debug)]
pub struct PrimRef(Vec4);

impl PrimRef {
    /// The reference of sphere `s`.
    #[inline]
    pub fn new(s: &Sphere) -> Self {
        PrimRef(s.center.extend(s.radius))
    }

    /// The primitive's centroid (its sphere's center).
    #[inline(always)]
    pub fn centroid(&self) -> Vec3A {
        Vec3A::from_vec4(self.0)
    }

    /// The primitive's box: [`Sphere::bounds`], bit for bit.
    #[inline(always)]
    pub fn bounds(&self) -> Box3A {
        let (c, r) = (self.centroid(), Vec3A::splat(self.0.w));
        let pad = (c.abs() + r) * Sphere::BOUNDS_PAD;
        Box3A { min: c - r - pad, max: c + r + pad }
    }

    /// The primitive's sphere.
    #[inline(always)]
    pub fn sphere(&self) -> Sphere {
        Sphere::new(self.0.truncate(), self.0.w)
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
        self.surface_area_of_nonempty()
    }

    /// [`Box3A::surface_area`] of a box known to hold something (no emptiness test).
    #[inline(always)]
    pub fn surface_area_of_nonempty(&self) -> f32 {
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

/// Rewrites `refs` from `spheres` (indexed by id) after a split rule reordered `prims` alone.
pub fn gather(refs: &mut [PrimRef], prims: &[u32], spheres: &[Sphere]) {
    for (r, &p) in refs.iter_mut().zip(prims) {
        *r = PrimRef::new(&spheres[p as usize]);
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn bounds_are_the_spheres_bounds_bit_for_bit() {
        let mut rng = SplitMix64::new(7);
        let mut f = |scale: f64| ((rng.next_f64() - 0.5) * scale) as f32;
        for i in 0..10_000 {
            let scale = [1.0, 1e3, 1e7, 1e-3][i % 4];
            let s = Sphere::new(Vec3::new(f(scale), f(scale), f(scale)), f(scale).abs() + 1e-6);
            let r = PrimRef::new(&s);
            assert_eq!(r.bounds().aabb(), s.bounds(), "{s:?}");
            assert_eq!((Vec3::from(r.centroid()), r.sphere()), (s.center, s));
        }
    }
}
