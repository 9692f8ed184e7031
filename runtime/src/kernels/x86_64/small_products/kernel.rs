//! The kernel of [`SmallProduct`](super::SmallProduct): register blocks of up to `ROWS` rows by
//! `VECTORS` vectors of output columns, the last vector masked, summed over k with fused
//! multiply-adds and finished by the epilogues before one store. One source, compiled once for
//! each instruction set of [`lanes`](super::lanes).

use super::lanes::{Avx2, Avx512, Lanes};
use super::{Combine, Isa, Matrix};

/// `C[p, q] = Σ_j L[p, j] R[j, q]` over `k`, then `ops` (per row of C when their flag is set,
/// else per column), into C with rows `c_row` apart and contiguous columns. `r` must have
/// contiguous columns (`r.mn == 1`).
///
/// # Safety
/// `isa` must be available; the pointers must cover the matrices they describe.
#[allow(clippy::too_many_arguments)]
pub(super) unsafe fn multiply(
    isa: Isa,
    p: usize,
    q: usize,
    k: usize,
    l: Matrix,
    r: Matrix,
    c: *mut f32,
    c_row: isize,
    ops: &[(Combine, bool, *const f32)],
) {
    let block = Block { k, l, r, c, c_row, p0: 0, q0: 0, width: 0, ops };
    match isa {
        Isa::Avx512 => with_avx512(block, p, q),
        Isa::Avx2 => with_avx2(block, p, q),
    }
}

#[target_feature(enable = "avx512f")]
unsafe fn with_avx512(block: Block, p: usize, q: usize) {
    blocks::<Avx512>(block, p, q)
}

#[target_feature(enable = "avx2,fma")]
unsafe fn with_avx2(block: Block, p: usize, q: usize) {
    blocks::<Avx2>(block, p, q)
}

/// C block by block: `I::VECTORS` vectors of columns at a time, `I::ROWS` rows at a time.
#[inline(always)]
unsafe fn blocks<I: Lanes>(mut block: Block, p: usize, q: usize) {
    while block.q0 < q {
        block.width = (q - block.q0).min(I::VECTORS * I::LANES);
        block.p0 = 0;
        while block.p0 < p {
            let rows = (p - block.p0).min(I::ROWS);
            macro_rules! by_vectors {
                ($rows:literal) => {
                    match block.width.div_ceil(I::LANES) {
                        1 => block.run::<I, $rows, 1>(),
                        2 => block.run::<I, $rows, 2>(),
                        3 => block.run::<I, $rows, 3>(),
                        _ => block.run::<I, $rows, 4>(),
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
            block.p0 += rows;
        }
        block.q0 += block.width;
    }
}

/// One register block of C: rows `p0..p0 + R`, columns `q0..q0 + width` as `V` vectors.
#[derive(Clone, Copy)]
struct Block<'a> {
    k: usize,
    l: Matrix,
    r: Matrix,
    c: *mut f32,
    c_row: isize,
    p0: usize,
    q0: usize,
    width: usize,
    ops: &'a [(Combine, bool, *const f32)],
}

impl Block<'_> {
    #[inline(always)]
    unsafe fn run<I: Lanes, const R: usize, const V: usize>(&self) {
        // Only the last vector can be partial.
        let tail = I::mask(self.width - (V - 1) * I::LANES);
        let load = |v: usize, p: *const f32| if v + 1 < V { I::load_all(p) } else { I::load(tail, p) };
        let mut acc = [[I::zero(); V]; R];
        let l = self.l.ptr.offset(self.p0 as isize * self.l.mn);
        let r = self.r.ptr.add(self.q0);
        for j in 0..self.k as isize {
            let b: [I::V; V] = std::array::from_fn(|v| load(v, r.offset(j * self.r.k + (v * I::LANES) as isize)));
            for (i, acc) in acc.iter_mut().enumerate() {
                let a = I::splat(*l.offset(i as isize * self.l.mn + j * self.l.k));
                for v in 0..V {
                    acc[v] = I::fma(a, b[v], acc[v]);
                }
            }
        }
        for &(op, per_row, x) in self.ops {
            for (i, acc) in acc.iter_mut().enumerate() {
                for (v, acc) in acc.iter_mut().enumerate() {
                    let y = if per_row { I::splat(*x.add(self.p0 + i)) } else { load(v, x.add(self.q0 + v * I::LANES)) };
                    *acc = match op {
                        Combine::Add => I::add(*acc, y),
                        Combine::Mul => I::mul(*acc, y),
                        Combine::SubtractedFrom => I::sub(y, *acc),
                        Combine::Subtract => I::sub(*acc, y),
                    };
                }
            }
        }
        let c = self.c.offset(self.p0 as isize * self.c_row).add(self.q0);
        for (i, acc) in acc.iter().enumerate() {
            for (v, acc) in acc.iter().enumerate() {
                let p = c.offset(i as isize * self.c_row + (v * I::LANES) as isize);
                if v + 1 < V {
                    I::store_all(p, *acc)
                } else {
                    I::store(tail, p, *acc)
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::x86_64::small_products::covered;

    fn values(len: usize, seed: usize) -> Vec<f32> {
        (0..len).map(|i| (((i + seed) * 7919 % 211) as f32 - 105.0) / 53.0).collect()
    }

    /// One product on `isa` against a triple loop: L `[p, k]` with row stride `l_mn` and column
    /// stride `l_k` (room for it in `lv`), R `[k, q]` rows `q + r_pad` apart, C rows
    /// `q + c_pad` apart, then `ops` (each: combine, per row, which vector). Values past each
    /// row of C must stay untouched.
    #[allow(clippy::too_many_arguments)]
    fn check(isa: Isa, p: usize, q: usize, k: usize, l_mn: usize, l_k: usize, r_pad: usize, c_pad: usize, ops: &[(Combine, bool)]) {
        let r_row = q + r_pad;
        let (lv, rv) = (values((p - 1) * l_mn + (k - 1) * l_k + 1, 1), values(k * r_row, 2));
        let l = Matrix { ptr: lv.as_ptr(), mn: l_mn as isize, k: l_k as isize };
        let r = Matrix { ptr: rv.as_ptr(), mn: 1, k: r_row as isize };
        let (rows, cols) = (values(p, 3), values(q, 4));
        let vector = |per_row: bool| if per_row { rows.as_ptr() } else { cols.as_ptr() };
        let kernel_ops: Vec<_> = ops.iter().map(|&(op, per_row)| (op, per_row, vector(per_row))).collect();
        let c_row = q + c_pad;
        let mut c = vec![f32::NAN; p * c_row];
        // SAFETY: the tests cover only sets this machine has (`covered`); `lv`, `rv` and `c`
        // were sized for the strides given, `rows` and `cols` hold p and q values.
        unsafe { multiply(isa, p, q, k, l, r, c.as_mut_ptr(), c_row as isize, &kernel_ops) };
        for i in 0..p {
            for j in 0..q {
                let mut want: f32 = (0..k).map(|s| lv[i * l_mn + s * l_k] * rv[s * r_row + j]).sum();
                for &(op, per_row) in ops {
                    let v = if per_row { rows[i] } else { cols[j] };
                    want = op.apply(want, v);
                }
                let got = c[i * c_row + j];
                let scale = (0..k).map(|s| (lv[i * l_mn + s * l_k] * rv[s * r_row + j]).abs()).sum::<f32>().max(1.0);
                assert!((got - want).abs() <= 1e-5 * scale * 4.0, "{isa:?} {p}x{q}x{k} at {i},{j}: {got} vs {want}");
            }
            assert!(c[i * c_row + q..(i + 1) * c_row].iter().all(|v| v.is_nan()), "{isa:?} {p}x{q}x{k} wrote past row {i}");
        }
    }

    /// Every block shape (all row counts, one to four vectors, masked tails), strided operands
    /// and every epilogue, along rows and along columns, on every instruction set the tests cover.
    #[test]
    fn the_kernel_computes_plain_products() {
        let ops = [
            (Combine::Add, false),
            (Combine::Mul, true),
            (Combine::SubtractedFrom, true),
            (Combine::Subtract, false),
            (Combine::Add, true),
        ];
        for isa in covered() {
            for (p, q, k) in [(1, 1, 1), (7, 20, 20), (13, 40, 3), (76, 76, 20), (375, 20, 40), (6, 64, 5), (5, 65, 2), (12, 130, 7)] {
                // L strided: row i, column j at 2·(i + j·p).
                check(isa, p, q, k, 2, 2 * p, 0, 3, &ops);
            }
        }
    }

    /// A randomised sweep: 300 products per instruction set with random sizes (up to 3 blocks
    /// of rows and columns beyond the widest block), row- or column-major left operands, padded
    /// rows and random epilogues, against the triple loop.
    #[test]
    fn a_random_sweep_of_shapes_matches_the_triple_loop() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |n: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n as u64) as usize
        };
        let mut checked = 0;
        for isa in covered() {
            for _ in 0..300 {
                let (p, q, k) = (1 + next(20), 1 + next(200), 1 + next(70));
                let (l_mn, l_k) = if next(2) == 0 { (k + next(3), 1) } else { (1, p + next(3)) };
                let combine = [Combine::Add, Combine::Mul, Combine::SubtractedFrom, Combine::Subtract];
                let ops: Vec<_> = (0..next(4)).map(|_| (combine[next(4)], next(2) == 0)).collect();
                check(isa, p, q, k, l_mn, l_k, next(5), next(5), &ops);
                checked += 1;
            }
        }
        assert!(checked >= 300);
    }
}
