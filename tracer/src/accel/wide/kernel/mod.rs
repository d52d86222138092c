//! The instruction-set kernels: the box test of all `W` children of a node and the sphere test of a leaf block.
//!
//! [`Ops`] is what the traversal needs from a kernel; [`scalar`] is portable, [`avx2`] and [`avx512`] use
//! `std::arch` through the lane arithmetic of [`lanes`], written once for every vector width ([`vector`]), and share
//! one [`Ops`] ([`simd`]). Every kernel computes the same IEEE operations in the same order as the scalar code
//! ([`crate::geometry::RayBoxTester::entry`] and [`crate::geometry::Sphere::intersect`]: subtract then multiply, no
//! fused multiply-add), so all kernels give bit-identical distances, hits and therefore work counts.
//!
//! Intrinsics inline only into functions compiled with their target features, so each SIMD kernel has one
//! `#[target_feature]` entry, `run`, that runs a whole [`Query`] (one ray's traversal, or a batch's) with
//! every helper inlined into it; the kernel is chosen once per query, never per node.

#[cfg(target_arch = "x86_64")]
pub mod avx2;
#[cfg(target_arch = "x86_64")]
pub mod avx512;
#[cfg(target_arch = "x86_64")]
pub mod lanes;
pub mod scalar;
#[cfg(target_arch = "x86_64")]
pub mod simd;
#[cfg(target_arch = "x86_64")]
pub mod vector;

use super::collapse::Tree;
use super::leaf::{LeafBlock, WidePrimitive};
use super::node::WideNode;
use super::order::Order;
use super::ray::{FrustumLanes, RayLanes};

/// One kernel's box and sphere tests. Unsafe: callers run them only on a CPU with the kernel's instructions,
/// inside the kernel's `run`.
pub trait Ops {
    /// Slab test of every child of `node` before `t_max`: bit `lane` of the result is set for the children the ray
    /// enters, and `dist[lane]` is their entry distance (as [`crate::geometry::RayBoxTester::entry`]).
    ///
    /// # Safety
    /// The CPU supports the kernel's instructions.
    unsafe fn boxes<const W: usize>(node: &WideNode<W>, ray: &RayLanes, t_max: f32, dist: &mut [f32; W]) -> u32;

    /// Frustum test of every child of `node` before `t_max`: bit `lane` of the result is clear for the children no
    /// ray of the packet enters (before `t_max`), and `dist[lane]` is at most the entry distance of any ray that
    /// enters child `lane` (see [`FrustumLanes`]). Empty lanes are never set.
    ///
    /// # Safety
    /// The CPU supports the kernel's instructions.
    unsafe fn frustum_boxes<const W: usize>(
        node: &WideNode<W>,
        frustum: &FrustumLanes,
        t_max: f32,
        dist: &mut [f32; W],
    ) -> u32;

    /// The nearest hit in `(t_min, t_max)` among the block's primitives: its distance and lowest lane, if any.
    ///
    /// # Safety
    /// The CPU supports the kernel's instructions.
    unsafe fn closest<L: LeafBlock<B>, const B: usize>(block: &L, ray: &RayLanes, t_max: f32) -> Option<(f32, usize)>;

    /// True when any of the block's primitives is hit in `(t_min, t_max)`.
    ///
    /// # Safety
    /// The CPU supports the kernel's instructions.
    unsafe fn any<L: LeafBlock<B>, const B: usize>(block: &L, ray: &RayLanes, t_max: f32) -> bool;

    /// Runs `query` in the kernel's entry function (compiled for the kernel, never inlined into the caller): for a
    /// query that picks one of several traversals per packet, so that each is compiled on its own.
    ///
    /// # Safety
    /// The CPU supports the kernel's instructions.
    unsafe fn run_apart<Q: Query, O: Order, P: WidePrimitive, const W: usize, const B: usize>(
        query: Q,
        tree: &Tree<W, B, P>,
    ) -> Q::Out;
}

/// Work run against a tree with a kernel and child order chosen at compile time (a ray, or a batch of rays).
pub trait Query {
    /// The answer.
    type Out;
    /// Runs the query with kernel `K` and child order `O`; implementations are `#[inline(always)]`, so that
    /// they compile into the kernel's `run`.
    ///
    /// # Safety
    /// The CPU supports `K`'s instructions.
    unsafe fn run<K: Ops, O: Order, P: WidePrimitive, const W: usize, const B: usize>(
        self,
        tree: &Tree<W, B, P>,
    ) -> Self::Out;
}
