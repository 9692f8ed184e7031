//! The kernel of [`SmallProduct`](super::SmallProduct) for x86-64 with AVX-512F: register blocks
//! of up to 6 rows by 4 vectors of 16 columns, the last vector masked, summed over k with fused
//! multiply-adds and finished by the epilogues before one store.

use std::arch::x86_64::*;

use super::{Combine, Matrix};

/// Rows of outputs per register block: 6 rows of 4 vectors keep 24 of the 32 registers.
const ROWS: usize = 6;
/// Vectors of 16 columns per register block.
const VECTORS: usize = 4;
const LANES: usize = 16;

/// `C[p, q] = Σ_j L[p, j] R[j, q]` over `k`, then `ops` (per row of C when their flag is set,
/// else per column), into C with rows `c_row` apart and contiguous columns. `r` must have
/// contiguous columns (`r.mn == 1`).
///
/// # Safety
/// AVX-512F must be available; the pointers must cover the matrices they describe.
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
pub(super) unsafe fn multiply(
    p: usize,
    q: usize,
    k: usize,
    l: Matrix,
    r: Matrix,
    c: *mut f32,
    c_row: isize,
    ops: &[(Combine, bool, *const f32)],
) {
    let mut q0 = 0;
    while q0 < q {
        let width = (q - q0).min(VECTORS * LANES);
        let tail = width % LANES;
        let mask: __mmask16 = if tail == 0 { 0xffff } else { (1 << tail) - 1 };
        let mut p0 = 0;
        while p0 < p {
            let rows = (p - p0).min(ROWS);
            let block = Block { k, l, r, c, c_row, p0, q0, mask, ops };
            macro_rules! by_vectors {
                ($rows:literal) => {
                    match width.div_ceil(LANES) {
                        1 => block.run::<$rows, 1>(),
                        2 => block.run::<$rows, 2>(),
                        3 => block.run::<$rows, 3>(),
                        _ => block.run::<$rows, 4>(),
                    }
                };
            }
            match rows {
                6 => by_vectors!(6),
                5 => by_vectors!(5),
                4 => by_vectors!(4),
                3 => by_vectors!(3),
                2 => by_vectors!(2),
                _ => by_vectors!(1),
            }
            p0 += rows;
        }
        q0 += width;
    }
}

/// One register block of C: rows `p0..p0 + R`, columns `q0..q0 + 16·V` (the last vector masked).
struct Block<'a> {
    k: usize,
    l: Matrix,
    r: Matrix,
    c: *mut f32,
    c_row: isize,
    p0: usize,
    q0: usize,
    mask: __mmask16,
    ops: &'a [(Combine, bool, *const f32)],
}

impl Block<'_> {
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn run<const R: usize, const V: usize>(&self) {
        let full: __mmask16 = 0xffff;
        let lane_mask = |v: usize| if v + 1 == V { self.mask } else { full };
        let mut acc = [[_mm512_setzero_ps(); V]; R];
        let l = self.l.ptr.offset(self.p0 as isize * self.l.mn);
        let r = self.r.ptr.add(self.q0);
        for j in 0..self.k as isize {
            let mut b = [_mm512_setzero_ps(); V];
            for (v, b) in b.iter_mut().enumerate() {
                *b = _mm512_maskz_loadu_ps(lane_mask(v), r.offset(j * self.r.k + (v * LANES) as isize));
            }
            for (i, acc) in acc.iter_mut().enumerate() {
                let a = _mm512_set1_ps(*l.offset(i as isize * self.l.mn + j * self.l.k));
                for v in 0..V {
                    acc[v] = _mm512_fmadd_ps(a, b[v], acc[v]);
                }
            }
        }
        for &(op, per_row, x) in self.ops {
            let apply = |acc: __m512, y: __m512| match op {
                Combine::Add => _mm512_add_ps(acc, y),
                Combine::Mul => _mm512_mul_ps(acc, y),
            };
            for (i, acc) in acc.iter_mut().enumerate() {
                for (v, acc) in acc.iter_mut().enumerate() {
                    let y = if per_row {
                        _mm512_set1_ps(*x.add(self.p0 + i))
                    } else {
                        _mm512_maskz_loadu_ps(lane_mask(v), x.add(self.q0 + v * LANES))
                    };
                    *acc = apply(*acc, y);
                }
            }
        }
        let c = self.c.offset(self.p0 as isize * self.c_row).add(self.q0);
        for (i, acc) in acc.iter().enumerate() {
            for (v, acc) in acc.iter().enumerate() {
                _mm512_mask_storeu_ps(c.offset(i as isize * self.c_row + (v * LANES) as isize), lane_mask(v), *acc);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::small_products::available;

    fn values(len: usize, seed: usize) -> Vec<f32> {
        (0..len).map(|i| (((i + seed) * 7919 % 211) as f32 - 105.0) / 53.0).collect()
    }

    /// Every block shape (rows 1–6, vectors 1–4, masked tails), strided operands and both
    /// epilogue kinds, against a plain triple loop.
    #[test]
    fn the_kernel_computes_plain_products() {
        if !available() {
            return;
        }
        for (p, q, k) in [(1, 1, 1), (7, 20, 20), (13, 40, 3), (76, 76, 20), (375, 20, 40), (6, 64, 5), (5, 65, 2), (12, 130, 7)] {
            let (lv, rv) = (values(p * k * 2, 1), values(k * q, 2));
            // L strided: row i, column j at 2·(i + j·p).
            let l = Matrix { ptr: lv.as_ptr(), mn: 2, k: 2 * p as isize };
            let r = Matrix { ptr: rv.as_ptr(), mn: 1, k: q as isize };
            let (rows, cols) = (values(p, 3), values(q, 4));
            let ops = [(Combine::Add, false, cols.as_ptr()), (Combine::Mul, true, rows.as_ptr()), (Combine::Add, true, rows.as_ptr())];
            let c_row = q as isize + 3;
            let mut c = vec![f32::NAN; p * c_row as usize];
            unsafe { multiply(p, q, k, l, r, c.as_mut_ptr(), c_row, &ops) };
            for i in 0..p {
                for j in 0..q {
                    let sum: f32 = (0..k).map(|s| lv[2 * (i + s * p)] * rv[s * q + j]).sum();
                    let want = (sum + cols[j]) * rows[i] + rows[i];
                    let got = c[i * c_row as usize + j];
                    assert!((got - want).abs() <= 1e-5 * want.abs().max(1.0), "{p}x{q}x{k} at {i},{j}: {got} vs {want}");
                }
                assert!(c[i * c_row as usize + q..(i + 1) * c_row as usize].iter().all(|v| v.is_nan()), "wrote past the row");
            }
        }
    }
}
