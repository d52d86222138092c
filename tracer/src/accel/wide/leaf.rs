//! SIMD leaves: a leaf's primitives copied into blocks of `B` lanes (SoA), padded with lanes that never hit.
//!
//! Each primitive has its block ([`WidePrimitive::Block`]): [`SphereBlock`] (centers and squared radii),
//! [`MollerTrumboreBlock`] (a vertex, both edges and their cross product, precomputed by the operations the
//! scalar test does) and [`WatertightBlock`] (the three vertices). Every block answers one lane at a time
//! ([`LeafBlock::lane`], the scalar kernel) and a vector of lanes at a time ([`LeafBlock::lanes`], the SIMD
//! kernels), with the same IEEE operations in the same order, so every kernel returns the same bits.

use glam::Vec3;

#[cfg(target_arch = "x86_64")]
use super::kernel::lanes::{self, Vf};
use super::ray::{RayLanes, Shear};
use crate::accel::bvh::split::Referenced;
use crate::geometry::{MollerTrumboreTriangle, Ray, Sphere, Triangle, WatertightTriangle};

/// Id of a padding lane.
pub const PAD: u32 = u32::MAX;

/// A primitive the wide BVH stores in SIMD leaf blocks.
pub trait WidePrimitive: Referenced {
    /// Its block of `B` lanes.
    type Block<const B: usize>: LeafBlock<B, Prim = Self>;

    /// Computes what the leaf test reads once per ray into `ray` (nothing, unless the test has per-ray setup).
    #[inline(always)]
    fn prepare(_ray: &mut RayLanes) {}
}

/// `B` primitives laid out for a kernel's leaf test, and their ids in the scene.
pub trait LeafBlock<const B: usize>: Copy + Send + Sync + std::fmt::Debug + 'static {
    /// The primitive.
    type Prim;
    /// A block of padding only: lanes of NaN that fail every comparison, ids [`PAD`].
    const PADDING: Self;

    /// Scene index of each lane's primitive, [`PAD`] for padding.
    fn ids(&self) -> &[u32; B];

    /// Writes `prim`, whose scene index is `id`, into `lane`.
    fn set(&mut self, lane: usize, prim: &Self::Prim, id: u32);

    /// Hit distance of lane `lane` in `(t_min, t_max)`, or infinity: the scalar kernel's test.
    fn lane(&self, r: &RayLanes, t_max: f32, lane: usize) -> f32;

    /// Hit distances (infinity where missed) and hit mask of the `V::LANES` lanes from `first`: the SIMD kernels'
    /// test, bit-identical to [`LeafBlock::lane`].
    ///
    /// # Safety
    /// The CPU supports `V`'s instructions, and `first + V::LANES <= B`.
    #[cfg(target_arch = "x86_64")]
    unsafe fn lanes<V: Vf>(&self, first: usize, r: &RayLanes, t_max: f32) -> (V, V::M);

    /// The block of (at most `B`) `prims`, whose scene indices are `ids`, padded.
    #[inline(always)]
    fn of(prims: &[Self::Prim], ids: &[u32]) -> Self {
        let mut block = Self::PADDING;
        for (lane, (p, &id)) in prims.iter().zip(ids).enumerate() {
            block.set(lane, p, id);
        }
        block
    }

    /// Appends blocks holding `prims` (whose scene indices are `ids`), the last one padded; returns how many.
    fn append(out: &mut Vec<Self>, prims: &[Self::Prim], ids: &[u32]) -> usize {
        assert_eq!(prims.len(), ids.len());
        for (prims, ids) in prims.chunks(B).zip(ids.chunks(B)) {
            out.push(Self::of(prims, ids));
        }
        ids.len().div_ceil(B)
    }

    /// [`LeafBlock::append`] into the first blocks of `out`, which must have room; returns how many.
    fn write(out: &mut [Self], prims: &[Self::Prim], ids: &[u32]) -> usize {
        assert_eq!(prims.len(), ids.len());
        for (block, (prims, ids)) in out[..ids.len().div_ceil(B)].iter_mut().zip(prims.chunks(B).zip(ids.chunks(B))) {
            *block = Self::of(prims, ids);
        }
        ids.len().div_ceil(B)
    }

    /// Real (non-padding) lanes: they come first.
    #[inline(always)]
    fn len(&self) -> usize {
        self.ids().iter().take_while(|&&id| id != PAD).count()
    }

    /// True for a block of padding only (never built).
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Every float of the block, row by row (for fingerprints).
    fn floats(&self) -> impl Iterator<Item = f32> + '_;
}

/// `B` spheres as rows of lanes: centers and squared radii (what [`Sphere::intersect`] reads).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct SphereBlock<const B: usize> {
    /// Center x.
    pub cx: [f32; B],
    /// Center y.
    pub cy: [f32; B],
    /// Center z.
    pub cz: [f32; B],
    /// Squared radius, `radius * radius` as [`Sphere::intersect`] computes it.
    pub r2: [f32; B],
    /// Scene index of each lane's sphere, [`PAD`] for padding.
    pub ids: [u32; B],
}

const _: () = assert!(std::mem::size_of::<SphereBlock<8>>() == 160 && std::mem::size_of::<SphereBlock<16>>() == 320);

impl WidePrimitive for Sphere {
    type Block<const B: usize> = SphereBlock<B>;
}

impl<const B: usize> LeafBlock<B> for SphereBlock<B> {
    type Prim = Sphere;
    const PADDING: Self =
        Self { cx: [f32::NAN; B], cy: [f32::NAN; B], cz: [f32::NAN; B], r2: [f32::NAN; B], ids: [PAD; B] };

    #[inline(always)]
    fn ids(&self) -> &[u32; B] {
        &self.ids
    }

    #[inline(always)]
    fn set(&mut self, lane: usize, s: &Sphere, id: u32) {
        (self.cx[lane], self.cy[lane], self.cz[lane]) = (s.center.x, s.center.y, s.center.z);
        self.r2[lane] = s.radius * s.radius;
        self.ids[lane] = id;
    }

    /// [`Sphere::intersect`] with the squared radius stored. Padding lanes (NaN) never hit.
    #[inline(always)]
    fn lane(&self, r: &RayLanes, t_max: f32, lane: usize) -> f32 {
        let c = Vec3::new(self.cx[lane], self.cy[lane], self.cz[lane]);
        let r2 = self.r2[lane];
        let d = Vec3::from_array(r.dir);
        let f = Vec3::from_array(r.origin) - c;
        let a = r.a;
        let b = f.dot(d);
        let offset = f - d * (b / a);
        let disc = a * (r2 - offset.dot(offset));
        if disc < 0.0 {
            return f32::INFINITY;
        }
        let c = f.dot(f) - r2;
        let q = -(b + disc.sqrt().copysign(b));
        let (r0, r1) = (c / q, q / a);
        let (near, far) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
        if near > r.t_min && near < t_max {
            near
        } else if far > r.t_min && far < t_max {
            far
        } else {
            f32::INFINITY
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn lanes<V: Vf>(&self, first: usize, r: &RayLanes, t_max: f32) -> (V, V::M) {
        // SAFETY: forwarded from the caller.
        unsafe { lanes::spheres::<V, B>(self, first, r, t_max) }
    }

    fn floats(&self) -> impl Iterator<Item = f32> + '_ {
        [&self.cx, &self.cy, &self.cz, &self.r2].into_iter().flatten().copied()
    }
}

/// `B` triangles for the Möller–Trumbore test: `p0`, the edges `e1 = p1 − p0`, `e2 = p2 − p0` and `n = e1 × e2`,
/// each a row per axis, computed once by the operations [`Triangle::intersect_moller_trumbore`] does per ray.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct MollerTrumboreBlock<const B: usize> {
    /// `p0`, `e1`, `e2`, `n`: x, y and z rows of each.
    pub rows: [[[f32; B]; 3]; 4],
    /// Scene index of each lane's triangle, [`PAD`] for padding.
    pub ids: [u32; B],
}

impl WidePrimitive for MollerTrumboreTriangle {
    type Block<const B: usize> = MollerTrumboreBlock<B>;
}

impl<const B: usize> LeafBlock<B> for MollerTrumboreBlock<B> {
    type Prim = MollerTrumboreTriangle;
    const PADDING: Self = Self { rows: [[[f32::NAN; B]; 3]; 4], ids: [PAD; B] };

    #[inline(always)]
    fn ids(&self) -> &[u32; B] {
        &self.ids
    }

    #[inline(always)]
    fn set(&mut self, lane: usize, t: &MollerTrumboreTriangle, id: u32) {
        let [p0, e1, e2, n] = t.0.moller_trumbore_frame();
        for (row, v) in self.rows.iter_mut().zip([p0, e1, e2, n]) {
            (row[0][lane], row[1][lane], row[2][lane]) = (v.x, v.y, v.z);
        }
        self.ids[lane] = id;
    }

    #[inline(always)]
    fn lane(&self, r: &RayLanes, t_max: f32, lane: usize) -> f32 {
        let [p0, e1, e2, n] = self.rows.map(|row| Vec3::new(row[0][lane], row[1][lane], row[2][lane]));
        Triangle::moller_trumbore(p0, e1, e2, n, &r.ray(), t_max).map_or(f32::INFINITY, |h| h.t)
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn lanes<V: Vf>(&self, first: usize, r: &RayLanes, t_max: f32) -> (V, V::M) {
        // SAFETY: forwarded from the caller.
        unsafe { lanes::moller_trumbore::<V, B>(self, first, r, t_max) }
    }

    fn floats(&self) -> impl Iterator<Item = f32> + '_ {
        self.rows.iter().flatten().flatten().copied()
    }
}

/// `B` triangles for the watertight test: the vertices, a row per axis.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct WatertightBlock<const B: usize> {
    /// `p0`, `p1`, `p2`: x, y and z rows of each.
    pub rows: [[[f32; B]; 3]; 3],
    /// Scene index of each lane's triangle, [`PAD`] for padding.
    pub ids: [u32; B],
}

impl WidePrimitive for WatertightTriangle {
    type Block<const B: usize> = WatertightBlock<B>;

    /// The ray space's permutation and shear ([`Shear`]), which the SIMD leaf test would otherwise redo per block.
    #[inline(always)]
    fn prepare(ray: &mut RayLanes) {
        ray.shear = Shear::new(Vec3::from_array(ray.dir));
    }
}

impl<const B: usize> WatertightBlock<B> {
    /// The triangle of `lane`.
    #[inline(always)]
    pub fn triangle(&self, lane: usize) -> Triangle {
        let [p0, p1, p2] = self.rows.map(|row| Vec3::new(row[0][lane], row[1][lane], row[2][lane]));
        Triangle::new(p0, p1, p2)
    }
}

impl<const B: usize> LeafBlock<B> for WatertightBlock<B> {
    type Prim = WatertightTriangle;
    const PADDING: Self = Self { rows: [[[f32::NAN; B]; 3]; 3], ids: [PAD; B] };

    #[inline(always)]
    fn ids(&self) -> &[u32; B] {
        &self.ids
    }

    #[inline(always)]
    fn set(&mut self, lane: usize, t: &WatertightTriangle, id: u32) {
        for (row, v) in self.rows.iter_mut().zip(t.0.p) {
            (row[0][lane], row[1][lane], row[2][lane]) = (v.x, v.y, v.z);
        }
        self.ids[lane] = id;
    }

    #[inline(always)]
    fn lane(&self, r: &RayLanes, t_max: f32, lane: usize) -> f32 {
        self.triangle(lane).intersect_watertight(&r.ray(), t_max).map_or(f32::INFINITY, |h| h.t)
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn lanes<V: Vf>(&self, first: usize, r: &RayLanes, t_max: f32) -> (V, V::M) {
        // SAFETY: forwarded from the caller.
        unsafe { lanes::watertight::<V, B>(self, first, r, t_max) }
    }

    fn floats(&self) -> impl Iterator<Item = f32> + '_ {
        self.rows.iter().flatten().flatten().copied()
    }
}

/// A ray of [`RayLanes`] as a [`Ray`] (`t_max` is the caller's).
impl RayLanes {
    /// The ray these lanes were prepared from (with an unbounded `t_max`).
    #[inline(always)]
    pub fn ray(&self) -> Ray {
        Ray {
            origin: Vec3::from_array(self.origin),
            dir: Vec3::from_array(self.dir),
            t_min: self.t_min,
            t_max: f32::INFINITY,
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn blocks_are_filled_in_order_and_padded() {
        let spheres: Vec<Sphere> = (0..11).map(|i| Sphere::new(Vec3::splat(i as f32), 0.5 + i as f32)).collect();
        let ids: Vec<u32> = (0..11).rev().collect();
        let ordered: Vec<Sphere> = ids.iter().map(|&i| spheres[i as usize]).collect();
        let mut blocks = Vec::new();
        assert_eq!(SphereBlock::<4>::append(&mut blocks, &ordered, &ids), 3);
        assert_eq!(blocks.iter().map(SphereBlock::len).collect::<Vec<_>>(), [4, 4, 3]);
        assert_eq!(blocks[0].ids, [10, 9, 8, 7]);
        assert_eq!((blocks[2].cx[2], blocks[2].r2[2]), (0.0, 0.25));
        assert!(blocks[2].cx[3].is_nan() && blocks[2].ids[3] == PAD);
        let mut written = [SphereBlock::<4>::PADDING; 4];
        assert_eq!(SphereBlock::write(&mut written, &ordered, &ids), 3);
        assert_eq!(format!("{:?}", &written[..3]), format!("{blocks:?}"), "the blocks of append (NaN padding)");
        assert!(written[3].is_empty());
    }
}
