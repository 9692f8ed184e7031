//! The PVT³ graph, from raw frames to logits and probabilities.

use std::path::Path;

use prost::Message;
use pvt3_models::bake::{BakedAttention, BakedBlock, BakedPvt3, BakedTransformer, Dense, Norm};
use pvt3_models::normalization::Normalization;
use tract_onnx::pb::{
    tensor_proto::DataType, tensor_shape_proto::dimension::Value as Dim, tensor_shape_proto::Dimension, type_proto, GraphProto, ModelProto,
    OperatorSetIdProto, StringStringEntryProto, TensorShapeProto, TypeProto, ValueInfoProto,
};

use crate::graph::{float, int, ints, Graph};
use crate::{Error, Result};

/// The input: raw sensor frames `[batch, height, width, (channels,) frames]`.
pub const INPUT: &str = "frames";
pub const LOGITS: &str = "logits";
/// Seam of the spatial stage: the raw frames of each kept temporal token, `[tokens, tubelet, height, width, channels]`.
pub const TOKEN_FRAMES: &str = "token_frames";
/// Seam of the spatial stage: each token's place among the kept tokens, int64 `[tokens]`.
pub const TOKEN_INDEX: &str = "token_index";
/// Seam between the stages: the spatial encoding of each kept token, `[tokens, dim]`.
pub const TOKEN_ENCODINGS: &str = "token_encodings";
pub const PROBABILITIES: &str = "probabilities";

/// What the file says about itself, besides the graph.
#[derive(Clone, Debug)]
pub struct Metadata {
    pub classes: Vec<String>,
    /// Where the model came from (data set, fold, accuracy, pruning), as JSON.
    pub provenance: serde_json::Value,
}

fn linear(g: &mut Graph, x: &str, l: &Dense, hint: &str) -> String {
    let wt: Vec<f32> = (0..l.cols).flat_map(|c| (0..l.rows).map(move |r| (r, c))).map(|(r, c)| l.weight[r * l.cols + c]).collect();
    let w = g.f32s(&format!("{hint}_w"), &[l.cols, l.rows], wt);
    let y = g.op("MatMul", &[x, &w]);
    match &l.bias {
        Some(b) => {
            let b = g.f32s(&format!("{hint}_b"), &[l.rows], b.clone());
            g.op("Add", &[&y, &b])
        }
        None => y,
    }
}

fn layer_norm(g: &mut Graph, x: &str, n: &Norm, eps: f64, hint: &str) -> String {
    let d = n.weight.len();
    let w = g.f32s(&format!("{hint}_scale"), &[d], n.weight.clone());
    let b = g.f32s(&format!("{hint}_bias"), &[d], n.bias.clone());
    g.node("LayerNormalization", &[x, &w, &b], vec![int("axis", -1), float("epsilon", eps as f32)], None)
}

/// Layer norm without its scale and bias, for when the next matrix product absorbs them: tract
/// runs a broadcast scale and bias as two slow generic ops, a bias after a product for free.
fn plain_layer_norm(g: &mut Graph, x: &str, d: usize, eps: f64, hint: &str) -> String {
    layer_norm(g, x, &Norm { weight: vec![1.0; d], bias: vec![0.0; d] }, eps, hint)
}

/// `l` applied after the affine part of `n`: `W (γ ∘ x + β) + b = (W diag γ) x + (W β + b)`.
fn absorb_norm(l: &Dense, n: &Norm) -> Dense {
    let weight = (0..l.rows * l.cols).map(|i| l.weight[i] * n.weight[i % l.cols]).collect();
    let bias = (0..l.rows)
        .map(|r| {
            let shift: f64 = (0..l.cols).map(|c| l.weight[r * l.cols + c] as f64 * n.bias[c] as f64).sum();
            (l.bias.as_ref().map_or(0.0, |b| b[r] as f64) + shift) as f32
        })
        .collect();
    Dense { weight, bias: Some(bias), ..l.clone() }
}

fn gelu(g: &mut Graph, x: &str) -> String {
    let root2 = g.f32s("sqrt2", &[], vec![std::f32::consts::SQRT_2]);
    let one = g.f32s("one", &[], vec![1.0]);
    let half = g.f32s("half", &[], vec![0.5]);
    let scaled = g.op("Div", &[x, &root2]);
    let erf = g.op("Erf", &[&scaled]);
    let plus = g.op("Add", &[&erf, &one]);
    let prod = g.op("Mul", &[x, &plus]);
    g.op("Mul", &[&prod, &half])
}

/// Softmax over the last axis (rows of `len`) from elementwise ops and a sum. tract's Softmax op
/// walks the rows one by one, which cost more than all matrix products together on the spatial
/// stage's many 5-token rows; these ops vectorise over the whole tensor. `bound`, if known, is
/// the largest |x| possible: below [`EXP_SAFE`] the row maximum is not subtracted, since `exp`
/// can neither overflow nor underflow a whole row.
fn softmax_rows(g: &mut Graph, x: &str, len: usize, bound: Option<f64>) -> String {
    let axis = g.i64s("last_axis", &[1], vec![-1]);
    if bound.is_some_and(|b| b < EXP_SAFE) {
        let e = g.op("Exp", &[x]);
        let sum = g.node("ReduceSum", &[&e, &axis], vec![int("keepdims", 1)], None);
        return g.op("Div", &[&e, &sum]);
    }
    // The row maximum by halving: the larger of two overlapping halves, until one column is
    // left. tract's ReduceMax walks the rows one by one, which on these short rows cost more than
    // the attention's matrix products; Slice and Max vectorise over the whole tensor.
    let (mut max, mut n) = (x.to_string(), len as i64);
    while n > 1 {
        let half = (n + 1) / 2;
        let (zero, h, rest, end) = (
            g.i64s("start", &[1], vec![0]),
            g.i64s("end", &[1], vec![half]),
            g.i64s("start", &[1], vec![n - half]),
            g.i64s("end", &[1], vec![n]),
        );
        let low = g.op("Slice", &[&max, &zero, &h, &axis]);
        let high = g.op("Slice", &[&max, &rest, &end, &axis]);
        max = g.op("Max", &[&low, &high]);
        n = half;
    }
    let shifted = g.op("Sub", &[x, &max]);
    let e = g.op("Exp", &[&shifted]);
    let sum = g.node("ReduceSum", &[&e, &axis], vec![int("keepdims", 1)], None);
    g.op("Div", &[&e, &sum])
}

/// Attention over the layer norm `n` of `x` `[sequences × tokens, dim]`, `tokens` per sequence:
/// folded where that is cheaper, else with the projections as baked.
fn attention(g: &mut Graph, x: &str, tokens: usize, a: &BakedAttention, n: &Norm, eps: f64, hint: &str) -> String {
    if folds(a, tokens) {
        let normed = plain_layer_norm(g, x, n.weight.len(), eps, &format!("{hint}_norm"));
        folded_attention(g, &normed, tokens, a, n, hint)
    } else {
        let normed = layer_norm(g, x, n, eps, &format!("{hint}_norm"));
        projected_attention(g, &normed, tokens, a, hint)
    }
}

/// Whether [`folded_attention`] needs fewer multiply-adds per token than the projections:
/// `2 · heads · dim²` + scores and mixing at width `dim`, against `4 · dim · inner` + scores and
/// mixing at width `head_dim`. The iCub model (dim 20, one head of 64) needs 3–6× fewer.
fn folds(a: &BakedAttention, tokens: usize) -> bool {
    let (d, h, inner) = (a.out.rows, a.heads, a.heads * a.head_dim);
    let biased = [&a.q, &a.k, &a.v].iter().any(|l| l.bias.is_some());
    !biased && a.head_dim > 0 && 2 * h * d * d + 2 * tokens * h * d < 4 * d * inner + 2 * tokens * inner
}

/// Attention with each head's four matrices multiplied out, exact up to float rounding. With
/// `y = γ ∘ x + β` the layer norm's output: the scores `(y Wqᵀ)(y Wkᵀ)ᵀ = (y M) yᵀ` with
/// `M = scale · Wqᵀ Wk`, and the head's share of the output `P (y Wvᵀ) Woᵀ = P (y U)` with
/// `U = Wvᵀ Woᵀ`, both `[dim, dim]`. The keys' `β` adds the same `(y M) β` to every score of a
/// row, which the softmax ignores, so the keys are `γ ∘ x` and `γ` moves into `M`: the plain norm
/// `x` is all that the graph computes besides one product, `x [ΓMΓ | ΓU] + β [MΓ | U]`. The
/// scores and mixing run at width `dim`; the heads are summed.
fn folded_attention(g: &mut Graph, x: &str, tokens: usize, a: &BakedAttention, n: &Norm, hint: &str) -> String {
    let (d, h, hd) = (a.out.rows, a.heads, a.head_dim);
    let inner = h * hd;
    let (gamma, beta) = (|i: usize| n.weight[i] as f64, |i: usize| n.bias[i] as f64);
    // Row-major [dim, 2 · heads · dim]: columns head by head, first every M, then every U.
    let width = 2 * h * d;
    let (mut w, mut bias) = (vec![0f64; d * width], vec![0f64; width]);
    for head in 0..h {
        for i in 0..d {
            for j in 0..d {
                let (mut m, mut u) = (0f64, 0f64);
                for c in head * hd..(head + 1) * hd {
                    m += a.q.weight[c * d + i] as f64 * a.k.weight[c * d + j] as f64;
                    u += a.v.weight[c * d + i] as f64 * a.out.weight[j * inner + c] as f64;
                }
                let (mc, uc) = (head * d + j, (h + head) * d + j);
                let m = m * a.scale as f64 * gamma(j);
                w[i * width + mc] = gamma(i) * m;
                w[i * width + uc] = gamma(i) * u;
                bias[mc] += beta(i) * m;
                bias[uc] += beta(i) * u;
            }
        }
    }
    // A score is `(x A + c) · x` with a plain norm `x` (|x|² ≤ dim) and A, c the head's columns
    // of w and bias: at most √dim (‖A‖_F √dim + |c|).
    let bound = (0..h)
        .map(|head| {
            let a: f64 = (0..d * d).map(|k| w[(k / d) * width + head * d + k % d].powi(2)).sum::<f64>().sqrt();
            let c: f64 = (0..d).map(|j| bias[head * d + j].powi(2)).sum::<f64>().sqrt();
            (d as f64).sqrt() * (a * (d as f64).sqrt() + c)
        })
        .fold(0.0, f64::max);
    let w = g.f32s(&format!("{hint}_mu"), &[d, width], w.into_iter().map(|v| v as f32).collect());
    let bias = g.f32s(&format!("{hint}_mu_b"), &[width], bias.into_iter().map(|v| v as f32).collect());
    let mu = g.op("MatMul", &[x, &w]);
    let mu = g.op("Add", &[&mu, &bias]);
    let split = g.i64s("split_heads", &[4], vec![-1, tokens as i64, 2 * h as i64, d as i64]);
    let r = g.op("Reshape", &[&mu, &split]);
    let heads = g.node("Transpose", &[&r], vec![ints("perm", &[0, 2, 1, 3])], None);
    let axis = g.i64s("head_axis", &[1], vec![1]);
    let (zero, mid, end) = (g.i64s("start", &[1], vec![0]), g.i64s("mid", &[1], vec![h as i64]), g.i64s("end", &[1], vec![2 * h as i64]));
    let xm = g.op("Slice", &[&heads, &zero, &mid, &axis]);
    let xu = g.op("Slice", &[&heads, &mid, &end, &axis]);
    let per_seq = g.i64s("keys", &[4], vec![-1, 1, tokens as i64, d as i64]);
    let keys = g.op("Reshape", &[x, &per_seq]);
    let kt = g.node("Transpose", &[&keys], vec![ints("perm", &[0, 1, 3, 2])], None);
    let scores = g.op("MatMul", &[&xm, &kt]);
    let probs = softmax_rows(g, &scores, tokens, Some(bound));
    let mixed = g.op("MatMul", &[&probs, &xu]);
    let summed = if h == 1 { mixed } else { g.node("ReduceSum", &[&mixed, &axis], vec![int("keepdims", 0)], None) };
    let rows = g.i64s("rows", &[2], vec![-1, d as i64]);
    let flat = g.op("Reshape", &[&summed, &rows]);
    match &a.out.bias {
        Some(b) => {
            let b = g.f32s(&format!("{hint}_out_b"), &[d], b.clone());
            g.op("Add", &[&flat, &b])
        }
        None => flat,
    }
}

/// Scores up to this size in magnitude need no max-subtraction: `exp(±60)` is far from f32's
/// overflow (`exp(88.7)`) and from underflowing every entry of a row.
const EXP_SAFE: f64 = 60.0;

/// Attention with the baked projections; the scale is folded into the q weights. Projections
/// run on the flat rows as one matrix product each; only the scores and their mixing see the
/// sequences.
fn projected_attention(g: &mut Graph, x: &str, tokens: usize, a: &BakedAttention, hint: &str) -> String {
    let q_scaled = Dense { weight: a.q.weight.iter().map(|w| w * a.scale).collect(), ..a.q.clone() };
    let q = linear(g, x, &q_scaled, &format!("{hint}_q"));
    let k = linear(g, x, &a.k, &format!("{hint}_k"));
    let v = linear(g, x, &a.v, &format!("{hint}_v"));
    let split = g.i64s("split_heads", &[4], vec![-1, tokens as i64, a.heads as i64, a.head_dim as i64]);
    let heads = |g: &mut Graph, t: &str, perm: &[i64]| {
        let r = g.op("Reshape", &[t, &split]);
        g.node("Transpose", &[&r], vec![ints("perm", perm)], None)
    };
    let (qh, kt, vh) = (heads(g, &q, &[0, 2, 1, 3]), heads(g, &k, &[0, 2, 3, 1]), heads(g, &v, &[0, 2, 1, 3]));
    let scores = g.op("MatMul", &[&qh, &kt]);
    let probs = softmax_rows(g, &scores, tokens, None);
    let mixed = g.op("MatMul", &[&probs, &vh]);
    let back = g.node("Transpose", &[&mixed], vec![ints("perm", &[0, 2, 1, 3])], None);
    let rows = g.i64s("merge_heads", &[2], vec![-1, (a.heads * a.head_dim) as i64]);
    let merged = g.op("Reshape", &[&back, &rows]);
    linear(g, &merged, &a.out, &format!("{hint}_out"))
}

fn block(g: &mut Graph, x: &str, tokens: usize, b: &BakedBlock, eps: f64, hint: &str) -> String {
    let a = attention(g, x, tokens, &b.attn, &b.attn_norm, eps, &format!("{hint}_attn"));
    let x1 = g.op("Add", &[x, &a]);
    let n2 = plain_layer_norm(g, &x1, b.ffn_norm.weight.len(), eps, &format!("{hint}_ffn_norm"));
    let h = linear(g, &n2, &absorb_norm(&b.ffn.fc1, &b.ffn_norm), &format!("{hint}_fc1"));
    let h = gelu(g, &h);
    let f = linear(g, &h, &b.ffn.fc2, &format!("{hint}_fc2"));
    g.op("Add", &[&x1, &f])
}

/// A transformer over `x` `[sequences, tokens, dim]` → its normalised first token `[sequences, dim]`.
/// The blocks work on the flat `[sequences × tokens, dim]` rows.
fn transformer_cls(g: &mut Graph, x: &str, tokens: usize, t: &BakedTransformer, eps: f64, hint: &str) -> String {
    let d = t.norm.weight.len() as i64;
    let flat = g.i64s("rows", &[2], vec![-1, d]);
    let mut x = g.op("Reshape", &[x, &flat]);
    for (i, b) in t.layers.iter().enumerate() {
        x = block(g, &x, tokens, b, eps, &format!("{hint}{i}"));
    }
    let seqs = g.i64s("sequences", &[3], vec![-1, tokens as i64, d]);
    let x = g.op("Reshape", &[&x, &seqs]);
    let zero = g.i64s("first", &[], vec![0]);
    let cls = g.node("Gather", &[&x, &zero], vec![int("axis", 1)], None);
    layer_norm(g, &cls, &t.norm, eps, &format!("{hint}_norm"))
}

/// The first entry of a shape, as a 1-element shape.
fn first_dim(g: &mut Graph, shape: &str) -> String {
    let (s0, s1) = (g.i64s("start", &[1], vec![0]), g.i64s("end", &[1], vec![1]));
    g.op("Slice", &[shape, &s0, &s1])
}

/// `token` `[1, 1, (1,) dim]` repeated to `[batch, rest…]`.
fn expand_over_batch(g: &mut Graph, token: &str, batch: &str, rest: &[usize]) -> String {
    let rest = g.i64s("shape_rest", &[rest.len()], rest.iter().map(|v| *v as i64).collect());
    let shape = g.node("Concat", &[batch, &rest], vec![int("axis", 0)], None);
    g.op("Expand", &[token, &shape])
}

/// Checks the parts of a baked model the graph relies on.
fn check(m: &BakedPvt3, norm: &Normalization, meta: &Metadata) -> Result<()> {
    let c = &m.config;
    c.validate().map_err(|e| Error::Inconsistent(e.to_string()))?;
    let channels = c.sample_shape().iter().product::<usize>() / c.frames;
    if norm.mean.len() != channels || norm.std.len() != channels || norm.frames != c.frames {
        return Err(Error::Inconsistent(format!("normalisation does not fit {channels} channels × {} frames", c.frames)));
    }
    if meta.classes.len() != c.classes {
        return Err(Error::Inconsistent(format!("{} class names for {} classes", meta.classes.len(), c.classes)));
    }
    if m.kept_tokens.is_empty() {
        return Err(Error::Unsupported("every frame is pruned; the model would ignore its input".into()));
    }
    for (name, t) in [("space", &m.space), ("temporal", &m.temporal)] {
        for (i, b) in t.layers.iter().enumerate() {
            if b.attn.head_dim == 0 || b.ffn.fc1.rows == 0 {
                return Err(Error::Unsupported(format!(
                    "{name} layer {i} has no attention channel or no feed-forward unit left; prune less"
                )));
            }
        }
    }
    Ok(())
}

fn value_info(name: &str, dims: &[Option<usize>]) -> ValueInfoProto {
    let dim = dims
        .iter()
        .map(|d| Dimension {
            value: Some(match d {
                Some(v) => Dim::DimValue(*v as i64),
                None => Dim::DimParam("batch".into()),
            }),
            ..Default::default()
        })
        .collect();
    ValueInfoProto {
        name: name.into(),
        r#type: Some(TypeProto {
            value: Some(type_proto::Value::TensorType(type_proto::Tensor {
                elem_type: DataType::Float as i32,
                shape: Some(TensorShapeProto { dim }),
            })),
            ..Default::default()
        }),
        ..Default::default()
    }
}

/// The ONNX model of a baked PVT³ with its normalisation.
///
/// The graph has two named seams so that a streaming runtime can cut it: the spatial stage maps
/// [`TOKEN_FRAMES`] (the raw frames of each kept temporal token) and [`TOKEN_INDEX`] (its place
/// among the kept tokens) to [`TOKEN_ENCODINGS`]; the temporal stage maps those to the outputs.
/// Both stages are written for any number of tokens, so the same nodes serve a whole batch and a
/// single token as it arrives.
pub fn export(m: &BakedPvt3, norm: &Normalization, meta: &Metadata) -> Result<ModelProto> {
    check(m, norm, meta)?;
    let c = &m.config;
    let (n, d, eps) = (c.num_patches(), c.dim, c.layer_norm_eps);
    let (t, tk, tt) = (c.time_tokens(), m.kept_tokens.len(), c.tubelet);
    let (h, w, ch) = (c.height, c.width, c.channels);
    let mut g = Graph::default();
    let sample = c.sample_shape();

    // The kept tokens' raw frames: [b, h, w, (c,) f] → [b, h, w, c, t, tt] → gather → [b·tk, tt, h, w, c].
    let split = g.i64s("split_tokens", &[6], [0, h, w, ch, t, tt].map(|v| v as i64).to_vec());
    let mut x = g.op("Reshape", &[INPUT, &split]);
    if tk < t {
        let idx = g.i64s("kept_tokens", &[tk], m.kept_tokens.iter().map(|k| *k as i64).collect());
        x = g.node("Gather", &[&x, &idx], vec![int("axis", 4)], None);
    }
    let x = g.node("Transpose", &[&x], vec![ints("perm", &[0, 4, 5, 1, 2, 3])], None);
    let per_token = g.i64s("per_token", &[5], [-1, tt as i64, h as i64, w as i64, ch as i64].to_vec());
    let x = g.op("Reshape", &[&x, &per_token]);
    g.node("Identity", &[&x], vec![], Some(TOKEN_FRAMES));
    let input_shape = g.op("Shape", &[INPUT]);
    let batch = first_dim(&mut g, &input_shape);
    let kept_row = g.i64s("kept_row", &[1, tk], (0..tk as i64).collect());
    let rows = g.i64s("rows", &[1], vec![tk as i64]);
    let b_tk = g.node("Concat", &[&batch, &rows], vec![int("axis", 0)], None);
    let index = g.op("Expand", &[&kept_row, &b_tk]);
    let flat = g.i64s("flat", &[1], vec![-1]);
    let index = g.op("Reshape", &[&index, &flat]);
    g.node("Identity", &[&index], vec![], Some(TOKEN_INDEX));

    // Spatial stage. Normalise per channel: (x - mean) / std.
    let mean = g.f32s("norm_mean", &[h, w, ch], norm.mean.clone());
    let std = g.f32s("norm_std", &[h, w, ch], norm.std.clone());
    let centred = g.op("Sub", &[TOKEN_FRAMES, &mean]);
    let x = g.op("Div", &[&centred, &std]);
    // Patches: [N, tt, gh, ph, gw, pw, c] → [N, gh, gw, tt, ph, pw, c] → [N, n, patch_dim].
    let (gh, gw) = (h / c.patch_height, w / c.patch_width);
    let grid = [0, tt, gh, c.patch_height, gw, c.patch_width, ch].map(|v| v as i64);
    let grid = g.i64s("grid", &[7], grid.to_vec());
    let x = g.op("Reshape", &[&x, &grid]);
    let x = g.node("Transpose", &[&x], vec![ints("perm", &[0, 2, 4, 1, 3, 5, 6])], None);
    let patch_rows = g.i64s("patch_rows", &[2], vec![-1, c.patch_dim() as i64]);
    let x = g.op("Reshape", &[&x, &patch_rows]);
    let x = linear(&mut g, &x, &m.patch_embed, "patch_embed");
    let tokens_shape = g.i64s("tokens", &[3], vec![-1, n as i64, d as i64]);
    let x = g.op("Reshape", &[&x, &tokens_shape]);
    let scales = g.f32s("frame_scale", &[tk], m.token_scale.clone());
    let scale = g.node("Gather", &[&scales, TOKEN_INDEX], vec![int("axis", 0)], None);
    let column = g.i64s("column", &[3], vec![-1, 1, 1]);
    let scale = g.op("Reshape", &[&scale, &column]);
    let embedded = g.op("Mul", &[&x, &scale]);
    let token_shape = g.op("Shape", &[TOKEN_FRAMES]);
    let count = first_dim(&mut g, &token_shape);
    let space_cls = g.f32s("space_cls", &[1, 1, d], m.space_cls.clone());
    let cls = expand_over_batch(&mut g, &space_cls, &count, &[1, d]);
    let tokens = g.node("Concat", &[&cls, &embedded], vec![int("axis", 1)], None);
    let positions = g.f32s("pos_embed", &[tk, n + 1, d], m.pos_embed.clone());
    let pos = g.node("Gather", &[&positions, TOKEN_INDEX], vec![int("axis", 0)], None);
    let tokens = g.op("Add", &[&tokens, &pos]);
    let encoded = transformer_cls(&mut g, &tokens, n + 1, &m.space, eps, "space");
    g.node("Identity", &[&encoded], vec![], Some(TOKEN_ENCODINGS));

    // Temporal stage.
    let per_sample = g.i64s("per_sample", &[3], vec![-1, tk as i64, d as i64]);
    let mut frames = g.op("Reshape", &[TOKEN_ENCODINGS, &per_sample]);
    let frames_shape = g.op("Shape", &[&frames]);
    let batch = first_dim(&mut g, &frames_shape);
    // Pruned tokens: their constant encodings, placed around the kept ones.
    if tk < t {
        let mut place = vec![0f32; t * tk];
        for (kk, &k) in m.kept_tokens.iter().enumerate() {
            place[k * tk + kk] = 1.0;
        }
        let place = g.f32s("place_kept", &[t, tk], place);
        let constants = g.f32s("pruned_encodings", &[t, d], m.pruned_encodings.clone());
        let placed = g.op("MatMul", &[&place, &frames]);
        frames = g.op("Add", &[&placed, &constants]);
    }
    let temporal_cls = g.f32s("temporal_cls", &[1, 1, d], m.temporal_cls.clone());
    let tcls = expand_over_batch(&mut g, &temporal_cls, &batch, &[1, d]);
    let sequence = g.node("Concat", &[&tcls, &frames], vec![int("axis", 1)], None);
    let pooled = transformer_cls(&mut g, &sequence, t + 1, &m.temporal, eps, "temporal");
    let normed = layer_norm(&mut g, &pooled, &m.head_norm, eps, "head_norm");
    let logits = linear(&mut g, &normed, &m.head, "head");
    g.node("Identity", &[&logits], vec![], Some(LOGITS));
    g.node("Softmax", &[&logits], vec![int("axis", -1)], Some(PROBABILITIES));
    let kept_frames: Vec<i64> = m.kept_tokens.iter().flat_map(|k| (k * tt..(k + 1) * tt).map(|f| f as i64)).collect();

    let mut input_dims = vec![None];
    input_dims.extend(sample.iter().map(|v| Some(*v)));
    let graph = GraphProto {
        name: "pvt3".into(),
        node: g.nodes,
        initializer: g.initializers,
        input: vec![value_info(INPUT, &input_dims)],
        output: vec![value_info(LOGITS, &[None, Some(c.classes)]), value_info(PROBABILITIES, &[None, Some(c.classes)])],
        ..Default::default()
    };
    let layout = if c.channels == 1 { "[batch, height, width, frames]" } else { "[batch, height, width, channels, frames]" };
    let props = [
        ("pvt3.classes", serde_json::to_string(&meta.classes).expect("strings serialise")),
        (
            "pvt3.input_layout",
            format!(
                "{layout} = [batch, {}], raw sensor values as float32",
                sample.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", ")
            ),
        ),
        ("pvt3.input_units", "the data set's raw units (normalisation is inside the graph)".into()),
        ("pvt3.kept_frames", serde_json::to_string(&kept_frames).expect("integers serialise")),
        ("pvt3.config", serde_json::to_string(c).expect("the configuration serialises")),
        ("pvt3.provenance", meta.provenance.to_string()),
    ];
    Ok(ModelProto {
        ir_version: 8,
        opset_import: vec![OperatorSetIdProto { domain: String::new(), version: 17 }],
        producer_name: "pvt3".into(),
        producer_version: env!("CARGO_PKG_VERSION").into(),
        graph: Some(graph),
        metadata_props: props.into_iter().map(|(k, v)| StringStringEntryProto { key: k.into(), value: v }).collect(),
        ..Default::default()
    })
}

/// Writes the model to `path` through a temporary file and a rename.
pub fn write(model: &ModelProto, path: &Path) -> Result<()> {
    let tmp = path.with_extension("onnx.tmp");
    let io = |e: std::io::Error| Error::Io { path: path.display().to_string(), source: e };
    std::fs::write(&tmp, model.encode_to_vec()).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

#[cfg(test)]
mod tests;
