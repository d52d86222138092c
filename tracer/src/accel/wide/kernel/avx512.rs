//! The AVX-512 kernel: 16-sphere blocks in one `__m512` (masks in `k` registers); nodes and narrower blocks as in
//! [`super::avx2`], compiled with AVX-512F enabled (which implies AVX2 and FMA).

use std::arch::x86_64::__m512;

use super::avx2::Avx2;
use super::lanes;
use super::{Ops, Query};
use crate::accel::wide::collapse::Tree;
use crate::accel::wide::leaf::Block;
use crate::accel::wide::node::WideNode;
use crate::accel::wide::order::Order;
use crate::accel::wide::ray::{FrustumLanes, RayLanes};

/// The AVX-512 kernel.
pub struct Avx512;

/// Runs `query` with the AVX-512 kernel: the whole traversal is compiled for AVX-512F, AVX2 and FMA.
///
/// # Safety
/// The CPU supports AVX-512F, AVX2 and FMA ([`crate::accel::wide::Kernel::Avx512`] is available).
#[inline(never)]
#[target_feature(enable = "avx512f,avx2,fma")]
pub unsafe fn run<Q: Query, O: Order, const W: usize, const B: usize>(query: Q, tree: &Tree<W, B>) -> Q::Out {
    // SAFETY: the caller checked the CPU.
    unsafe { query.run::<Avx512, O, W, B>(tree) }
}

impl Ops for Avx512 {
    #[inline(always)]
    unsafe fn run_apart<Q: Query, O: Order, const W: usize, const B: usize>(query: Q, tree: &Tree<W, B>) -> Q::Out {
        // SAFETY: forwarded from the caller.
        unsafe { run::<Q, O, W, B>(query, tree) }
    }

    #[inline(always)]
    unsafe fn boxes<const W: usize>(node: &WideNode<W>, r: &RayLanes, t_max: f32, dist: &mut [f32; W]) -> u32 {
        unsafe { Avx2::boxes(node, r, t_max, dist) }
    }

    #[inline(always)]
    unsafe fn frustum_boxes<const W: usize>(
        node: &WideNode<W>,
        f: &FrustumLanes,
        t_max: f32,
        dist: &mut [f32; W],
    ) -> u32 {
        unsafe { Avx2::frustum_boxes(node, f, t_max, dist) }
    }

    #[inline(always)]
    unsafe fn closest<const B: usize>(block: &Block<B>, r: &RayLanes, t_max: f32) -> Option<(f32, usize)> {
        unsafe { if B == 16 { lanes::closest::<__m512, B>(block, r, t_max) } else { Avx2::closest(block, r, t_max) } }
    }

    #[inline(always)]
    unsafe fn any<const B: usize>(block: &Block<B>, r: &RayLanes, t_max: f32) -> bool {
        unsafe { if B == 16 { lanes::any::<__m512, B>(block, r, t_max) } else { Avx2::any(block, r, t_max) } }
    }
}
