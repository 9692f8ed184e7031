//! The vector instructions the kernel of [`SmallProduct`](super::SmallProduct) is written in, for
//! the two x86-64 instruction sets it runs on: AVX-512F (16 lanes, 32 registers) and AVX2 with FMA
//! (8 lanes, 16 registers). Every method inlines into a function compiled for its set.

use std::arch::x86_64::*;

/// One instruction set: its vectors, its masks of leading lanes, and the register block it fits.
pub(super) trait Lanes {
    /// f32 lanes per vector.
    const LANES: usize;
    /// Rows of outputs per register block, and vectors per row: `ROWS × VECTORS` accumulators,
    /// `VECTORS` loaded operands and one broadcast fit in the registers.
    const ROWS: usize;
    const VECTORS: usize;
    type V: Copy;
    type Mask: Copy;

    /// The first `n` lanes (all of them for `n` ≥ `LANES`).
    unsafe fn mask(n: usize) -> Self::Mask;
    unsafe fn zero() -> Self::V;
    unsafe fn splat(x: f32) -> Self::V;
    /// The masked lanes from `p`, zero elsewhere; lanes outside the mask are not read.
    unsafe fn load(mask: Self::Mask, p: *const f32) -> Self::V;
    /// The masked lanes to `p`; lanes outside the mask are not written.
    unsafe fn store(mask: Self::Mask, p: *mut f32, v: Self::V);
    /// All lanes from `p`.
    unsafe fn load_all(p: *const f32) -> Self::V;
    /// All lanes to `p`.
    unsafe fn store_all(p: *mut f32, v: Self::V);
    /// `a · b + c`.
    unsafe fn fma(a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    unsafe fn add(a: Self::V, b: Self::V) -> Self::V;
    unsafe fn mul(a: Self::V, b: Self::V) -> Self::V;
    /// `a − b`.
    unsafe fn sub(a: Self::V, b: Self::V) -> Self::V;
}

pub(super) struct Avx512;

impl Lanes for Avx512 {
    const LANES: usize = 16;
    const ROWS: usize = 6;
    const VECTORS: usize = 4;
    type V = __m512;
    type Mask = __mmask16;

    #[inline(always)]
    unsafe fn mask(n: usize) -> __mmask16 {
        if n >= 16 {
            0xffff
        } else {
            (1 << n) - 1
        }
    }
    #[inline(always)]
    unsafe fn zero() -> __m512 {
        _mm512_setzero_ps()
    }
    #[inline(always)]
    unsafe fn splat(x: f32) -> __m512 {
        _mm512_set1_ps(x)
    }
    #[inline(always)]
    unsafe fn load(mask: __mmask16, p: *const f32) -> __m512 {
        _mm512_maskz_loadu_ps(mask, p)
    }
    #[inline(always)]
    unsafe fn store(mask: __mmask16, p: *mut f32, v: __m512) {
        _mm512_mask_storeu_ps(p, mask, v)
    }
    #[inline(always)]
    unsafe fn load_all(p: *const f32) -> __m512 {
        _mm512_loadu_ps(p)
    }
    #[inline(always)]
    unsafe fn store_all(p: *mut f32, v: __m512) {
        _mm512_storeu_ps(p, v)
    }
    #[inline(always)]
    unsafe fn fma(a: __m512, b: __m512, c: __m512) -> __m512 {
        _mm512_fmadd_ps(a, b, c)
    }
    #[inline(always)]
    unsafe fn add(a: __m512, b: __m512) -> __m512 {
        _mm512_add_ps(a, b)
    }
    #[inline(always)]
    unsafe fn mul(a: __m512, b: __m512) -> __m512 {
        _mm512_mul_ps(a, b)
    }
    #[inline(always)]
    unsafe fn sub(a: __m512, b: __m512) -> __m512 {
        _mm512_sub_ps(a, b)
    }
}

pub(super) struct Avx2;

impl Lanes for Avx2 {
    const LANES: usize = 8;
    const ROWS: usize = 4;
    const VECTORS: usize = 3;
    type V = __m256;
    type Mask = __m256i;

    #[inline(always)]
    unsafe fn mask(n: usize) -> __m256i {
        _mm256_cmpgt_epi32(_mm256_set1_epi32(n.min(8) as i32), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7))
    }
    #[inline(always)]
    unsafe fn zero() -> __m256 {
        _mm256_setzero_ps()
    }
    #[inline(always)]
    unsafe fn splat(x: f32) -> __m256 {
        _mm256_set1_ps(x)
    }
    #[inline(always)]
    unsafe fn load(mask: __m256i, p: *const f32) -> __m256 {
        _mm256_maskload_ps(p, mask)
    }
    #[inline(always)]
    unsafe fn store(mask: __m256i, p: *mut f32, v: __m256) {
        _mm256_maskstore_ps(p, mask, v)
    }
    #[inline(always)]
    unsafe fn load_all(p: *const f32) -> __m256 {
        _mm256_loadu_ps(p)
    }
    #[inline(always)]
    unsafe fn store_all(p: *mut f32, v: __m256) {
        _mm256_storeu_ps(p, v)
    }
    #[inline(always)]
    unsafe fn fma(a: __m256, b: __m256, c: __m256) -> __m256 {
        _mm256_fmadd_ps(a, b, c)
    }
    #[inline(always)]
    unsafe fn add(a: __m256, b: __m256) -> __m256 {
        _mm256_add_ps(a, b)
    }
    #[inline(always)]
    unsafe fn mul(a: __m256, b: __m256) -> __m256 {
        _mm256_mul_ps(a, b)
    }
    #[inline(always)]
    unsafe fn sub(a: __m256, b: __m256) -> __m256 {
        _mm256_sub_ps(a, b)
    }
}
