//! Raw frames to patch embeddings: normalisation per channel, then the patch embedding.
//!
//! Both steps avoid work that tract runs element by element. The normalisation works on rows
//! padded to whole vectors (on the raw iCub rows of 60 values it cost a sixth of the model). The
//! embedding of small frames is one product with a block-diagonal matrix that maps a token's
//! whole frame to all of its patch embeddings, which spares the rearrangement into patches; large
//! frames (where that matrix would be large) are cut into patches first. A model whose patch mask
//! pruned patches gathers the kept patches' values first, so that nothing after reads the
//! pruned ones.

use pvt3_spec::baked::{BakedPvt3, Dense};
use pvt3_spec::normalization::Normalization;
use pvt3_spec::Config;

use pvt3_format::onnx::{int, ints, Op};

use crate::graph::Graph;
use crate::layers::{centred, linear};

/// Values per vector that tract's broadcasts need to take their fast path (AVX-512: 64).
const ALIGN: usize = 64;

/// Largest block-diagonal embedding matrix, in values (4 MB): iCub needs 5,120, BioTac 3,840.
const DENSE_LIMIT: usize = 1 << 20;

/// `frames` `[tokens, tubelet, height, width, channels]` → centred patch embeddings
/// `[tokens, patches, dim]`.
pub(crate) fn embed(g: &mut Graph, frames: &str, m: &BakedPvt3, norm: &Normalization) -> String {
    let c = &m.config;
    let (tt, h, w, ch, d) = (c.tubelet, c.height, c.width, c.channels, c.dim);
    let features = tt * h * w * ch;
    let flat = g.i64s("frame_rows", &[2], vec![-1, features as i64]);
    let rows = g.op(Op::Reshape, &[frames, &flat]);
    if m.kept_patches.len() < c.num_patches() {
        return embed_kept_patches(g, &rows, m, norm);
    }
    let n = c.num_patches();
    // Padded to whole vectors: tract runs a row broadcast fast only if the row is a multiple of
    // 64 values, and element by element otherwise.
    let padded = features.div_ceil(ALIGN) * ALIGN;
    let rows = if padded > features {
        let columns = g.i64s("pad_columns", &[padded], (0..padded).map(|i| (i % features) as i64).collect());
        g.node(Op::Gather, &[&rows, &columns], vec![int("axis", 1)], None)
    } else {
        rows
    };
    let per_feature = |v: &[f32], pad: f32| {
        let mut row: Vec<f32> = (0..tt).flat_map(|_| v.iter().copied()).collect();
        row.resize(padded, pad);
        row
    };
    let rows = normalise(g, &rows, per_feature(&norm.mean, 0.0), per_feature(&norm.std, 1.0));
    let embedding = centred(&m.patch_embed);
    let x = if padded * n * d <= DENSE_LIMIT {
        linear(g, &rows, &block_diagonal(m, &embedding, padded), "patch_embed")
    } else {
        let (start, end, axis) =
            (g.i64s("start", &[1], vec![0]), g.i64s("end", &[1], vec![features as i64]), g.i64s("axis", &[1], vec![1]));
        let rows = g.op(Op::Slice, &[&rows, &start, &end, &axis]);
        // [N, tt, gh, ph, gw, pw, c] → [N, gh, gw, tt, ph, pw, c] → [N · n, patch_dim].
        let (ph, pw) = (c.patch_height, c.patch_width);
        let grid = g.i64s("grid", &[7], [0, tt, h / ph, ph, w / pw, pw, ch].map(|v| v as i64).to_vec());
        let x = g.op(Op::Reshape, &[&rows, &grid]);
        let x = g.node(Op::Transpose, &[&x], vec![ints("perm", &[0, 2, 4, 1, 3, 5, 6])], None);
        let patch_rows = g.i64s("patch_rows", &[2], vec![-1, c.patch_dim() as i64]);
        let x = g.op(Op::Reshape, &[&x, &patch_rows]);
        linear(g, &x, &embedding, "patch_embed")
    };
    let tokens = g.i64s("tokens", &[3], vec![-1, n as i64, d as i64]);
    g.op(Op::Reshape, &[&x, &tokens])
}

/// `(rows − mean) / std`, per column.
fn normalise(g: &mut Graph, rows: &str, mean: Vec<f32>, std: Vec<f32>) -> String {
    let mean = g.f32s("norm_mean", &[mean.len()], mean);
    let std = g.f32s("norm_std", &[std.len()], std);
    let shifted = g.op(Op::Sub, &[rows, &mean]);
    g.op(Op::Div, &[&shifted, &std])
}

/// The embedding of the kept patches alone from a token's frame `rows` `[N, tt·h·w·c]`: one
/// gather takes their values in patch order (padded to whole vectors, as above), then the
/// normalisation and the embedding read those only.
fn embed_kept_patches(g: &mut Graph, rows: &str, m: &BakedPvt3, norm: &Normalization) -> String {
    let c = &m.config;
    let (h, w, ch, d, pd, nk) = (c.height, c.width, c.channels, c.dim, c.patch_dim(), m.kept_patches.len());
    let mut columns = patch_columns(c, &m.kept_patches);
    let values = nk * pd;
    columns.resize(values.div_ceil(ALIGN) * ALIGN, 0);
    let index = g.i64s("kept_patch_values", &[columns.len()], columns.iter().map(|v| *v as i64).collect());
    let rows = g.node(Op::Gather, &[rows, &index], vec![int("axis", 1)], None);
    let per_value = |v: &[f32]| columns.iter().map(|i| v[i % (h * w * ch)]).collect();
    let rows = normalise(g, &rows, per_value(&norm.mean), per_value(&norm.std));
    let (start, end, axis) = (g.i64s("start", &[1], vec![0]), g.i64s("end", &[1], vec![values as i64]), g.i64s("axis", &[1], vec![1]));
    let rows = g.op(Op::Slice, &[&rows, &start, &end, &axis]);
    let patch_rows = g.i64s("patch_rows", &[2], vec![-1, pd as i64]);
    let x = g.op(Op::Reshape, &[&rows, &patch_rows]);
    let x = linear(g, &x, &centred(&m.patch_embed), "patch_embed");
    let tokens = g.i64s("tokens", &[3], vec![-1, nk as i64, d as i64]);
    g.op(Op::Reshape, &[&x, &tokens])
}

/// For each of `patches` (row-major over the grid) and each of its values in the patch
/// embedding's order, `((f · ph + dy) · pw + dx) · c + k`, its column in a token's frame row
/// `(f, y, x, k)`.
fn patch_columns(c: &Config, patches: &[usize]) -> Vec<usize> {
    let (tt, h, w, ch) = (c.tubelet, c.height, c.width, c.channels);
    let (ph, pw, gw) = (c.patch_height, c.patch_width, c.width / c.patch_width);
    let mut columns = Vec::with_capacity(patches.len() * c.patch_dim());
    for &p in patches {
        for f in 0..tt {
            for dy in 0..ph {
                for dx in 0..pw {
                    let (y, x) = ((p / gw) * ph + dy, (p % gw) * pw + dx);
                    columns.extend((0..ch).map(|k| ((f * h + y) * w + x) * ch + k));
                }
            }
        }
    }
    columns
}

/// The embedding `e` of each patch as one layer over a token's whole frame, `[tt·h·w·c]` →
/// `[patches · dim]`: each patch's value at its place within the patch ([`patch_columns`])
/// feeds that patch's embedding; every other weight is zero, as are the weights of the padding
/// up to `inputs`.
fn block_diagonal(m: &BakedPvt3, e: &Dense, inputs: usize) -> Dense {
    let c = &m.config;
    let (d, n, pd) = (c.dim, c.num_patches(), c.patch_dim());
    let mut weight = vec![0f32; n * d * inputs];
    let every: Vec<usize> = (0..n).collect();
    for (i, input) in patch_columns(c, &every).into_iter().enumerate() {
        let (patch, within) = (i / pd, i % pd);
        for j in 0..d {
            weight[(patch * d + j) * inputs + input] = e.weight[j * e.cols + within];
        }
    }
    let bias = e.bias.as_ref().map(|b| (0..n).flat_map(|_| b.iter().copied()).collect());
    Dense { rows: n * d, cols: inputs, weight, bias }
}
