//! Attention as ONNX nodes, in the two layouts of the two stages.
//!
//! The spatial stage has many short sequences (iCub: 5 tokens, one per patch and the CLS token),
//! which batched matrix products would run one tiny product at a time. There the rows are laid
//! out token by token, and every query meets every key through one gather: the keys rolled by
//! `r` positions line up with the queries, so a whole stage's scores are one elementwise product
//! and one sum, feature-major so that each sum runs over whole contiguous blocks. The temporal
//! stage has one long sequence per window and uses two batched products.
//!
//! Each head's four matrices are multiplied out where that is cheaper (see [`Heads::new`]): the
//! keys and values are then the plain norm `x̂` itself; the mixed `x̂` goes through one output
//! product. In the last layer of a stage only the CLS token is read, so only its query is asked.

use pvt3_spec::baked::{BakedAttention, Dense, Norm};

use pvt3_format::onnx::{int, ints, Op};

use crate::graph::Graph;
use crate::layers::{absorb_norm, centred, linear, linear_columns, residual_linear};

/// How a stage lays out its rows `[rows, dim]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Layout {
    /// `[tokens, sequences, dim]`: the spatial stage.
    TokenMajor,
    /// `[sequences, tokens, dim]`: the temporal stage.
    SequenceMajor,
}

/// The rows of a stage: their layout and the tokens per sequence.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rows {
    pub layout: Layout,
    pub tokens: usize,
    /// A tensor `[1, 1, 1, tokens]` every score adds by its key (sequence-major rows only).
    pub key_bias: Option<&'static str>,
}

impl Rows {
    /// The first (CLS) token of every sequence, `[sequences, dim]`.
    pub(crate) fn first(&self, g: &mut Graph, x: &str, dim: usize) -> String {
        let (shape, axis) = match self.layout {
            Layout::TokenMajor => (vec![self.tokens as i64, -1, dim as i64], 0),
            Layout::SequenceMajor => (vec![-1, self.tokens as i64, dim as i64], 1),
        };
        let shape = g.i64s("sequences", &[3], shape);
        let x = g.op(Op::Reshape, &[x, &shape]);
        let zero = g.i64s("first", &[], vec![0]);
        g.node(Op::Gather, &[&x, &zero], vec![int("axis", axis)], None)
    }
}

/// One attention's weights as the graph applies them to the plain norm `x̂` of the stream.
pub(crate) struct Heads {
    heads: usize,
    /// `x̂ ↦` every head's queries, head by head, `width` each; the scale is inside.
    queries: Dense,
    /// `x̂ ↦` keys and values, head by head; `None` when the heads are folded and both are `x̂`.
    projections: Option<(Dense, Dense)>,
    /// Every head's mixed values `↦` the stream, centred.
    out: Dense,
    /// The largest |score| the weights allow.
    bound: f64,
}

/// The largest |y| of a head's rows `y = A x̂ + c` of `l` (`width` rows from `head · width`), for
/// any plain norm `x̂` (|x̂|² ≤ dim): ‖A‖_F √dim + |c|. A score is the product of a query and a
/// key, so the product of their reaches bounds it.
fn reach(l: &Dense, head: usize, width: usize) -> f64 {
    let rows = head * width..(head + 1) * width;
    let a: f64 = l.weight[rows.start * l.cols..rows.end * l.cols].iter().map(|v| (*v as f64).powi(2)).sum::<f64>().sqrt();
    let c: f64 = l.bias.as_ref().map_or(0.0, |b| b[rows].iter().map(|v| (*v as f64).powi(2)).sum::<f64>().sqrt());
    a * (l.cols as f64).sqrt() + c
}

/// Scores up to this size in magnitude need no max-subtraction: `exp(±60)` is far from f32's
/// overflow (`exp(88.7)`) and from underflowing every entry of a row.
const EXP_SAFE: f64 = 60.0;

impl Heads {
    /// The attention `a` after the layer norm `n`, its affine part absorbed into the weights.
    ///
    /// Folded where that needs fewer multiply-adds per token (`2 · heads · dim²` + scores and
    /// mixing at width `dim`, against `4 · dim · inner` + scores and mixing at width `head_dim`;
    /// the iCub model needs 3–6× fewer): with `y = γ ∘ x̂ + β`, the scores are
    /// `(y Wqᵀ)(y Wkᵀ)ᵀ = (y M) yᵀ` with `M = scale · Wqᵀ Wk`; the keys' `β` adds the same amount
    /// to every score of a row, which the softmax ignores, so the keys are `x̂` and `Γ` moves into
    /// `M`. The values: `P (y Wvᵀ) Woᵀ = (P x̂) Γ U + β U` with `U = Wvᵀ Woᵀ`, since every row of
    /// `P` sums to one. Both `M` and `U` are `dim × dim` per head.
    pub(crate) fn new(a: &BakedAttention, n: &Norm, tokens: usize) -> Self {
        let (d, h, hd) = (a.out.rows, a.heads, a.head_dim);
        let inner = h * hd;
        let biased = [&a.q, &a.k, &a.v].iter().any(|l| l.bias.is_some());
        let folds = !biased && hd > 0 && 2 * h * d * d + 2 * tokens * h * d < 4 * d * inner + 2 * tokens * inner;
        if !folds {
            let q_scaled = Dense { weight: a.q.weight.iter().map(|w| w * a.scale).collect(), ..a.q.clone() };
            let (queries, keys) = (absorb_norm(&q_scaled, n), absorb_norm(&a.k, n));
            let bound = (0..h).map(|head| reach(&queries, head, hd) * reach(&keys, head, hd)).fold(0.0, f64::max);
            return Self { heads: h, queries, projections: Some((keys, absorb_norm(&a.v, n))), out: centred(&a.out), bound };
        }
        let (gamma, beta) = (|i: usize| n.weight[i] as f64, |i: usize| n.bias[i] as f64);
        let (mut q, mut qb) = (vec![0f64; h * d * d], vec![0f64; h * d]);
        let (mut o, mut ob) = (vec![0f64; d * h * d], a.out.bias.as_ref().map_or(vec![0f64; d], |b| b.iter().map(|v| *v as f64).collect()));
        for head in 0..h {
            for i in 0..d {
                for j in 0..d {
                    let (mut m, mut u) = (0f64, 0f64);
                    for c in head * hd..(head + 1) * hd {
                        m += a.q.weight[c * d + i] as f64 * a.k.weight[c * d + j] as f64;
                        u += a.v.weight[c * d + i] as f64 * a.out.weight[j * inner + c] as f64;
                    }
                    let m = m * a.scale as f64 * gamma(j);
                    // Query row `head·d + j` reads feature i; output row j reads head feature i.
                    q[(head * d + j) * d + i] = gamma(i) * m;
                    qb[head * d + j] += beta(i) * m;
                    o[j * h * d + head * d + i] = gamma(i) * u;
                    ob[j] += beta(i) * u;
                }
            }
        }
        let f32s = |v: Vec<f64>| v.into_iter().map(|x| x as f32).collect::<Vec<_>>();
        let queries = Dense { rows: h * d, cols: d, weight: f32s(q), bias: Some(f32s(qb)) };
        // The keys are x̂ itself, |x̂| ≤ √dim.
        let bound = (0..h).map(|head| reach(&queries, head, d) * (d as f64).sqrt()).fold(0.0, f64::max);
        Self {
            heads: h,
            queries,
            projections: None,
            out: centred(&Dense { rows: d, cols: h * d, weight: f32s(o), bias: Some(f32s(ob)) }),
            bound,
        }
    }

    /// Whether the softmax can skip subtracting its row maximum.
    fn bounded(&self) -> bool {
        self.bound < EXP_SAFE
    }

    /// Width of a head's queries and keys, and of its values.
    fn width(&self) -> usize {
        self.queries.rows / self.heads
    }

    fn value_width(&self) -> usize {
        self.out.cols / self.heads
    }
}

/// The stream `x` updated by attention over `xhat`, its plain norm, both laid out as `rows`:
/// `[rows, dim]`; with `cls_only`, the first token of each sequence alone, `[sequences, dim]`.
pub(crate) fn attention(g: &mut Graph, x: &str, xhat: &str, rows: Rows, cls_only: bool, h: &Heads, hint: &str) -> String {
    let mixed = match rows.layout {
        Layout::TokenMajor => {
            debug_assert!(rows.key_bias.is_none(), "token-major attention takes no key bias");
            rolled(g, xhat, rows, cls_only, h, hint)
        }
        Layout::SequenceMajor => batched(g, xhat, rows, cls_only, h, hint),
    };
    let x = if cls_only { rows.first(g, x, h.out.rows) } else { x.to_string() };
    residual_linear(g, &x, &mixed, &h.out, &format!("{hint}_out"))
}

/// `[1 or heads, …]` repeated to `[heads, …]` along axis 0.
fn per_head(g: &mut Graph, x: &str, shared: bool, heads: usize) -> String {
    if !shared || heads == 1 {
        return x.to_string();
    }
    let idx = g.i64s("heads", &[heads], vec![0; heads]);
    g.node(Op::Gather, &[x, &idx], vec![int("axis", 0)], None)
}

/// Token-major attention; the mixed values, `[queries, heads · value width]`.
///
/// Feature-major, every tensor is `[heads, features, key offset r, query i, sequence]`: key
/// `(i + r) mod tokens` meets query `i`. Gathers line the tokens up and repeat the scores over
/// the features, so every product is elementwise on equal shapes and every sum runs over an outer
/// axis.
fn rolled(g: &mut Graph, xhat: &str, rows: Rows, cls_only: bool, h: &Heads, hint: &str) -> String {
    let (t, heads, e, ev, d) = (rows.tokens, h.heads, h.width(), h.value_width(), h.queries.cols);
    let nq = if cls_only { 1 } else { t };
    let xf = g.node(Op::Transpose, &[xhat], vec![ints("perm", &[1, 0])], None);
    let shape = |g: &mut Graph, x: &str, dims: Vec<i64>| {
        let s = g.i64s("shape", &[dims.len()], dims);
        g.op(Op::Reshape, &[x, &s])
    };
    let queries_in = if cls_only {
        let x3 = shape(g, &xf, vec![d as i64, t as i64, -1]);
        let zero = g.i64s("first", &[], vec![0]);
        g.node(Op::Gather, &[&x3, &zero], vec![int("axis", 1)], None)
    } else {
        xf.clone()
    };
    let q = linear_columns(g, &queries_in, &h.queries, &format!("{hint}_queries"));
    let q = shape(g, &q, vec![heads as i64, e as i64, nq as i64, -1]);
    let same = g.i64s("query_of", &[t, nq], (0..t).flat_map(|_| 0..nq as i64).collect());
    let roll = g.i64s("key_of", &[t, nq], (0..t).flat_map(|r| (0..nq).map(move |i| ((i + r) % t) as i64)).collect());
    let q = g.node(Op::Gather, &[&q, &same], vec![int("axis", 2)], None);
    let projected = |g: &mut Graph, l: Option<&Dense>, width: usize, tag: &str| match l {
        Some(l) => {
            let y = linear_columns(g, &xf, l, &format!("{hint}_{tag}"));
            shape(g, &y, vec![heads as i64, width as i64, t as i64, -1])
        }
        None => shape(g, &xf, vec![1, d as i64, t as i64, -1]),
    };
    let shared = h.projections.is_none();
    let keys = projected(g, h.projections.as_ref().map(|p| &p.0), e, "keys");
    let keys = g.node(Op::Gather, &[&keys, &roll], vec![int("axis", 2)], None);
    let keys = per_head(g, &keys, shared, heads);
    let values = match &h.projections {
        None => keys.clone(),
        Some((_, v)) => {
            let v = projected(g, Some(v), ev, "values");
            g.node(Op::Gather, &[&v, &roll], vec![int("axis", 2)], None)
        }
    };
    let prod = g.op(Op::Mul, &[&q, &keys]);
    let features = g.i64s("features", &[1], vec![1]);
    let scores = g.node(Op::ReduceSum, &[&prod, &features], vec![int("keepdims", 1)], None);
    let scores = if h.bounded() {
        scores
    } else {
        let max = max_over(g, &scores, t, 2);
        g.op(Op::Sub, &[&scores, &max])
    };
    let weights = g.op(Op::Exp, &[&scores]);
    let spread = g.i64s("spread", &[ev], vec![0; ev]);
    let repeated = g.node(Op::Gather, &[&weights, &spread], vec![int("axis", 1)], None);
    let weighted = g.op(Op::Mul, &[&repeated, &values]);
    let offsets = g.i64s("offsets", &[1], vec![2]);
    let mixed = g.node(Op::ReduceSum, &[&weighted, &offsets], vec![int("keepdims", 0)], None);
    let total = g.node(Op::ReduceSum, &[&weights, &offsets], vec![int("keepdims", 0)], None);
    let total = g.node(Op::Gather, &[&total, &spread], vec![int("axis", 1)], None);
    let mixed = g.op(Op::Div, &[&mixed, &total]);
    let mixed = shape(g, &mixed, vec![(heads * ev) as i64, -1]);
    g.node(Op::Transpose, &[&mixed], vec![ints("perm", &[1, 0])], None)
}

/// Sequence-major attention with two batched products; the mixed values, `[queries, heads · value width]`.
fn batched(g: &mut Graph, xhat: &str, rows: Rows, cls_only: bool, h: &Heads, hint: &str) -> String {
    let (t, heads, e, ev, d) = (rows.tokens, h.heads, h.width(), h.value_width(), h.queries.cols);
    let nq = if cls_only { 1 } else { t };
    let queries_in = if cls_only { rows.first(g, xhat, d) } else { xhat.to_string() };
    let split = |g: &mut Graph, x: &str, len: usize, width: usize, perm: &[i64]| {
        let s = g.i64s("split_heads", &[4], vec![-1, len as i64, heads as i64, width as i64]);
        let r = g.op(Op::Reshape, &[x, &s]);
        g.node(Op::Transpose, &[&r], vec![ints("perm", perm)], None)
    };
    let q = linear(g, &queries_in, &h.queries, &format!("{hint}_queries"));
    let q = split(g, &q, nq, e, &[0, 2, 1, 3]);
    let (keys_t, values) = match &h.projections {
        None => {
            let s = g.i64s("per_sequence", &[4], vec![-1, 1, t as i64, d as i64]);
            let x4 = g.op(Op::Reshape, &[xhat, &s]);
            (g.node(Op::Transpose, &[&x4], vec![ints("perm", &[0, 1, 3, 2])], None), x4)
        }
        Some((k, v)) => {
            let k = linear(g, xhat, k, &format!("{hint}_keys"));
            let v = linear(g, xhat, v, &format!("{hint}_values"));
            (split(g, &k, t, e, &[0, 2, 3, 1]), split(g, &v, t, ev, &[0, 2, 1, 3]))
        }
    };
    let scores = g.op(Op::MatMul, &[&q, &keys_t]);
    let scores = match rows.key_bias {
        Some(bias) => g.op(Op::Add, &[&scores, bias]),
        None => scores,
    };
    let (weights, total) = softmax_terms(g, &scores, t, h.bounded());
    let mixed = g.op(Op::MatMul, &[&weights, &values]);
    // Normalised after mixing: a division of `[queries, width]` rather than `[queries, keys]`.
    let mixed = g.op(Op::Div, &[&mixed, &total]);
    let back = g.node(Op::Transpose, &[&mixed], vec![ints("perm", &[0, 2, 1, 3])], None);
    let flat = g.i64s("merge_heads", &[2], vec![-1, (heads * ev) as i64]);
    g.op(Op::Reshape, &[&back, &flat])
}

/// A softmax over the last axis (rows of `len`) as its two terms, the exponentials and their row
/// sums, from elementwise ops and a sum. tract's Softmax op walks the rows one by one, which
/// costs more than the products on short rows; these ops vectorise over the whole tensor.
/// `bounded`: no score can overflow `exp`, so the row maximum is not subtracted.
fn softmax_terms(g: &mut Graph, x: &str, len: usize, bounded: bool) -> (String, String) {
    let axis = g.i64s("last_axis", &[1], vec![-1]);
    let shifted = if bounded {
        x.to_string()
    } else {
        let max = max_over(g, x, len, -1);
        g.op(Op::Sub, &[x, &max])
    };
    let e = g.op(Op::Exp, &[&shifted]);
    let sum = g.node(Op::ReduceSum, &[&e, &axis], vec![int("keepdims", 1)], None);
    (e, sum)
}

/// The maximum over `axis` (of length `len`), kept as a unit axis, by halving: the larger of two
/// overlapping halves, until one entry is left. tract's ReduceMax walks short rows one by one;
/// Slice and Max vectorise over the whole tensor.
fn max_over(g: &mut Graph, x: &str, len: usize, axis: i64) -> String {
    let axes = g.i64s("axis", &[1], vec![axis]);
    let (mut max, mut n) = (x.to_string(), len as i64);
    while n > 1 {
        let half = (n + 1) / 2;
        let (zero, h, rest, end) = (
            g.i64s("start", &[1], vec![0]),
            g.i64s("end", &[1], vec![half]),
            g.i64s("start", &[1], vec![n - half]),
            g.i64s("end", &[1], vec![n]),
        );
        let low = g.op(Op::Slice, &[&max, &zero, &h, &axes]);
        let high = g.op(Op::Slice, &[&max, &rest, &end, &axes]);
        max = g.op(Op::Max, &[&low, &high]);
        n = half;
    }
    max
}
