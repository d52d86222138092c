//! Acceleration structures behind one small trait: closest hit and any hit (occlusion).
//!
//! [`List`] is the brute-force reference; [`Bvh`] is the paper's pointer tree; [`FlatBvh`] is the same
//! tree in one array; [`WideBvh`] collapses it into 4- or 8-wide nodes with SIMD leaves. Each is generic over the
//! primitive ([`crate::geometry::Primitive`]: spheres, or triangles with their test). [`AccelParams`] chooses and
//! parameterizes one at run time, [`BuiltAccel`] holds it, and an [`AccelVisitor`] reaches the concrete type so that
//! hot loops stay monomorphic.

pub mod bvh;
mod list;
mod null;
pub mod wide;

use serde::{Deserialize, Serialize};

use crate::counters::Counters;
use crate::geometry::{Ray, Sphere};
use wide::WidePrimitive;

pub use bvh::{Bvh, BvhParams, FlatBvh, Split, Traversal, TreeStats};
pub use list::List;
pub use null::Null;
pub use wide::{WideBvh, WideParams};

/// The closest intersection found: distance along the ray and the primitive's index in the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Index of the primitive in the scene's primitive list.
    pub prim: u32,
}

/// A structure that answers ray queries over the primitives it was built from.
pub trait Accelerator: Send + Sync {
    /// The nearest hit in `(ray.t_min, ray.t_max)`, if any.
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit>;
    /// True when any primitive is hit in `(ray.t_min, ray.t_max)`.
    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool;
    /// Size and quality of the built structure.
    fn stats(&self) -> TreeStats;

    /// Closest hits of many rays (`out[i]` for `rays[i]`, misses as `PrimaryHits::MISS`); packet backends override it.
    fn intersect_batch<C: Counters>(&self, rays: &[Ray], out: &mut [Hit], counters: &mut C) {
        for (ray, o) in rays.iter().zip(out) {
            counters.ray();
            *o = self.intersect(ray, counters).unwrap_or(crate::render::PrimaryHits::MISS);
        }
    }

    /// Occlusion of many rays; packet backends override it.
    fn occluded_batch<C: Counters>(&self, rays: &[Ray], out: &mut [bool], counters: &mut C) {
        for (ray, o) in rays.iter().zip(out) {
            counters.ray();
            *o = self.occluded(ray, counters);
        }
    }
}

/// Which acceleration structure to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[derive(Default)]
pub enum AccelKind {
    /// Brute force over every primitive.
    List,
    /// The paper's pointer-based tree of boxed nodes.
    Bvh,
    /// The same tree in one contiguous array.
    #[default]
    FlatBvh,
    /// The tree collapsed into 4- or 8-wide nodes with SIMD leaves ([`WideBvh`]).
    WideBvh,
}

impl AccelKind {
    /// Every kind the harness lists, in the order it lists them.
    pub const ALL: [AccelKind; 4] = [AccelKind::List, AccelKind::Bvh, AccelKind::FlatBvh, AccelKind::WideBvh];

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            AccelKind::List => "list",
            AccelKind::Bvh => "bvh",
            AccelKind::FlatBvh => "flat-bvh",
            AccelKind::WideBvh => "wide-bvh",
        }
    }
}

/// Everything that selects and shapes one accelerator (tree parameters are ignored by `List`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub struct AccelParams {
    /// The structure.
    pub kind: AccelKind,
    /// Tree parameters for `Bvh` and `FlatBvh`, and of the binary tree `WideBvh` is collapsed from.
    pub bvh: BvhParams,
    /// Parameters of `WideBvh` (ignored by the others). Left out when serialized at their default, and filled
    /// with it when missing, so the other kinds' serialized parameters are what they were before it existed.
    #[serde(default, skip_serializing_if = "WideParams::is_default")]
    pub wide: WideParams,
}

/// A built accelerator of any kind, over primitives `P`.
#[derive(Debug)]
pub enum BuiltAccel<P: WidePrimitive = Sphere> {
    /// See [`List`].
    List(List<P>),
    /// See [`Bvh`].
    Bvh(Bvh<P>),
    /// See [`FlatBvh`].
    FlatBvh(FlatBvh<P>),
    /// See [`WideBvh`].
    WideBvh(WideBvh<P>),
}

/// Code run with the concrete accelerator type, so that its loops are compiled for that type.
pub trait AccelVisitor {
    /// What the visit returns.
    type Output;
    /// Runs with the concrete accelerator.
    fn visit<A: Accelerator>(self, accel: &A) -> Self::Output;
}

impl<P: WidePrimitive> BuiltAccel<P> {
    /// Builds the structure `params` names over `prims` (the tree parameters must be valid, and for `WideBvh`
    /// the kernel available on this CPU: see [`WideParams::validate`]).
    ///
    /// Trees build with the threads of the current rayon pool (outside any pool: rayon's global pool), so run
    /// it inside `pool.install(..)` to choose the thread count; the tree is identical whatever the thread count
    /// (see [`bvh::builder`]).
    pub fn build(prims: &[P], params: &AccelParams) -> Self {
        match params.kind {
            AccelKind::List => BuiltAccel::List(List::build(prims)),
            AccelKind::Bvh => BuiltAccel::Bvh(Bvh::build(prims, &params.bvh)),
            AccelKind::FlatBvh => BuiltAccel::FlatBvh(FlatBvh::build(prims, &params.bvh)),
            AccelKind::WideBvh => BuiltAccel::WideBvh(WideBvh::build(prims, &params.bvh, &params.wide)),
        }
    }

    /// The wide BVH of `params` over a binary tree built elsewhere ([`WideBvh::try_from_tree`]).
    pub fn wide_from_tree(built: &bvh::tree::BuiltTree<P>, params: &AccelParams) -> Result<Self, bvh::ParamError> {
        WideBvh::try_from_tree(built, &params.bvh, &params.wide).map(BuiltAccel::WideBvh)
    }

    /// Calls `visitor` with the concrete structure.
    pub fn visit<V: AccelVisitor>(&self, visitor: V) -> V::Output {
        match self {
            BuiltAccel::List(a) => visitor.visit(a),
            BuiltAccel::Bvh(a) => visitor.visit(a),
            BuiltAccel::FlatBvh(a) => visitor.visit(a),
            BuiltAccel::WideBvh(a) => visitor.visit(a),
        }
    }

    /// Size and quality of the built structure.
    pub fn stats(&self) -> TreeStats {
        match self {
            BuiltAccel::List(a) => a.stats(),
            BuiltAccel::Bvh(a) => a.stats(),
            BuiltAccel::FlatBvh(a) => a.stats(),
            BuiltAccel::WideBvh(a) => a.stats(),
        }
    }

    /// The SIMD kernel the structure runs (`avx2`, …) for a `WideBvh`; `None` for the others.
    pub fn kernel_name(&self) -> Option<&'static str> {
        match self {
            BuiltAccel::WideBvh(a) => Some(a.kernel_name()),
            _ => None,
        }
    }
}
