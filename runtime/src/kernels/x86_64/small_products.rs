//! [`SmallProduct`]: a matrix product for short sums (k of a few dozen), which the tuner puts in
//! place of tract's where it measures faster. tract calls its kernel once per tile of outputs,
//! and each call has a fixed cost (about 130 ns here, against 2–3 ns per step of k; part of it is
//! saving and setting the float control register), so at k = 20 most of a product's time is that
//! cost, after packing the input. This product reads its inputs where they lie and computes
//! register blocks of outputs within one call (docs/benchmarks.md, step 17), with AVX-512 or with
//! AVX2 and FMA. The module exists on x86-64 only (`kernels/mod.rs`); elsewhere tract's kernels run.

use tract_core::internal::*;
use tract_core::tract_linalg::BinOp;

mod kernel;
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
        match self {
            Isa::Avx512 => is_x86_feature_detected!("avx512f"),
            Isa::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
        }
    }

    /// Every set the kernel is compiled for, widest first.
    pub(crate) const ALL: [Isa; 2] = [Isa::Avx512, Isa::Avx2];
}

/// The instruction sets this machine can run [`SmallProduct`] with, widest first. The
/// environment variable `PVT3_SMALL_PRODUCTS` narrows them when set and not empty: `avx512` or
/// `avx2` for that set alone, anything else (`none`) for none, so that tract's kernels run every
/// product.
pub(crate) fn instruction_sets() -> Vec<Isa> {
    let only = std::env::var("PVT3_SMALL_PRODUCTS").ok().filter(|v| !v.is_empty());
    Isa::ALL.into_iter().filter(|isa| isa.present() && only.as_deref().is_none_or(|o| o == isa.name())).collect()
}

/// The instruction sets a test must cover: those named in `PVT3_TEST_ISAS` (comma-separated),
/// or every set the kernel is compiled for. Panics, failing the test, when the machine lacks one
/// of them: a kernel test never passes by checking nothing. On a machine without AVX-512, run
/// the tests with `PVT3_TEST_ISAS=avx2` to say so.
#[cfg(test)]
pub(crate) fn covered() -> Vec<Isa> {
    let asked = std::env::var("PVT3_TEST_ISAS").unwrap_or_else(|_| "avx512,avx2".into());
    let sets: Vec<Isa> = asked
        .split(',')
        .map(|name| Isa::ALL.into_iter().find(|i| i.name() == name.trim()).unwrap_or_else(|| panic!("PVT3_TEST_ISAS: no set `{name}`")))
        .collect();
    for isa in &sets {
        assert!(isa.present(), "this machine lacks {isa:?}, which the tests were asked to cover (PVT3_TEST_ISAS={asked})");
    }
    sets
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

/// How an epilogue combines a product's value c with its vector's (or scalar's) value v.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Combine {
    /// c + v
    Add,
    /// c · v
    Mul,
    /// v − c: tract's `BinOp::Sub` in a fused product
    SubtractedFrom,
    /// c − v: tract's `BinOp::SubF`
    Subtract,
}

impl Combine {
    pub(crate) fn from_tract(op: BinOp) -> Option<Self> {
        match op {
            BinOp::Add => Some(Combine::Add),
            BinOp::Mul => Some(Combine::Mul),
            BinOp::Sub => Some(Combine::SubtractedFrom),
            BinOp::SubF => Some(Combine::Subtract),
            BinOp::Min | BinOp::Max => None,
        }
    }

    /// `c` combined with `v`, one value.
    pub(crate) fn apply(self, c: f32, v: f32) -> f32 {
        match self {
            Combine::Add => c + v,
            Combine::Mul => c * v,
            Combine::SubtractedFrom => v - c,
            Combine::Subtract => c - v,
        }
    }
}

/// `C = A B`, then the epilogues in order and the scalar, stored into C of shape `c_shape` with
/// its m and n axes at `c_m_axis` and `c_n_axis` (the others unit axes; no n axis when n is 1).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct SmallProduct {
    pub m: usize,
    pub k: usize,
    pub n: usize,
    pub a: Source,
    pub b: Source,
    pub epilogues: Vec<Epilogue>,
    /// Node input holding one value that every value of C is combined with, after the
    /// epilogues (tract's `BinScalar`, as the last thing tract fused).
    pub scalar: Option<(usize, Combine)>,
    pub c_shape: TVec<usize>,
    pub c_m_axis: usize,
    pub c_n_axis: Option<usize>,
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
    /// How the kernel writes C, if it can: whether the vectors run along C's columns (n) or, with
    /// Cᵀ = Bᵀ Aᵀ, along its rows (m), whichever is contiguous; and the stride between the
    /// kernel's rows. `None` when neither is contiguous or C has other axes than unit ones.
    fn layout(&self) -> Option<(bool, isize)> {
        let strides = Tensor::natural_strides(&self.c_shape);
        let others_unit = self.c_shape.iter().enumerate().all(|(ax, d)| ax == self.c_m_axis || Some(ax) == self.c_n_axis || *d == 1);
        // Without an n axis C is one column: the kernel writes it as one row of m values.
        let n_stride = match self.c_n_axis {
            Some(ax) => strides[ax],
            None if self.n == 1 => 0,
            None => return None,
        };
        let (m_unit, n_unit) = (strides[self.c_m_axis] == 1, n_stride == 1);
        let along_n = n_unit && !(self.n == 1 && m_unit);
        (others_unit && (m_unit || n_unit)).then_some(if along_n { (true, strides[self.c_m_axis]) } else { (false, n_stride) })
    }

    /// Whether the kernel can write C (see [`Self::layout`]).
    pub(crate) fn supported(&self) -> bool {
        self.layout().is_some()
    }

    /// The product of `inputs` (the node's inputs).
    pub(crate) fn run(&self, inputs: &[TValue]) -> TractResult<Tensor> {
        let layout = self.layout().filter(|_| self.isa.present());
        let Some((n_contiguous, c_row)) = layout else { bail!("SmallProduct {:?} cannot run here", self.isa) };
        let a = self.matrix(&self.a, inputs, self.m)?;
        let b = self.matrix(&self.b, inputs, self.n)?;
        let vector = |e: &Epilogue| -> TractResult<*const f32> {
            let t = &inputs[e.input];
            ensure!(t.len() == if e.per_row { self.m } else { self.n } && t.datum_type() == f32::datum_type());
            t.as_ptr::<f32>()
        };
        let mut ops = TVec::new();
        for e in &self.epilogues {
            // Along the kernel's rows (scalars) or along its vectors.
            ops.push((e.op, e.per_row == n_contiguous, vector(e)?));
        }
        // SAFETY: f32 has no invalid bit patterns, and the kernel writes every value of C before
        // it is returned (each register block stores all its rows and, masked, its columns).
        let mut c = unsafe { Tensor::uninitialized::<f32>(&self.c_shape)? };
        let mut scratch = Vec::new();
        // The kernel's vectors run along C's contiguous axis: C = A B, or Cᵀ = Bᵀ Aᵀ.
        let (p, q, l, r) = if n_contiguous {
            (self.m, self.n, a, rows_contiguous(b, self.k, self.n, &mut scratch))
        } else {
            (self.n, self.m, b, rows_contiguous(a, self.k, self.m, &mut scratch))
        };
        let out = c.as_ptr_mut::<f32>()?;
        // SAFETY: `self.isa` is present (checked above). `l` and `r` cover the `[p, k]` and
        // `[k, q]` matrices: `matrix` checked each input's shape against m, k and n and took its
        // own strides, and `rows_contiguous` copied any strided right-hand side. `out` is C,
        // `c_shape` holds m × n values (other axes are unit axes, `layout`) with rows `c_row`
        // apart, and every epilogue vector was checked to hold m or n values.
        unsafe { kernel::multiply(self.isa, p, q, self.k, l, r, out, c_row, &ops) };
        if let Some((input, op)) = self.scalar {
            let t = &inputs[input];
            ensure!(t.len() == 1 && t.datum_type() == f32::datum_type(), "SmallProduct scalar input {input} has shape {:?}", t.shape());
            let s = t.to_plain_array_view::<f32>()?.iter().copied().next().unwrap_or_default();
            let mut c = c.to_plain_array_view_mut::<f32>()?;
            c.iter_mut().for_each(|v| *v = op.apply(*v, s));
        }
        Ok(c)
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
        // SAFETY: `m` describes a `[mn, k]` matrix its pointer covers (`SmallProduct::matrix`).
        scratch.extend((0..mn as isize).map(|i| unsafe { *m.ptr.offset(i * m.mn + j * m.k) }));
    }
    Matrix { ptr: scratch.as_ptr(), mn: 1, k: mn as isize }
}

impl Op for SmallProduct {
    fn name(&self) -> StaticName {
        "SmallProduct".into()
    }

    fn info(&self) -> TractResult<Vec<String>> {
        Ok(vec![format!(
            "m:{} k:{} n:{}, {:?}, epilogues {:?}, scalar {:?}, c {:?}",
            self.m, self.k, self.n, self.isa, self.epilogues, self.scalar, self.c_shape
        )])
    }

    op_as_typed_op!();
}

impl EvalOp for SmallProduct {
    op_out_of_plan!();

    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        Ok(tvec!(self.run(&inputs)?.into_tvalue()))
    }
}

impl TypedOp for SmallProduct {
    fn output_facts(&self, _inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        Ok(tvec!(f32::fact(&*self.c_shape)))
    }

    as_op!();
}
