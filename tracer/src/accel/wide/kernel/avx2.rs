//! The AVX2 kernel: 8 lanes of f32 (`__m256`) for 8-wide nodes and 8-sphere blocks, two of them for 16-sphere
//! blocks, 128-bit vectors for 4-wide nodes and 4-sphere blocks. Built with FMA enabled, but the arithmetic is
//! kept unfused (see [`super`]) so that hits agree bit for bit with the scalar tests.

use std::arch::x86_64::__m256;

use super::Query;
use super::simd::Simd;
use crate::accel::wide::collapse::Tree;
use crate::accel::wide::leaf::WidePrimitive;
use crate::accel::wide::order::Order;

/// The AVX2 kernel.
pub struct Avx2;

impl Simd for Avx2 {
    type Block16 = __m256;

    /// The whole traversal compiled for AVX2 and FMA.
    ///
    /// # Safety
    /// The CPU supports AVX2 and FMA ([`crate::accel::wide::Kernel::Avx2`] is available).
    #[inline(never)]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn run<Q: Query, O: Order, Prim: WidePrimitive, const W: usize, const B: usize>(
        query: Q,
        tree: &Tree<W, B, Prim>,
    ) -> Q::Out {
        // SAFETY: the caller checked the CPU.
        unsafe { query.run::<Self, O, Prim, W, B>(tree) }
    }
}
