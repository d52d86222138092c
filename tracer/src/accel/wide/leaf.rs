//! SIMD leaves: a leaf's primitives copied into blocks of `B` lanes (SoA), padded with lanes that never hit.
//!
//! Each primitive has its block ([`WidePrimitive::Block`]): [`SphereBlock`] (centers and squared radii),
//! [`MollerTrumboreBlock`] (a vertex, both edges and their cross product, precomputed by the operations the
//! scalar test does) and [`WatertightBlock`] (the three vertices). Every block answers one lane at a time
//! ([`LeafBlock::lane`], the scalar kernel) and a vector of lanes at a time ([`LeafBlock::lanes`], the SIMD
//! kernels), with the same IEEE operations in the same order, so every kernel returns the same bits.
//!
//! This module holds the traits and the layouts; [`super::primitives`] implements them for each primitive.

use glam::Vec3;

#[cfg(target_arch = "x86_64")]
use super::kernel::vector::Vf;
use super::ray::RayLanes;
use crate::accel::bvh::split::Referenced;
use crate::geometry::{Ray, Triangle};

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

/// The ray prepared for leaves of a [`WidePrimitive`].
impl RayLanes {
    /// Prepares `ray` for leaves of `P`: [`RayLanes::new`] and what `P`'s leaf test reads once per ray.
    #[inline(always)]
    pub fn for_leaves<P: WidePrimitive>(ray: &Ray) -> Self {
        let mut r = Self::new(ray);
        P::prepare(&mut r);
        r
    }
}

/// `B` spheres as rows of lanes: centers and squared radii (what
/// [`Sphere::intersect`](crate::geometry::Sphere::intersect) reads).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct SphereBlock<const B: usize> {
    /// Center x.
    pub cx: [f32; B],
    /// Center y.
    pub cy: [f32; B],
    /// Center z.
    pub cz: [f32; B],
    /// Squared radius, `radius * radius` as [`Sphere::intersect`](crate::geometry::Sphere::intersect)
    /// computes it.
    pub r2: [f32; B],
    /// Scene index of each lane's sphere, [`PAD`] for padding.
    pub ids: [u32; B],
}

const _: () = assert!(std::mem::size_of::<SphereBlock<8>>() == 160 && std::mem::size_of::<SphereBlock<16>>() == 320);

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

/// `B` triangles for the watertight test: the vertices, a row per axis.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct WatertightBlock<const B: usize> {
    /// `p0`, `p1`, `p2`: x, y and z rows of each.
    pub rows: [[[f32; B]; 3]; 3],
    /// Scene index of each lane's triangle, [`PAD`] for padding.
    pub ids: [u32; B],
}

impl<const B: usize> WatertightBlock<B> {
    /// The triangle of `lane`.
    #[inline(always)]
    pub fn triangle(&self, lane: usize) -> Triangle {
        let [p0, p1, p2] = self.rows.map(|row| Vec3::new(row[0][lane], row[1][lane], row[2][lane]));
        Triangle::new(p0, p1, p2)
    }
}
