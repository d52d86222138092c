//! The AVX-512 kernel: 16-sphere blocks in one `__m512` (masks in `k` registers); nodes and narrower blocks as in
//! [`super::avx2`], compiled with AVX-512F and AVX-512VL enabled (VL lets 256-bit code use all 32 vector
//! registers, so a ray's splatted constants need not be reloaded from the stack at every node).

use std::arch::x86_64::__m512;

use super::Query;
use super::simd::Simd;
use crate::accel::wide::collapse::Tree;
use crate::accel::wide::leaf::WidePrimitive;
use crate::accel::wide::order::Order;

/// The AVX-512 kernel.
pub struct Avx512;

impl Simd for Avx512 {
    type Block16 = __m512;

    /// The whole traversal compiled for AVX-512F, AVX-512VL, AVX2 and FMA.
    ///
    /// # Safety
    /// The CPU supports AVX-512F, AVX-512VL, AVX2 and FMA ([`crate::accel::wide::Kernel::Avx512`] is available).
    #[inline(never)]
    #[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
    unsafe fn run<Q: Query, O: Order, Prim: WidePrimitive, const W: usize, const B: usize>(
        query: Q,
        tree: &Tree<W, B, Prim>,
    ) -> Q::Out {
        // SAFETY: the caller checked the CPU.
        unsafe { query.run::<Self, O, Prim, W, B>(tree) }
    }
}
