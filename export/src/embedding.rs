//! Raw frames to patch embeddings: normalisation per channel, then the patch embedding.
//!
//! The normalisation works on a token's whole frame as one row. It once padded rows to 64 values
//! (tract's broadcasts then took their fast path: a sixth of the iCub model's time); with the
//! runtime's own loader and kernels padding no longer changed the time (docs/benchmarks.md,
//! step 19), so rows stay as they are on every target. The embedding of small frames is one product with a block-diagonal matrix that maps a token's
//! whole frame to all of its patch embeddings, which spares the rearrangement into patches; large
//! frames (where that matrix would be large) are cut into patches first.

use pvt3_models::bake::{BakedPvt3, Dense};
use pvt3_models::normalization::Normalization;

use crate::graph::{ints, Graph};
use crate::layers::{centred, linear};

/// Largest block-diagonal embedding matrix, in values (4 MB): iCub needs 5,120, BioTac 3,840.
const DENSE_LIMIT: usize = 1 << 20;

/// `frames` `[tokens, tubelet, height, width, channels]` → centred patch embeddings
/// `[tokens, patches, dim]`.
pub(crate) fn embed(g: &mut Graph, frames: &str, m: &BakedPvt3, norm: &Normalization) -> String {
    let c = &m.config;
    let (tt, h, w, ch, d, n) = (c.tubelet, c.height, c.width, c.channels, c.dim, c.num_patches());
    let features = tt * h * w * ch;
    let flat = g.i64s("frame_rows", &[2], vec![-1, features as i64]);
    let rows = g.op("Reshape", &[frames, &flat]);
    let per_feature = |v: &[f32]| (0..tt).flat_map(|_| v.iter().copied()).collect::<Vec<f32>>();
    let mean = g.f32s("norm_mean", &[features], per_feature(&norm.mean));
    let std = g.f32s("norm_std", &[features], per_feature(&norm.std));
    let shifted = g.op("Sub", &[&rows, &mean]);
    let rows = g.op("Div", &[&shifted, &std]);
    let embedding = centred(&m.patch_embed);
    let x = if features * n * d <= DENSE_LIMIT {
        linear(g, &rows, &block_diagonal(m, &embedding), "patch_embed")
    } else {
        // [N, tt, gh, ph, gw, pw, c] → [N, gh, gw, tt, ph, pw, c] → [N · n, patch_dim].
        let (ph, pw) = (c.patch_height, c.patch_width);
        let grid = g.i64s("grid", &[7], [0, tt, h / ph, ph, w / pw, pw, ch].map(|v| v as i64).to_vec());
        let x = g.op("Reshape", &[&rows, &grid]);
        let x = g.node("Transpose", &[&x], vec![ints("perm", &[0, 2, 4, 1, 3, 5, 6])], None);
        let patch_rows = g.i64s("patch_rows", &[2], vec![-1, c.patch_dim() as i64]);
        let x = g.op("Reshape", &[&x, &patch_rows]);
        linear(g, &x, &embedding, "patch_embed")
    };
    let tokens = g.i64s("tokens", &[3], vec![-1, n as i64, d as i64]);
    g.op("Reshape", &[&x, &tokens])
}

/// The embedding `e` of each patch as one layer over a token's whole frame, `[tt·h·w·c]` →
/// `[patches · dim]`: input `(f, y, x, ch)` feeds patch `(y / ph, x / pw)` at its place
/// `(f, y mod ph, x mod pw, ch)` within the patch; every other weight is zero.
fn block_diagonal(m: &BakedPvt3, e: &Dense) -> Dense {
    let c = &m.config;
    let (tt, h, w, ch, d, n) = (c.tubelet, c.height, c.width, c.channels, c.dim, c.num_patches());
    let (ph, pw, gw) = (c.patch_height, c.patch_width, c.width / c.patch_width);
    let inputs = tt * h * w * ch;
    let mut weight = vec![0f32; n * d * inputs];
    for f in 0..tt {
        for y in 0..h {
            for x in 0..w {
                for k in 0..ch {
                    let input = ((f * h + y) * w + x) * ch + k;
                    let patch = (y / ph) * gw + x / pw;
                    let within = ((f * ph + y % ph) * pw + x % pw) * ch + k;
                    for j in 0..d {
                        weight[(patch * d + j) * inputs + input] = e.weight[j * e.cols + within];
                    }
                }
            }
        }
    }
    let bias = e.bias.as_ref().map(|b| (0..n).flat_map(|_| b.iter().copied()).collect());
    Dense { rows: n * d, cols: inputs, weight, bias }
}
