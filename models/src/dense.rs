//! Dense f32 arithmetic for the fused transformer block: matrix products through the `gemm` crate
//! (the kernel candle's own CPU matmul uses, with run-time AVX2/AVX-512/NEON dispatch) behind a
//! bounds-checked strided view, and the short dot and axpy loops of attention over a handful of
//! tokens, where a call into gemm would cost more than its arithmetic.

/// A strided, read-only matrix over a slice: element `(i, j)` is `data[i * row_stride + j * col_stride]`.
#[derive(Clone, Copy, Debug)]
pub struct View<'a> {
    data: &'a [f32],
    rows: usize,
    cols: usize,
    row_stride: usize,
    col_stride: usize,
}

impl<'a> View<'a> {
    /// The row-major `rows × cols` matrix at the start of `data`.
    pub fn rows(data: &'a [f32], rows: usize, cols: usize) -> Self {
        Self { data, rows, cols, row_stride: cols, col_stride: 1 }
    }

    /// `rows × cols` at the start of `data`, rows `row_stride` apart (a column block of a wider matrix).
    pub fn strided(data: &'a [f32], rows: usize, cols: usize, row_stride: usize) -> Self {
        Self { data, rows, cols, row_stride, col_stride: 1 }
    }

    /// The transpose, without moving data.
    pub fn t(self) -> Self {
        Self { rows: self.cols, cols: self.rows, row_stride: self.col_stride, col_stride: self.row_stride, ..self }
    }

    /// Whether every element lies inside `data`.
    fn in_bounds(&self) -> bool {
        self.rows == 0 || self.cols == 0 || (self.rows - 1) * self.row_stride + (self.cols - 1) * self.col_stride < self.data.len()
    }
}

/// `dst = a · b` (or `dst += a · b` with `accumulate`), `dst` row-major `a.rows × b.cols`.
///
/// # Panics
/// If the shapes disagree or a view reaches outside its slice: a caller's bug, never data.
pub fn matmul(dst: &mut [f32], a: View, b: View, accumulate: bool) {
    assert_eq!(dst.len(), a.rows * b.cols, "matmul of {}×{} by {}×{} into {} values", a.rows, a.cols, b.rows, b.cols, dst.len());
    matmul_strided(dst, b.cols, a, b, accumulate);
}

/// [`matmul`] into the `a.rows × b.cols` block at the start of `dst` whose rows are
/// `dst_row_stride` apart.
pub fn matmul_strided(dst: &mut [f32], dst_row_stride: usize, a: View, b: View, accumulate: bool) {
    let (m, n) = (a.rows, b.cols);
    assert!(n <= dst_row_stride, "matmul into rows of {dst_row_stride} values, {n} wide");
    if m == 0 || n == 0 {
        return;
    }
    assert!((m - 1) * dst_row_stride + n <= dst.len(), "matmul destination outside its slice");
    // SAFETY: the destination block (m rows of n values, `dst_row_stride` apart) was checked to
    // lie inside `dst`, which is borrowed mutably, so it aliases neither view.
    unsafe { gemm_into(dst.as_mut_ptr(), dst_row_stride, a, b, accumulate) }
}

/// `a · b` as a new row-major `a.rows × b.cols` matrix, written without first zeroing it.
pub fn product(a: View, b: View) -> Vec<f32> {
    let len = a.rows * b.cols;
    let mut out = Vec::with_capacity(len);
    // SAFETY: `out` has room for the `a.rows × b.cols` block with rows `b.cols` apart and aliases
    // nothing. gemm_into writes every element of that block when not accumulating, so all
    // `len` values are initialised before the length is set.
    unsafe {
        gemm_into(out.as_mut_ptr(), b.cols, a, b, false);
        out.set_len(len);
    }
    out
}

/// `dst ← a · b`, or `dst ← dst + a · b` with `accumulate`, for a destination block of
/// `a.rows × b.cols` values whose rows are `dst_row_stride` apart.
///
/// # Safety
/// `dst` must be valid for writes (and, with `accumulate`, reads of initialised values) over that
/// block, and must not overlap either view. Without `accumulate` every element of the block is written.
///
/// # Panics
/// If the shapes disagree or a view reaches outside its slice: a caller's bug, never data.
unsafe fn gemm_into(dst: *mut f32, dst_row_stride: usize, a: View, b: View, accumulate: bool) {
    let (m, k, n) = (a.rows, a.cols, b.cols);
    assert!(b.rows == k, "matmul of {m}×{k} by {}×{n}", b.rows);
    assert!(a.in_bounds() && b.in_bounds(), "matmul view outside its slice");
    if m == 0 || n == 0 {
        return;
    }
    if k == 0 {
        if !accumulate {
            for i in 0..m {
                // SAFETY: row i of the block lies inside `dst` (the caller's contract).
                unsafe { std::ptr::write_bytes(dst.add(i * dst_row_stride), 0, n) };
            }
        }
        return;
    }
    // SAFETY: both views were checked above to address only elements inside their own slices,
    // and the strides fit in isize because they index existing slices; the destination block is
    // the caller's contract. gemm reads `dst` only when `read_dst` is set, writes every element
    // of the block, and runs on this thread (Parallelism::None), so no pointer outlives the call.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            dst,
            1,
            dst_row_stride as isize,
            accumulate,
            a.data.as_ptr(),
            a.col_stride as isize,
            a.row_stride as isize,
            b.data.as_ptr(),
            b.col_stride as isize,
            b.row_stride as isize,
            1.0,
            1.0,
            false,
            false,
            false,
            gemm::Parallelism::None,
        )
    }
}

/// `Σ a[i]·b[i]`, eight partial sums at a time so that the compiler can keep them in vector lanes.
#[inline(always)]
pub fn dot(a: &[f32], b: &[f32]) -> f32 {
    debug_assert_eq!(a.len(), b.len());
    let mut lanes = [0f32; 8];
    let (a8, b8) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f32 = a8.remainder().iter().zip(b8.remainder()).map(|(x, y)| x * y).sum();
    for (x, y) in a8.zip(b8) {
        for l in 0..8 {
            lanes[l] += x[l] * y[l];
        }
    }
    lanes.iter().sum::<f32>() + tail
}

/// `y += alpha · x`.
#[inline(always)]
pub fn axpy(y: &mut [f32], alpha: f32, x: &[f32]) {
    debug_assert_eq!(x.len(), y.len());
    for (y, x) in y.iter_mut().zip(x) {
        *y += alpha * x;
    }
}

/// Adds `row` to each `row.len()`-long row of the row-major matrix `m` (a bias).
#[inline(always)]
pub fn add_to_rows(m: &mut [f32], row: &[f32]) {
    for r in m.chunks_exact_mut(row.len()) {
        for (v, b) in r.iter_mut().zip(row) {
            *v += b;
        }
    }
}

/// Adds each row of the row-major `rows × sums.len()` matrix `m` into `sums` (a bias's gradient).
#[inline(always)]
pub fn add_column_sums(sums: &mut [f32], m: &[f32]) {
    for row in m.chunks_exact(sums.len()) {
        for (s, v) in sums.iter_mut().zip(row) {
            *s += v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Rng;

    fn triple_loop(a: View, b: View) -> Vec<f64> {
        let at = |v: &View, i: usize, j: usize| v.data[i * v.row_stride + j * v.col_stride] as f64;
        let mut c = vec![0f64; a.rows * b.cols];
        for i in 0..a.rows {
            for j in 0..b.cols {
                c[i * b.cols + j] = (0..a.cols).map(|p| at(&a, i, p) * at(&b, p, j)).sum();
            }
        }
        c
    }

    #[test]
    fn products_of_strided_views_match_a_triple_loop() {
        let mut rng = Rng::new(3);
        for (m, k, n) in [(1, 1, 1), (5, 64, 5), (7, 20, 192), (33, 3, 17), (4, 0, 3), (0, 4, 3)] {
            let a: Vec<f32> = (0..m * k).map(|_| rng.normal()).collect();
            let bt: Vec<f32> = (0..n * k).map(|_| rng.normal()).collect();
            // a · btᵀ, the product every linear layer makes; then accumulated once more.
            let (va, vb) = (View::rows(&a, m, k), View::rows(&bt, n, k).t());
            let mut c = vec![1f32; m * n];
            matmul(&mut c, va, vb, false);
            let want = triple_loop(va, vb);
            assert!(c.iter().zip(&want).all(|(x, y)| (*x as f64 - y).abs() <= 1e-4 * (1.0 + y.abs())), "{m}×{k}×{n}");
            assert_eq!(product(va, vb), c, "{m}×{k}×{n} as a new matrix");
            matmul(&mut c, va, vb, true);
            assert!(c.iter().zip(&want).all(|(x, y)| (*x as f64 - 2.0 * y).abs() <= 2e-4 * (1.0 + y.abs())), "{m}×{k}×{n} accumulated");
        }
    }

    #[test]
    fn a_block_of_a_wider_matrix_is_written_and_nothing_beside_it() {
        let a = [1f32, 2.0, 3.0, 4.0];
        let mut dst = vec![9f32; 2 * 5];
        matmul_strided(&mut dst[1..], 5, View::rows(&a, 2, 2), View::rows(&a, 2, 2), false);
        assert_eq!(dst, [9.0, 7.0, 10.0, 9.0, 9.0, 9.0, 15.0, 22.0, 9.0, 9.0]);
    }

    #[test]
    #[should_panic(expected = "outside its slice")]
    fn a_view_past_its_slice_is_refused() {
        let a = [0f32; 5];
        let mut c = [0f32; 4];
        matmul(&mut c, View::rows(&a, 2, 3), View::rows(&a, 3, 2), false);
    }

    #[test]
    fn dot_axpy_and_column_sums() {
        let a: Vec<f32> = (0..19).map(|i| i as f32).collect();
        assert_eq!(dot(&a, &a), (0..19).map(|i| (i * i) as f32).sum::<f32>());
        let mut y = vec![1f32; 19];
        axpy(&mut y, 2.0, &a);
        assert_eq!(y[18], 37.0);
        let mut sums = vec![0f32; 2];
        add_column_sums(&mut sums, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(sums, [9.0, 12.0]);
    }
}
