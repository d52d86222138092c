//! The SIMD kernels' [`Ops`], written once over [`lanes`]: 128-bit vectors for 4-wide nodes and 4-lane blocks,
//! `__m256` for 8-wide ones, and the kernel's own vector ([`Simd::Block16`]) for 16-lane blocks.

use std::arch::x86_64::{__m128, __m256};

use super::lanes;
use super::vector::Vf;
use super::{Ops, Query};
use crate::accel::wide::collapse::Tree;
use crate::accel::wide::leaf::{LeafBlock, WidePrimitive};
use crate::accel::wide::node::WideNode;
use crate::accel::wide::order::Order;
use crate::accel::wide::ray::{FrustumLanes, RayLanes};

/// A SIMD kernel: its vector for 16-sphere blocks and its entry, compiled for its instructions.
pub trait Simd {
    /// The vector a 16-sphere block is tested in, `LANES` spheres at a time.
    type Block16: Vf;

    /// Runs `query` with the kernel: the whole traversal is compiled for its instructions (`#[target_feature]`,
    /// never inlined into the caller).
    ///
    /// # Safety
    /// The CPU supports the kernel's instructions.
    unsafe fn run<Q: Query, O: Order, P: WidePrimitive, const W: usize, const B: usize>(
        query: Q,
        tree: &Tree<W, B, P>,
    ) -> Q::Out;
}

impl<S: Simd> Ops for S {
    #[inline(always)]
    unsafe fn run_apart<Q: Query, O: Order, P: WidePrimitive, const W: usize, const B: usize>(
        query: Q,
        tree: &Tree<W, B, P>,
    ) -> Q::Out {
        // SAFETY: forwarded from the caller.
        unsafe { S::run::<Q, O, P, W, B>(query, tree) }
    }

    #[inline(always)]
    unsafe fn boxes<const W: usize>(node: &WideNode<W>, r: &RayLanes, t_max: f32, dist: &mut [f32; W]) -> u32 {
        unsafe {
            if W == 4 {
                lanes::boxes::<__m128, W>(node, r, t_max, dist)
            } else {
                lanes::boxes::<__m256, W>(node, r, t_max, dist)
            }
        }
    }

    #[inline(always)]
    unsafe fn frustum_boxes<const W: usize>(
        node: &WideNode<W>,
        f: &FrustumLanes,
        t_max: f32,
        dist: &mut [f32; W],
    ) -> u32 {
        unsafe {
            if W == 4 {
                lanes::frustum_boxes::<__m128, W>(node, f, t_max, dist)
            } else {
                lanes::frustum_boxes::<__m256, W>(node, f, t_max, dist)
            }
        }
    }

    #[inline(always)]
    unsafe fn closest<L: LeafBlock<B>, const B: usize>(block: &L, r: &RayLanes, t_max: f32) -> Option<(f32, usize)> {
        unsafe {
            match B {
                4 => lanes::closest::<__m128, L, B>(block, r, t_max),
                8 => lanes::closest::<__m256, L, B>(block, r, t_max),
                _ => lanes::closest::<S::Block16, L, B>(block, r, t_max),
            }
        }
    }

    #[inline(always)]
    unsafe fn any<L: LeafBlock<B>, const B: usize>(block: &L, r: &RayLanes, t_max: f32) -> bool {
        unsafe {
            match B {
                4 => lanes::any::<__m128, L, B>(block, r, t_max),
                8 => lanes::any::<__m256, L, B>(block, r, t_max),
                _ => lanes::any::<S::Block16, L, B>(block, r, t_max),
            }
        }
    }
}
