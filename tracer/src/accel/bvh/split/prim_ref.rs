//! What the builder keeps of each primitive, in the node's primitive order ([`BuildRef`]): for a sphere, the sphere
//! in one SIMD register ([`PrimRef`]); for a triangle, its box ([`BoxRef`]).
//!
//! A sphere's reference is its sphere in one SIMD register, kept in the node's primitive order so that split loops read it in
//! sequence: 16 bytes a primitive, where a stored box and centroid took 48. Its box is computed when read, by the
//! operations of [`Sphere::bounds`], so it has the same bits.
//!
//! Unions here are SSE min/max where [`Aabb::union`] is `f32::min`/`max` per lane: the same values for finite
//! inputs (a box's extremes do not depend on the order or the instruction, short of a tie between -0 and +0).

use glam::{Vec3A, Vec3Swizzles, Vec4};

use crate::geometry::{Aabb, MollerTrumboreTriangle, Primitive, Sphere, WatertightTriangle};

/// What split rules read of a primitive, kept beside its id in the node's primitive order.
pub trait BuildRef: Copy + Send + Sync + std::fmt::Debug {
    /// The primitive's centroid ([`Primitive::centroid`], bit for bit).
    fn centroid(&self) -> Vec3A;
    /// The primitive's box ([`Primitive::bounds`], bit for bit).
    fn bounds(&self) -> Box3A;
}

/// A primitive the shared builder builds over: how it is referenced while splitting.
pub trait Referenced: Primitive {
    /// Its reference.
    type Ref: BuildRef;
    /// The reference of `self`.
    fn reference(&self) -> Self::Ref;
    /// The primitive of reference `r`, whose id is `id` in `all`.
    fn from_ref(r: &Self::Ref, all: &[Self], id: u32) -> Self;
    /// Boxes of the primitive's parts inside `within` below and above the plane `axis = pos` (spatial splits);
    /// by default `within` cut at the plane (spheres), either may be empty.
    #[inline]
    fn halves(&self, within: &Box3A, axis: usize, pos: f32) -> [Box3A; 2] {
        super::clip::box_halves(within, axis, pos)
    }
    /// Calls `part(i, b)` with the box `b` of the primitive's part inside `within` in slab `i` of `axis` (slab 0 below
    /// `planes[0]`, slab `i` between `planes[i - 1]` and `planes[i]`, the last above the last plane; planes
    /// ascending), for every slab where that part is not empty (spatial binning).
    #[inline]
    fn slab_parts(&self, within: &Box3A, axis: usize, planes: &[f32], part: impl FnMut(usize, Box3A)) {
        super::clip::box_slab_parts(within, axis, planes, part)
    }
}

impl Referenced for Sphere {
    type Ref = PrimRef;

    #[inline(always)]
    fn reference(&self) -> PrimRef {
        PrimRef::new(self)
    }

    #[inline(always)]
    fn from_ref(r: &PrimRef, _all: &[Self], _id: u32) -> Self {
        r.sphere()
    }
}

/// A primitive's box in two SIMD registers; its centroid is the box's center.
#[derive(Clone, Copy, Debug)]
pub struct BoxRef(Box3A);

impl BuildRef for BoxRef {
    #[inline(always)]
    fn centroid(&self) -> Vec3A {
        (self.0.min + self.0.max) * 0.5
    }

    #[inline(always)]
    fn bounds(&self) -> Box3A {
        self.0
    }
}

macro_rules! boxed_reference {
    ($($t:ty),*) => {$(
        impl Referenced for $t {
            type Ref = BoxRef;

            #[inline(always)]
            fn reference(&self) -> BoxRef {
                let b = Primitive::bounds(self);
                BoxRef(Box3A { min: b.min.into(), max: b.max.into() })
            }

            #[inline(always)]
            fn from_ref(_r: &BoxRef, all: &[Self], id: u32) -> Self {
                all[id as usize]
            }

            /// The triangle clipped exactly ([`super::clip::triangle_halves`]).
            #[inline]
            fn halves(&self, within: &Box3A, axis: usize, pos: f32) -> [Box3A; 2] {
                super::clip::triangle_halves(&self.0, within, axis, pos)
            }

            /// The triangle clipped to `within` once, then cut at each plane ([`super::clip::triangle_slab_parts`]).
            #[inline]
            fn slab_parts(&self, within: &Box3A, axis: usize, planes: &[f32], part: impl FnMut(usize, Box3A)) {
                super::clip::triangle_slab_parts(&self.0, within, axis, planes, part)
            }
        }
    )*};
}

boxed_reference!(MollerTrumboreTriangle, WatertightTriangle);

/// The sphere of the primitive at the same position of the node's primitive ids: center in x, y, z, radius in w.
#[derive(Clone, Copy, Debug)]
pub struct PrimRef(Vec4);

impl PrimRef {
    /// The reference of sphere `s`.
    #[inline]
    pub fn new(s: &Sphere) -> Self {
        PrimRef(s.center.extend(s.radius))
    }

    /// The primitive's sphere.
    #[inline(always)]
    pub fn sphere(&self) -> Sphere {
        Sphere::new(self.0.truncate(), self.0.w)
    }
}

impl BuildRef for PrimRef {
    /// The primitive's centroid (its sphere's center).
    #[inline(always)]
    fn centroid(&self) -> Vec3A {
        Vec3A::from_vec4(self.0)
    }

    /// The primitive's box: [`Sphere::bounds`], bit for bit.
    #[inline(always)]
    fn bounds(&self) -> Box3A {
        let (c, r) = (self.centroid(), Vec3A::splat(self.0.w));
        let pad = (c.abs() + r) * Sphere::BOUNDS_PAD;
        Box3A { min: c - r - pad, max: c + r + pad }
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

/// Rewrites `refs` from `all` (indexed by id) after a split rule reordered `prims` alone.
pub fn gather<P: Referenced>(refs: &mut [P::Ref], prims: &[u32], all: &[P]) {
    for (r, &p) in refs.iter_mut().zip(prims) {
        *r = all[p as usize].reference();
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

    #[test]
    fn triangle_references_are_the_triangles_bounds_and_centroids_bit_for_bit() {
        let mut rng = SplitMix64::new(8);
        let mut f = |scale: f64| ((rng.next_f64() - 0.5) * scale) as f32;
        for i in 0..10_000 {
            let scale = [1.0, 1e3, 1e7, 1e-3][i % 4];
            let mut p = || Vec3::new(f(scale), f(scale), f(scale));
            let t = WatertightTriangle(crate::geometry::Triangle::new(p(), p(), p()));
            let r = t.reference();
            assert_eq!(r.bounds().aabb(), Primitive::bounds(&t), "{t:?}");
            assert_eq!(Vec3::from(r.centroid()), Primitive::centroid(&t), "{t:?}");
        }
    }
}
