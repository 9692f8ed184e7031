//! [`SmallProduct`]: a matrix product for short sums (k of a few dozen), which the tuner puts in
//! place of tract's where it measures faster. tract calls its kernel once per tile of outputs,
//! and each call has a fixed cost (about 130 ns here, against 2–3 ns per step of k; part of it is
//! saving and setting the float control register), so at k = 20 most of a product's time is that
//! cost, after packing the input. This product reads its inputs where they lie and computes
//! register blocks of outputs within one call (docs/benchmarks.md, step 17): on x86-64 with
//! AVX-512 or with AVX2 and FMA. Elsewhere tract's kernels run.

use tract_onnx::prelude::*;
use tract_onnx::tract_core::internal::*;
use tract_onnx::tract_core::tract_linalg::BinOp;

#[cfg(target_arch = "x86_64")]
mod kernel;
#[cfg(target_arch = "x86_64")]
mod lanes;

/// The vector instructions a [`SmallProduct`] runs with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Isa {
    /// AVX-512F: 16 lanes, register blocks of 6 rows by 4 vectors.
    Avx512,
    /// AVX2 and FMA: 8 lanes, register blocks of 4 rows by 3 vectors.
    Avx2,
}

impl Isa {
    fn name(self) -> &'static str {
        match self {
            Isa::Avx512 => "avx512",
            Isa::Avx2 => "avx2",
        }
    }

    /// Whether this machine has these instructions.
    fn present(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        return match self {
            Isa::Avx512 => is_x86_feature_detected!("avx512f"),
            Isa::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
        };
        #[cfg(not(target_arch = "x86_64"))]
        false
    }
}

/// The instruction sets this machine can run [`SmallProduct`] with (none off x86-64). The
/// environment variable `PVT3_SMALL_PRODUCTS` narrows them when set (not empty): `avx512` or `avx2` for that
/// set alone, anything else (`none`) for none, so that tract's kernels run every product.
pub(crate) fn instruction_sets() -> Vec<Isa> {
    let only = std::env::var("PVT3_SMALL_PRODUCTS").ok().filter(|v| !v.is_empty());
    [Isa::Avx512, Isa::Avx2].into_iter().filter(|isa| isa.present() && only.as_deref().is_none_or(|o| o == isa.name())).collect()
}

/// Where one operand of a product comes from.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Source {
    /// Node input `input`, its k and mn axes (every other axis is a unit axis).
    Input { input: usize, k_axis: usize, mn_axis: usize },
    /// A constant, `[k, mn]` row by row.
    Const(Arc<Tensor>),
}

/// A per-row or per-column operation after the sums, by node input `input` (m or n values).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct Epilogue {
    pub input: usize,
    pub op: Combine,
    /// Along the rows of C (one value per row, m values), or along its columns (n values).
    pub per_row: bool,
}

/// How an epilogue combines a product with its vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Combine {
    Add,
    Mul,
}

impl Combine {
    pub(crate) fn from_tract(op: BinOp) -> Option<Self> {
        match op {
            BinOp::Add => Some(Combine::Add),
            BinOp::Mul => Some(Combine::Mul),
            _ => None,
        }
    }
}

/// `C = A B`, then the epilogues in order, stored into C of shape `c_shape` with its m and n
/// axes at `c_m_axis` and `c_n_axis` (the others unit axes).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct SmallProduct {
    pub m: usize,
    pub k: usize,
    pub n: usize,
    pub a: Source,
    pub b: Source,
    pub epilogues: Vec<Epilogue>,
    pub c_shape: TVec<usize>,
    pub c_m_axis: usize,
    pub c_n_axis: usize,
    pub isa: Isa,
}

/// An operand as the kernel reads it: entry (i, j) of a `[mn, k]` matrix at `ptr + i·mn + j·k`.
#[derive(Clone, Copy)]
pub(crate) struct Matrix {
    ptr: *const f32,
    mn: isize,
    k: isize,
}

impl SmallProduct {
    /// Whether C's columns (n) are contiguous; otherwise its rows (m) are, and the kernel computes
    /// Cᵀ = Bᵀ Aᵀ so that its vectors still run along contiguous outputs.
    fn n_contiguous(&self) -> bool {
        let strides = Tensor::natural_strides(&self.c_shape);
        if self.n == 1 && strides[self.c_m_axis] == 1 {
            return false;
        }
        strides[self.c_n_axis] == 1
    }

    /// Checks what the kernel relies on: C's vectors run along a contiguous axis.
    pub(crate) fn supported(&self) -> bool {
        let strides = Tensor::natural_strides(&self.c_shape);
        let others_unit = self.c_shape.iter().enumerate().all(|(ax, d)| ax == self.c_m_axis || ax == self.c_n_axis || *d == 1);
        others_unit && (strides[self.c_n_axis] == 1 || strides[self.c_m_axis] == 1)
    }

    /// `source` as a `[mn, k]` matrix over `inputs`; a constant is `[k, mn]` row by row.
    fn matrix(&self, source: &Source, inputs: &[TValue], mn: usize) -> TractResult<Matrix> {
        Ok(match source {
            Source::Const(v) => {
                ensure!(v.datum_type() == f32::datum_type() && v.shape() == [self.k, mn]);
                Matrix { ptr: v.as_ptr::<f32>()?, mn: 1, k: mn as isize }
            }
            Source::Input { input, k_axis, mn_axis } => {
                let t = &inputs[*input];
                let shape = t.shape();
                ensure!(t.datum_type() == f32::datum_type() && t.len() == shape.iter().product::<usize>());
                ensure!(shape[*k_axis] == self.k && shape[*mn_axis] == mn, "SmallProduct input {input} has shape {shape:?}");
                let strides = t.strides();
                Matrix { ptr: t.as_ptr::<f32>()?, mn: strides[*mn_axis], k: strides[*k_axis] }
            }
        })
    }
}

/// `m` as `[k, mn]` rows with contiguous columns: itself if it already is, else a copy in `scratch`.
fn rows_contiguous(m: Matrix, k: usize, mn: usize, scratch: &mut Vec<f32>) -> Matrix {
    if m.mn == 1 {
        return m;
    }
    scratch.clear();
    for j in 0..k as isize {
        scratch.extend((0..mn as isize).map(|i| unsafe { *m.ptr.offset(i * m.mn + j * m.k) }));
    }
    Matrix { ptr: scratch.as_ptr(), mn: 1, k: mn as isize }
}

impl Op for SmallProduct {
    fn name(&self) -> StaticName {
        "SmallProduct".into()
    }

    fn info(&self) -> TractResult<Vec<String>> {
        Ok(vec![format!("m:{} k:{} n:{}, {:?}, epilogues {:?}, c {:?}", self.m, self.k, self.n, self.isa, self.epilogues, self.c_shape)])
    }

    op_as_typed_op!();
}

impl EvalOp for SmallProduct {
    op_out_of_plan!();

    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        Ok(tvec!(self.run(&inputs)?.into_tvalue()))
    }
}

impl SmallProduct {
    /// The product of `inputs` (the node's inputs).
    pub(crate) fn run(&self, inputs: &[TValue]) -> TractResult<Tensor> {
        ensure!(self.isa.present() && self.supported(), "SmallProduct {:?} cannot run here", self.isa);
        let a = self.matrix(&self.a, inputs, self.m)?;
        let b = self.matrix(&self.b, inputs, self.n)?;
        let vector = |e: &Epilogue| -> TractResult<*const f32> {
            let t = &inputs[e.input];
            ensure!(t.len() == if e.per_row { self.m } else { self.n } && t.datum_type() == f32::datum_type());
            t.as_ptr::<f32>()
        };
        let n_contiguous = self.n_contiguous();
        let mut ops = TVec::new();
        for e in &self.epilogues {
            // Along the kernel's rows (scalars) or along its vectors.
            ops.push((e.op, e.per_row == n_contiguous, vector(e)?));
        }
        let mut c = unsafe { Tensor::uninitialized::<f32>(&self.c_shape)? };
        let strides = Tensor::natural_strides(&self.c_shape);
        let mut scratch = Vec::new();
        // The kernel's vectors run along C's contiguous axis: C = A B, or Cᵀ = Bᵀ Aᵀ.
        let (p, q, l, r, c_row) = if n_contiguous {
            (self.m, self.n, a, rows_contiguous(b, self.k, self.n, &mut scratch), strides[self.c_m_axis])
        } else {
            (self.n, self.m, b, rows_contiguous(a, self.k, self.m, &mut scratch), strides[self.c_n_axis])
        };
        let out = c.as_ptr_mut::<f32>()?;
        #[cfg(target_arch = "x86_64")]
        unsafe {
            kernel::multiply(self.isa, p, q, self.k, l, r, out, c_row, &ops)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (p, q, l, r, out, c_row, ops);
        Ok(c)
    }
}

impl TypedOp for SmallProduct {
    fn output_facts(&self, _inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        Ok(tvec!(f32::fact(&*self.c_shape)))
    }

    as_op!();
}
