//! The PVT³ graph, from raw frames to logits and probabilities.

use std::path::Path;

use prost::Message;
use pvt3_spec::baked::{BakedBlock, BakedPvt3, BakedTransformer};
use pvt3_spec::normalization::Normalization;

use crate::attention::{attention, Heads, Layout, Rows};
use crate::embedding::embed;
use pvt3_format::onnx::{
    int, ints, DataType, Dimension, DimensionValue as Dim, GraphProto, ModelProto, Op, OperatorSetIdProto, StringStringEntryProto,
    TensorShapeProto, TensorTypeProto, TypeProto, ValueInfoProto,
};

use crate::graph::Graph;
use crate::layers::{absorb_norm, centre_rows, centred, gelu, layer_norm, linear, norm_affine, residual_linear, rms_norm};
use crate::spectrum::spectral_logits;
use crate::{Error, Result};
use pvt3_format::{keys, Dims, Header, INPUT, LOGITS, PROBABILITIES, TOKEN_BIAS, TOKEN_ENCODINGS, TOKEN_FRAMES, TOKEN_INDEX};

/// What the file says about itself, besides the graph.
#[derive(Clone, Debug)]
pub struct Metadata {
    pub classes: Vec<String>,
    /// Where the model came from (data set, fold, accuracy, pruning), as JSON.
    pub provenance: serde_json::Value,
    /// The stopping rule of provisional answers (`pvt3.stop_rule`).
    pub stop_rule: Option<pvt3_format::StopRule>,
    /// How the model reads a touch (`pvt3.reading`), if its training touches were brought to one
    /// speed and force.
    pub reading: Option<pvt3_format::Reading>,
    /// How a camera's frames become the model's (`pvt3.camera`), for a model of camera frames
    /// imported from videos or images.
    pub camera: Option<pvt3_format::Camera>,
}

/// One pre-norm block on the (centred) stream `x`: `[rows, dim]` out, or with `cls_only` the
/// first token of each sequence alone, `[sequences, dim]`.
fn block(g: &mut Graph, x: &str, rows: Rows, cls_only: bool, b: &BakedBlock, eps: f64, hint: &str) -> String {
    let xhat = rms_norm(g, x, eps);
    let heads = Heads::new(&b.attn, &b.attn_norm, rows.tokens);
    let x1 = attention(g, x, &xhat, rows, cls_only, &heads, &format!("{hint}_attn"));
    let n2 = rms_norm(g, &x1, eps);
    let h = linear(g, &n2, &absorb_norm(&b.ffn.fc1, &b.ffn_norm), &format!("{hint}_fc1"));
    let h = gelu(g, &h);
    residual_linear(g, &x1, &h, &centred(&b.ffn.fc2), &format!("{hint}_fc2"))
}

/// A transformer over the flat rows `x` of a centred stream laid out as `rows`: its first token
/// after the last block, not yet normalised, `[sequences, dim]`. The last block asks only the
/// first token's query, since nothing else is read.
fn transformer_cls(g: &mut Graph, x: &str, rows: Rows, t: &BakedTransformer, eps: f64, hint: &str) -> String {
    let last = t.layers.len().checked_sub(1);
    let mut x = x.to_string();
    for (i, b) in t.layers.iter().enumerate() {
        x = block(g, &x, rows, Some(i) == last, b, eps, &format!("{hint}{i}"));
    }
    if last.is_none() {
        x = rows.first(g, &x, t.norm.weight.len());
    }
    x
}

/// The first entry of a shape, as a 1-element shape.
fn first_dim(g: &mut Graph, shape: &str) -> String {
    let (s0, s1) = (g.i64s("start", &[1], vec![0]), g.i64s("end", &[1], vec![1]));
    g.op(Op::Slice, &[shape, &s0, &s1])
}

/// `token` `[1, 1, (1,) dim]` repeated to `[batch, rest…]`.
fn expand_over_batch(g: &mut Graph, token: &str, batch: &str, rest: &[usize]) -> String {
    let rest = g.i64s("shape_rest", &[rest.len()], rest.iter().map(|v| *v as i64).collect());
    let shape = g.node(Op::Concat, &[batch, &rest], vec![int("axis", 0)], None);
    g.op(Op::Expand, &[token, &shape])
}

/// Checks the parts of a baked model the graph relies on.
fn check(m: &BakedPvt3, norm: &Normalization, meta: &Metadata) -> Result<()> {
    let c = &m.config;
    c.validate().map_err(|e| Error::Inconsistent(e.to_string()))?;
    if !norm.fits(c) {
        return Err(Error::Inconsistent(format!("normalisation does not fit {} channels × {} frames", c.sensor_channels(), c.frames)));
    }
    if meta.classes.len() != c.classes {
        return Err(Error::Inconsistent(format!("{} class names for {} classes", meta.classes.len(), c.classes)));
    }
    if let Some(problem) = meta.camera.and_then(|cam| cam.problem(&dims(c))) {
        return Err(Error::Inconsistent(format!("camera: {problem}")));
    }
    if let Some(problem) = meta.stop_rule.and_then(|r| r.problem()) {
        return Err(Error::Inconsistent(format!("stopping rule: {problem}")));
    }
    if m.kept_tokens.is_empty() || m.kept_patches.is_empty() {
        return Err(Error::Unsupported("every frame or every patch is pruned; the model would ignore its input".into()));
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
        })
        .collect();
    ValueInfoProto {
        name: name.into(),
        r#type: Some(TypeProto {
            tensor_type: Some(TensorTypeProto { elem_type: DataType::Float as i32, shape: Some(TensorShapeProto { dim }) }),
        }),
    }
}

/// The ONNX model of a baked PVT³ with its normalisation.
///
/// The graph has two named seams so that a streaming runtime can cut it: the spatial stage maps
/// `TOKEN_FRAMES` (the raw frames of each kept temporal token) and `TOKEN_INDEX` (its place
/// among the kept tokens) to `TOKEN_ENCODINGS`; the temporal stage maps those to the outputs.
/// Both stages are written for any number of tokens, so the same nodes serve a whole batch and a
/// single token as it arrives. A third seam, `TOKEN_BIAS` (zeros), is added to every temporal
/// attention score by its key: a runtime that feeds −∞ for the tokens a touch has not reached
/// gets the temporal stage over the tokens so far, a provisional answer.
pub fn export(m: &BakedPvt3, norm: &Normalization, meta: &Metadata) -> Result<ModelProto> {
    check(m, norm, meta)?;
    let mut g = Graph::default();
    token_seams(&mut g, m);
    let rows = spatial_stage(&mut g, m, norm);
    temporal_stage(&mut g, m, norm, &rows);
    Ok(signed_model(g, m, meta))
}

/// The kept tokens' raw frames (`TOKEN_FRAMES`) cut from the input, and each one's place among
/// the kept tokens (`TOKEN_INDEX`).
fn token_seams(g: &mut Graph, m: &BakedPvt3) {
    let c = &m.config;
    let (t, tk, tt) = (c.time_tokens(), m.kept_tokens.len(), c.tubelet);
    let (h, w, ch) = (c.height, c.width, c.channels);
    // The kept tokens' raw frames: [b, h, w, (c,) f] → [b, h, w, c, t, tt] → gather → [b·tk, tt, h, w, c].
    let split = g.i64s("split_tokens", &[6], [0, h, w, ch, t, tt].map(|v| v as i64).to_vec());
    let mut x = g.op(Op::Reshape, &[INPUT, &split]);
    if tk < t {
        let idx = g.i64s("kept_tokens", &[tk], m.kept_tokens.iter().map(|k| *k as i64).collect());
        x = g.node(Op::Gather, &[&x, &idx], vec![int("axis", 4)], None);
    }
    let x = g.node(Op::Transpose, &[&x], vec![ints("perm", &[0, 4, 5, 1, 2, 3])], None);
    let per_token = g.i64s("per_token", &[5], [-1, tt as i64, h as i64, w as i64, ch as i64].to_vec());
    let x = g.op(Op::Reshape, &[&x, &per_token]);
    g.node(Op::Identity, &[&x], vec![], Some(TOKEN_FRAMES));
    let input_shape = g.op(Op::Shape, &[INPUT]);
    let batch = first_dim(g, &input_shape);
    let kept_row = g.i64s("kept_row", &[1, tk], (0..tk as i64).collect());
    let rows = g.i64s("rows", &[1], vec![tk as i64]);
    let b_tk = g.node(Op::Concat, &[&batch, &rows], vec![int("axis", 0)], None);
    let index = g.op(Op::Expand, &[&kept_row, &b_tk]);
    let flat = g.i64s("flat", &[1], vec![-1]);
    let index = g.op(Op::Reshape, &[&index, &flat]);
    g.node(Op::Identity, &[&index], vec![], Some(TOKEN_INDEX));
}

/// The spatial stage, from `TOKEN_FRAMES` and `TOKEN_INDEX` to `TOKEN_ENCODINGS`. Returns the
/// name of the shape `[-1, dim]` of its rows, which the temporal stage reads too.
fn spatial_stage(g: &mut Graph, m: &BakedPvt3, norm: &Normalization) -> String {
    let c = &m.config;
    let (n, d, eps, tk) = (m.kept_patches.len(), c.dim, c.layer_norm_eps, m.kept_tokens.len());
    // Spatial stage. Everything written to the residual stream is centred (see `layers`), so
    // every pre-norm is a root-mean-square norm: the patch embedding, the CLS tokens, the
    // position embedding, each block's outputs, and the encodings handed to the temporal stage.
    let x = embed(g, TOKEN_FRAMES, m, norm);
    // Each kept token's frame-mask value, times each kept patch's patch-mask value if any is not one.
    let (scales, column) = if m.patch_scale.iter().all(|s| *s == 1.0) {
        (g.f32s("frame_scale", &[tk], m.token_scale.clone()), vec![-1, 1, 1])
    } else {
        let table = m.token_scale.iter().flat_map(|t| m.patch_scale.iter().map(move |p| t * p)).collect();
        (g.f32s("frame_scale", &[tk, n], table), vec![-1, n as i64, 1])
    };
    let scale = g.node(Op::Gather, &[&scales, TOKEN_INDEX], vec![int("axis", 0)], None);
    let column = g.i64s("column", &[3], column);
    let scale = g.op(Op::Reshape, &[&scale, &column]);
    let embedded = g.op(Op::Mul, &[&x, &scale]);
    let token_shape = g.op(Op::Shape, &[TOKEN_FRAMES]);
    let count = first_dim(g, &token_shape);
    let space_cls = g.f32s("space_cls", &[1, 1, d], centre_rows(&m.space_cls, d));
    let cls = expand_over_batch(g, &space_cls, &count, &[1, d]);
    let tokens = g.node(Op::Concat, &[&cls, &embedded], vec![int("axis", 1)], None);
    let positions = g.f32s("pos_embed", &[tk, n + 1, d], centre_rows(&m.pos_embed, d));
    let pos = g.node(Op::Gather, &[&positions, TOKEN_INDEX], vec![int("axis", 0)], None);
    let tokens = g.op(Op::Add, &[&tokens, &pos]);
    // Token-major rows [n + 1, sequences, dim] for the spatial attention (see `attention`).
    let tokens = g.node(Op::Transpose, &[&tokens], vec![ints("perm", &[1, 0, 2])], None);
    let flat = g.i64s("rows", &[2], vec![-1, d as i64]);
    let tokens = g.op(Op::Reshape, &[&tokens, &flat]);
    let space = Rows { layout: Layout::TokenMajor, tokens: n + 1, key_bias: None };
    let cls = transformer_cls(g, &tokens, space, &m.space, eps, "space");
    let cls = rms_norm(g, &cls, eps);
    let encoded = linear(g, &cls, &centred(&norm_affine(&m.space.norm)), "space_norm");
    g.node(Op::Identity, &[&encoded], vec![], Some(TOKEN_ENCODINGS));
    flat
}

/// The temporal stage, from `TOKEN_ENCODINGS` (and `TOKEN_BIAS`) to `LOGITS` and
/// `PROBABILITIES`; `flat` names the shape of the spatial stage's rows.
fn temporal_stage(g: &mut Graph, m: &BakedPvt3, norm: &Normalization, flat: &str) {
    let c = &m.config;
    let (d, eps, t, tk) = (c.dim, c.layer_norm_eps, c.time_tokens(), m.kept_tokens.len());
    // Temporal stage.
    let per_sample = g.i64s("per_sample", &[3], vec![-1, tk as i64, d as i64]);
    let frames = g.op(Op::Reshape, &[TOKEN_ENCODINGS, &per_sample]);
    let frames_shape = g.op(Op::Shape, &[&frames]);
    let batch = first_dim(g, &frames_shape);
    // The sequence: the CLS token, then every time token in order, a pruned one as its constant
    // encoding. The constants come first, [CLS, pruned…, kept…], and one gather orders them.
    let pruned: Vec<usize> = (0..t).filter(|k| !m.kept_tokens.contains(k)).collect();
    let mut constants = centre_rows(&m.temporal_cls, d);
    constants.extend(pruned.iter().flat_map(|&k| centre_rows(&m.pruned_encodings[k * d..(k + 1) * d], d)));
    let constants = g.f32s("temporal_constants", &[1, 1 + pruned.len(), d], constants);
    let constants = expand_over_batch(g, &constants, &batch, &[1 + pruned.len(), d]);
    let mut sequence = g.node(Op::Concat, &[&constants, &frames], vec![int("axis", 1)], None);
    if tk < t {
        let place = |k: usize| match m.kept_tokens.binary_search(&k) {
            Ok(kept) => 1 + pruned.len() + kept,
            Err(_) => 1 + pruned.binary_search(&k).expect("a token is kept or pruned"),
        };
        let order = g.i64s("token_order", &[t + 1], std::iter::once(0).chain((0..t).map(|k| place(k) as i64)).collect());
        sequence = g.node(Op::Gather, &[&sequence, &order], vec![int("axis", 1)], None);
    }
    let sequence = g.op(Op::Reshape, &[&sequence, flat]);
    // The key bias, zeros here, is a seam: a runtime feeds −∞ for the tokens not yet received.
    let zeros = g.f32s("no_key_bias", &[1, 1, 1, t + 1], vec![0.0; t + 1]);
    g.node(Op::Identity, &[&zeros], vec![], Some(TOKEN_BIAS));
    let temporal = Rows { layout: Layout::SequenceMajor, tokens: t + 1, key_bias: Some(TOKEN_BIAS) };
    let pooled = transformer_cls(g, &sequence, temporal, &m.temporal, eps, "temporal");
    let pooled = layer_norm(g, &pooled, &m.temporal.norm, eps, "temporal_norm");
    let normed = layer_norm(g, &pooled, &m.head_norm, eps, "head_norm");
    let mut logits = linear(g, &normed, &m.head, "head");
    if let Some(s) = &m.spectrum {
        let spectral = spectral_logits(g, m, s, norm);
        logits = g.op(Op::Add, &[&logits, &spectral]);
    }
    g.node(Op::Identity, &[&logits], vec![], Some(LOGITS));
    g.node(Op::Softmax, &[&logits], vec![int("axis", -1)], Some(PROBABILITIES));
}

/// The input and token sizes a runtime reads, of configuration `c`.
fn dims(c: &pvt3_spec::Config) -> Dims {
    Dims { height: c.height, width: c.width, channels: c.channels, frames: c.frames, tubelet: c.tubelet, dim: c.dim }
}

/// The graph `g` as a model with its inputs, outputs and metadata, signed.
fn signed_model(g: Graph, m: &BakedPvt3, meta: &Metadata) -> ModelProto {
    let c = &m.config;
    let tt = c.tubelet;
    let sample = c.sample_shape();
    let kept_frames: Vec<usize> = m.kept_tokens.iter().flat_map(|k| k * tt..(k + 1) * tt).collect();

    let mut input_dims = vec![None];
    input_dims.extend(sample.iter().map(|v| Some(*v)));
    let graph = GraphProto {
        name: "pvt3".into(),
        node: g.nodes,
        initializer: g.initializers,
        input: vec![value_info(INPUT, &input_dims)],
        output: vec![value_info(LOGITS, &[None, Some(c.classes)]), value_info(PROBABILITIES, &[None, Some(c.classes)])],
    };
    let dims = dims(c);
    let header =
        Header { classes: meta.classes.clone(), kept_frames, dims, stop_rule: meta.stop_rule, reading: meta.reading, camera: meta.camera };
    let config = serde_json::to_value(c).expect("the configuration serialises");
    let mut props = header.entries(&config);
    props.push((keys::PROVENANCE, meta.provenance.to_string()));
    let mut model = ModelProto {
        ir_version: 8,
        opset_import: vec![OperatorSetIdProto { domain: String::new(), version: 17 }],
        producer_name: "pvt3".into(),
        producer_version: env!("CARGO_PKG_VERSION").into(),
        graph: Some(graph),
        metadata_props: props.into_iter().map(|(k, v)| StringStringEntryProto { key: k.into(), value: v }).collect(),
    };
    // Last: the digest of everything above, which the runtime checks before it reads the file.
    model.sign();
    model
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
