//! The AVX2 kernel: 8 lanes of f32 (`__m256`) for 8-wide nodes and 8-sphere blocks, two of them for 16-sphere
//! blocks, 128-bit vectors for 4-wide nodes and 4-sphere blocks. Built with FMA enabled, but the arithmetic is
//! kept unfused (see [`super`]) so that hits agree bit for bit with the scalar tests.

use std::arch::x86_64::{__m128, __m256};

use super::lanes;
use super::{Ops, Query};
use crate::accel::wide::collapse::Tree;
use crate::accel::wide::leaf::Block;
use crate::accel::wide::node::WideNode;
use crate::accel::wide::order::Order;
use crate::accel::wide::ray::{FrustumLanes, RayLanes};

/// The AVX2 kernel.
pub struct Avx2;

/// Runs `query` with the AVX2 kernel: the whole traversal is compiled for AVX2 and FMA.
///
/// # Safety
/// The CPU supports AVX2 and FMA ([`crate::accel::wide::Kernel::Avx2`] is available).
#[inline(never)]
#[target_feature(enable = "avx2,fma")]
pub unsafe fn run<Q: Query, O: Order, const W: usize, const B: usize>(query: Q, tree: &Tree<W, B>) -> Q::Out {
    // SAFETY: the caller checked the CPU.
    unsafe { query.run::<Avx2, O, W, B>(tree) }
}

impl Ops for Avx2 {
    #[inline(always)]
    unsafe fn run_apart<Q: Query, O: Order, const W: usize, const B: usize>(query: Q, tree: &Tree<W, B>) -> Q::Out {
        // SAFETY: forwarded from the caller.
        unsafe { run::<Q, O, W, B>(query, tree) }
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
    unsafe fn closest<const B: usize>(block: &Block<B>, r: &RayLanes, t_max: f32) -> Option<(f32, usize)> {
        unsafe {
            if B == 4 {
                lanes::closest::<__m128, B>(block, r, t_max)
            } else {
                lanes::closest::<__m256, B>(block, r, t_max)
            }
        }
    }

    #[inline(always)]
    unsafe fn any<const B: usize>(block: &Block<B>, r: &RayLanes, t_max: f32) -> bool {
        unsafe {
            if B == 4 { lanes::any::<__m128, B>(block, r, t_max) } else { lanes::any::<__m256, B>(block, r, t_max) }
        }
    }
}
