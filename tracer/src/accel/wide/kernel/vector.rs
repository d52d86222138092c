//! A vector of f32 lanes ([`Vf`]: `__m128`, `__m256` or `__m512`, 4, 8 or 16 lanes), what the tests of
//! [`super::lanes`] are written over.
//!
//! Every operation is the IEEE operation the scalar code does: `min`/`max` are the x86 `(a < b) ? a : b` /
//! `(a > b) ? a : b` that `lo`/`hi` in [`crate::geometry::RayBoxTester`] are, comparisons are ordered (false on NaN)
//! like Rust's, `copysign` and negation are bit operations.

use std::arch::x86_64::*;

/// A vector of f32 lanes and its lane mask. Every method is unsafe: it runs only inside a kernel's `run`, on a
/// CPU with the instructions its implementation uses.
#[allow(clippy::missing_safety_doc)] // One contract for every method, stated above.
pub trait Vf: Copy {
    /// Lane mask (a vector of all-ones lanes, or an AVX-512 mask register).
    type M: Copy;
    /// Lanes.
    const LANES: usize;
    unsafe fn splat(x: f32) -> Self;
    /// Loads `LANES` floats from `p` (any alignment).
    unsafe fn load(p: *const f32) -> Self;
    unsafe fn store(self, p: *mut f32);
    unsafe fn add(self, o: Self) -> Self;
    unsafe fn sub(self, o: Self) -> Self;
    unsafe fn mul(self, o: Self) -> Self;
    unsafe fn div(self, o: Self) -> Self;
    unsafe fn sqrt(self) -> Self;
    /// `self < o ? self : o`.
    unsafe fn lo(self, o: Self) -> Self;
    /// `self > o ? self : o`.
    unsafe fn hi(self, o: Self) -> Self;
    /// Magnitude of `self`, sign of `sign`.
    unsafe fn copysign(self, sign: Self) -> Self;
    unsafe fn neg(self) -> Self;
    unsafe fn lt(self, o: Self) -> Self::M;
    unsafe fn le(self, o: Self) -> Self::M;
    unsafe fn gt(self, o: Self) -> Self::M;
    unsafe fn eq(self, o: Self) -> Self::M;
    unsafe fn and(a: Self::M, b: Self::M) -> Self::M;
    unsafe fn or(a: Self::M, b: Self::M) -> Self::M;
    /// `m ? a : b`, lane by lane.
    unsafe fn select(m: Self::M, a: Self, b: Self) -> Self;
    /// One bit per lane, lane 0 lowest.
    unsafe fn bits(m: Self::M) -> u32;
    /// The smallest lane (no lane is NaN).
    unsafe fn reduce_lo(self) -> f32;
}

const SIGN: i32 = i32::MIN;

impl Vf for __m128 {
    type M = __m128;
    const LANES: usize = 4;
    #[inline(always)]
    unsafe fn splat(x: f32) -> Self {
        unsafe { _mm_set1_ps(x) }
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> Self {
        unsafe { _mm_loadu_ps(p) }
    }
    #[inline(always)]
    unsafe fn store(self, p: *mut f32) {
        unsafe { _mm_storeu_ps(p, self) }
    }
    #[inline(always)]
    unsafe fn add(self, o: Self) -> Self {
        unsafe { _mm_add_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn sub(self, o: Self) -> Self {
        unsafe { _mm_sub_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn mul(self, o: Self) -> Self {
        unsafe { _mm_mul_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn div(self, o: Self) -> Self {
        unsafe { _mm_div_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn sqrt(self) -> Self {
        unsafe { _mm_sqrt_ps(self) }
    }
    #[inline(always)]
    unsafe fn lo(self, o: Self) -> Self {
        unsafe { _mm_min_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn hi(self, o: Self) -> Self {
        unsafe { _mm_max_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn copysign(self, sign: Self) -> Self {
        unsafe {
            let s = _mm_castsi128_ps(_mm_set1_epi32(SIGN));
            _mm_or_ps(_mm_andnot_ps(s, self), _mm_and_ps(s, sign))
        }
    }
    #[inline(always)]
    unsafe fn neg(self) -> Self {
        unsafe { _mm_xor_ps(self, _mm_castsi128_ps(_mm_set1_epi32(SIGN))) }
    }
    #[inline(always)]
    unsafe fn lt(self, o: Self) -> Self {
        unsafe { _mm_cmp_ps::<_CMP_LT_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn le(self, o: Self) -> Self {
        unsafe { _mm_cmp_ps::<_CMP_LE_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn gt(self, o: Self) -> Self {
        unsafe { _mm_cmp_ps::<_CMP_GT_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn eq(self, o: Self) -> Self {
        unsafe { _mm_cmp_ps::<_CMP_EQ_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn and(a: Self, b: Self) -> Self {
        unsafe { _mm_and_ps(a, b) }
    }
    #[inline(always)]
    unsafe fn or(a: Self, b: Self) -> Self {
        unsafe { _mm_or_ps(a, b) }
    }
    #[inline(always)]
    unsafe fn select(m: Self, a: Self, b: Self) -> Self {
        unsafe { _mm_blendv_ps(b, a, m) }
    }
    #[inline(always)]
    unsafe fn bits(m: Self) -> u32 {
        unsafe { _mm_movemask_ps(m) as u32 }
    }
    #[inline(always)]
    unsafe fn reduce_lo(self) -> f32 {
        unsafe {
            let m = _mm_min_ps(self, _mm_movehl_ps(self, self));
            _mm_cvtss_f32(_mm_min_ss(m, _mm_shuffle_ps::<0b01>(m, m)))
        }
    }
}

impl Vf for __m256 {
    type M = __m256;
    const LANES: usize = 8;
    #[inline(always)]
    unsafe fn splat(x: f32) -> Self {
        unsafe { _mm256_set1_ps(x) }
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> Self {
        unsafe { _mm256_loadu_ps(p) }
    }
    #[inline(always)]
    unsafe fn store(self, p: *mut f32) {
        unsafe { _mm256_storeu_ps(p, self) }
    }
    #[inline(always)]
    unsafe fn add(self, o: Self) -> Self {
        unsafe { _mm256_add_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn sub(self, o: Self) -> Self {
        unsafe { _mm256_sub_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn mul(self, o: Self) -> Self {
        unsafe { _mm256_mul_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn div(self, o: Self) -> Self {
        unsafe { _mm256_div_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn sqrt(self) -> Self {
        unsafe { _mm256_sqrt_ps(self) }
    }
    #[inline(always)]
    unsafe fn lo(self, o: Self) -> Self {
        unsafe { _mm256_min_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn hi(self, o: Self) -> Self {
        unsafe { _mm256_max_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn copysign(self, sign: Self) -> Self {
        unsafe {
            let s = _mm256_castsi256_ps(_mm256_set1_epi32(SIGN));
            _mm256_or_ps(_mm256_andnot_ps(s, self), _mm256_and_ps(s, sign))
        }
    }
    #[inline(always)]
    unsafe fn neg(self) -> Self {
        unsafe { _mm256_xor_ps(self, _mm256_castsi256_ps(_mm256_set1_epi32(SIGN))) }
    }
    #[inline(always)]
    unsafe fn lt(self, o: Self) -> Self {
        unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn le(self, o: Self) -> Self {
        unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn gt(self, o: Self) -> Self {
        unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn eq(self, o: Self) -> Self {
        unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn and(a: Self, b: Self) -> Self {
        unsafe { _mm256_and_ps(a, b) }
    }
    #[inline(always)]
    unsafe fn or(a: Self, b: Self) -> Self {
        unsafe { _mm256_or_ps(a, b) }
    }
    #[inline(always)]
    unsafe fn select(m: Self, a: Self, b: Self) -> Self {
        unsafe { _mm256_blendv_ps(b, a, m) }
    }
    #[inline(always)]
    unsafe fn bits(m: Self) -> u32 {
        unsafe { _mm256_movemask_ps(m) as u32 }
    }
    #[inline(always)]
    unsafe fn reduce_lo(self) -> f32 {
        unsafe { _mm_min_ps(_mm256_castps256_ps128(self), _mm256_extractf128_ps::<1>(self)).reduce_lo() }
    }
}

impl Vf for __m512 {
    type M = __mmask16;
    const LANES: usize = 16;
    #[inline(always)]
    unsafe fn splat(x: f32) -> Self {
        unsafe { _mm512_set1_ps(x) }
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> Self {
        unsafe { _mm512_loadu_ps(p) }
    }
    #[inline(always)]
    unsafe fn store(self, p: *mut f32) {
        unsafe { _mm512_storeu_ps(p, self) }
    }
    #[inline(always)]
    unsafe fn add(self, o: Self) -> Self {
        unsafe { _mm512_add_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn sub(self, o: Self) -> Self {
        unsafe { _mm512_sub_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn mul(self, o: Self) -> Self {
        unsafe { _mm512_mul_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn div(self, o: Self) -> Self {
        unsafe { _mm512_div_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn sqrt(self) -> Self {
        unsafe { _mm512_sqrt_ps(self) }
    }
    #[inline(always)]
    unsafe fn lo(self, o: Self) -> Self {
        unsafe { _mm512_min_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn hi(self, o: Self) -> Self {
        unsafe { _mm512_max_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn copysign(self, sign: Self) -> Self {
        unsafe {
            let s = _mm512_set1_epi32(SIGN);
            let (m, g) = (_mm512_castps_si512(self), _mm512_castps_si512(sign));
            _mm512_castsi512_ps(_mm512_or_si512(_mm512_andnot_si512(s, m), _mm512_and_si512(s, g)))
        }
    }
    #[inline(always)]
    unsafe fn neg(self) -> Self {
        unsafe { _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(self), _mm512_set1_epi32(SIGN))) }
    }
    #[inline(always)]
    unsafe fn lt(self, o: Self) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn le(self, o: Self) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn gt(self, o: Self) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn eq(self, o: Self) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn and(a: __mmask16, b: __mmask16) -> __mmask16 {
        a & b
    }
    #[inline(always)]
    unsafe fn or(a: __mmask16, b: __mmask16) -> __mmask16 {
        a | b
    }
    #[inline(always)]
    unsafe fn select(m: __mmask16, a: Self, b: Self) -> Self {
        unsafe { _mm512_mask_blend_ps(m, b, a) }
    }
    #[inline(always)]
    unsafe fn bits(m: __mmask16) -> u32 {
        m as u32
    }
    #[inline(always)]
    unsafe fn reduce_lo(self) -> f32 {
        unsafe { _mm512_reduce_min_ps(self) }
    }
}
