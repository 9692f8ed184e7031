//! The spectral head over an image's space (`pvt3_spec::spectrum::space`) as ONNX nodes: the
//! frames normalised, each colour of each frame transformed by products with the width's and the
//! height's `[cos | sin]` matrices (plain `MatMul`s: the two-dimensional transform of a small
//! frame, in tract and onnxruntime alike), the powers `(CC − SS)² + (CS + SC)²` of its four
//! blocks summed into rings, each colour's level beside them and its histograms after them, of its
//! values and, with `spectral_gradients`, of the differences between neighbours across and down
//! (`Slice`s and a `Sub`): each value's share above each interior edge, a clamp built of `Max`es,
//! then the bins' differences;
//! each colour's normalised pixels after them with `spectral_pixels`;
//! all weighed over the frames received ([`FRAME_WEIGHTS`]) as the temporal head weighs them, the
//! logarithms of the powers (each frame's, before the weighing, with `spectral_log_frames`), and
//! the linear map with the standardisation folded in. Where the patch mask pruned patches, the
//! head reads the kept patches' pixels alone and the others as 0 ([`read_kept_pixels`]). Every
//! frame is a row from the cut [`HEAD_FRAMES`] to each frame's features [`HEAD_FEATURES`], so
//! that a streaming runtime computes a frame's features as it arrives and an answer reads only
//! them.

use pvt3_format::onnx::{int, ints, Op};
use pvt3_format::{FRAME_WEIGHTS, HEAD_FEATURES, HEAD_FRAMES, INPUT};
use pvt3_spec::baked::{BakedPvt3, BakedSpectrum};
use pvt3_spec::normalization::Normalization;
use pvt3_spec::spectrum::space;
use pvt3_spec::Config;

use crate::graph::Graph;

/// The head's logits `[batch, classes]`; `weighed` is the frames weighed, `[1]`.
pub(super) fn logits(g: &mut Graph, m: &BakedPvt3, s: &BakedSpectrum, norm: &Normalization, weighed: &str) -> String {
    let c = &m.config;
    let (colours, frames, bands, bins, pixels) =
        (c.channels, c.frames, c.spectral_bands(), c.spectral_histogram_bins(), c.spectral_pixel_count());
    let per_frame = per_frame(g, m, norm);
    // Levels, rings, histograms and pixels [b, frames, colours · (1 + bands + bins + pixels)],
    // weighed over the frames (`bins` those of every histogram).
    let each = 1 + bands + bins + pixels;
    let shape = g.i64s("space_per_frame", &[3], vec![-1, frames as i64, (colours * each) as i64]);
    let joined = g.op(Op::Reshape, &[&per_frame, &shape]);
    let joined = g.node(Op::Transpose, &[&joined], vec![ints("perm", &[0, 2, 1])], None);
    let column = g.i64s("space_frames_column", &[2], vec![frames as i64, 1]);
    let column = g.op(Op::Reshape, &[FRAME_WEIGHTS, &column]);
    let weighted = g.op(Op::MatMul, &[&joined, &column]);
    let weighted = g.op(Op::Div, &[&weighted, weighed]);
    let per_colour = g.i64s("space_per_colour", &[3], vec![-1, colours as i64, each as i64]);
    let weighted = g.op(Op::Reshape, &[&weighted, &per_colour]);
    let axis = g.i64s("space_feature_axis", &[1], vec![2]);
    let (zero, one, end) =
        (g.i64s("space_zero", &[1], vec![0]), g.i64s("space_one", &[1], vec![1]), g.i64s("space_end", &[1], vec![1 + bands as i64]));
    let level = g.op(Op::Slice, &[&weighted, &zero, &one, &axis]);
    let power = g.op(Op::Slice, &[&weighted, &one, &end, &axis]);
    // The histograms' bins, then the pixels, where the head has them.
    let (mut after, mut start, mut offset) = (Vec::with_capacity(2), end, 1 + bands);
    for (name, n) in [("space_histogram_end", bins), ("space_pixels_end", pixels)].into_iter().filter(|(_, n)| *n > 0) {
        offset += n;
        let last = g.i64s(name, &[1], vec![offset as i64]);
        after.push(g.op(Op::Slice, &[&weighted, &start, &last, &axis]));
        start = last;
    }
    // With `spectral_log_frames`, each frame's powers were taken the logarithm of already.
    let log_power = if c.spectral_log_frames() { power } else { super::log(g, &power) };
    super::logits_of(g, m, s, &level, &log_power, &after)
}

/// The frames [`HEAD_FRAMES`] `[n, h, w, colours]` normalised pixel by pixel, a pruned patch's
/// pixels at 0, read from the kept pixels alone ([`read_kept_pixels`]).
fn normalised(g: &mut Graph, m: &BakedPvt3, norm: &Normalization) -> String {
    let c = &m.config;
    let (h, w, colours) = (c.height, c.width, c.channels);
    let kept = (m.kept_patches.len() < c.num_patches()).then(|| space::kept_pixels(c, &m.kept_patches));
    let x = match &kept {
        Some(kept) => read_kept_pixels(g, c, kept),
        None => HEAD_FRAMES.to_string(),
    };
    let mean = g.f32s("space_norm_mean", &[h, w, colours], norm.mean.clone());
    let std = g.f32s("space_norm_std", &[h, w, colours], norm.std.clone());
    let x = g.op(Op::Sub, &[&x, &mean]);
    let x = g.op(Op::Div, &[&x, &std]);
    let Some(kept) = kept else { return x };
    let read = kept.iter().flat_map(|k| std::iter::repeat_n(f32::from(*k), colours)).collect();
    let read = g.f32s("space_kept_pixels", &[h, w, colours], read);
    g.op(Op::Mul, &[&x, &read])
}

/// The frames [`HEAD_FRAMES`] `[n, h, w, colours]` as the head reads them where patches were
/// pruned: one `Gather` takes each kept pixel's values and, in a pruned pixel's place, those of
/// the frame's first kept pixel, which the head then multiplies by 0. No op reads a pruned
/// patch's pixels.
fn read_kept_pixels(g: &mut Graph, c: &Config, kept: &[bool]) -> String {
    let (h, w, colours) = (c.height, c.width, c.channels);
    let first = kept.iter().position(|k| *k).expect("a baked model keeps a patch");
    let index = (0..h * w).flat_map(|p| (0..colours).map(move |k| (if kept[p] { p } else { first } * colours + k) as i64)).collect();
    let index = g.i64s("space_kept_pixel_values", &[h * w * colours], index);
    let flat = g.i64s("space_frame_values", &[2], vec![-1, (h * w * colours) as i64]);
    let x = g.op(Op::Reshape, &[HEAD_FRAMES, &flat]);
    let x = g.node(Op::Gather, &[&x, &index], vec![int("axis", 1)], None);
    let frame = g.i64s("space_frame_pixels", &[4], vec![-1, h as i64, w as i64, colours as i64]);
    g.op(Op::Reshape, &[&x, &frame])
}

/// Each colour's histograms of every frame `[n, colours, kinds · bins]`
/// (`Config::spectral_histograms`), from its normalised frames `x` `[n, colours, h, w]` and their
/// pixels `flat` `[n, colours, h · w]`: the values' and the differences
/// between neighbours across and down, each a [`histogram`].
fn histograms(g: &mut Graph, c: &Config, x: &str, flat: &str) -> String {
    let (h, w) = (c.height, c.width);
    let difference = |g: &mut Graph, axis: usize, n: usize| {
        let axis = g.i64s("space_gradient_axis", &[1], vec![axis as i64]);
        let (zero, one) = (g.i64s("space_gradient_zero", &[1], vec![0]), g.i64s("space_gradient_one", &[1], vec![1]));
        let (short, long) = (g.i64s("space_gradient_short", &[1], vec![n as i64 - 1]), g.i64s("space_gradient_long", &[1], vec![n as i64]));
        let after = g.op(Op::Slice, &[x, &one, &long, &axis]);
        let before = g.op(Op::Slice, &[x, &zero, &short, &axis]);
        g.op(Op::Sub, &[&after, &before])
    };
    let each: Vec<String> = c
        .spectral_histograms()
        .iter()
        .map(|kind| {
            let values = match kind {
                space::Histogram::Values => flat.to_string(),
                space::Histogram::Across => difference(g, 3, w),
                space::Histogram::Down => difference(g, 2, h),
            };
            histogram(g, c, &values, kind.values(h, w))
        })
        .collect();
    match each.as_slice() {
        [one] => one.clone(),
        _ => g.node(Op::Concat, &each.iter().map(String::as_str).collect::<Vec<_>>(), vec![int("axis", 2)], None),
    }
}

/// Each colour's histogram of every frame `[n, colours, bins]` from `n` normalised values of
/// each, `[n, colours, …]`: each value's share above each interior edge,
/// `clamp(z, 0, 1)` of `z = (v − e) / Δ + ½` as `max(−max(−z, −1), 0)` (exact in f32, where
/// `max(z, 0) − max(z − 1, 0)` would round), its sum over the pixels (a `ReduceSum`: a product
/// with a column packs the shares first: 1.4 to 2.2 times the sum's time in tract), then the
/// bins' differences, divided by the pixels' count.
fn histogram(g: &mut Graph, c: &Config, pixels: &str, n: usize) -> String {
    let (colours, bins) = (c.channels, c.spectral_histogram());
    let (edges, width) = (space::histogram_edges(bins), space::histogram_width(bins));
    let shape = g.i64s("space_histogram_pixels", &[4], vec![-1, colours as i64, 1, n as i64]);
    let v = g.op(Op::Reshape, &[pixels, &shape]);
    let minus_scale = g.f32s("space_histogram_minus_scale", &[1], vec![(-1.0 / width) as f32]);
    let v = g.op(Op::Mul, &[&v, &minus_scale]);
    // −z for every edge: [n, colours, edges, values].
    let offsets = g.f32s("space_histogram_offsets", &[bins - 1, 1], edges.iter().map(|e| (e / width - 0.5) as f32).collect());
    let minus_z = g.op(Op::Add, &[&v, &offsets]);
    let (minus_one, zero) = (g.f32s("space_histogram_minus_one", &[1], vec![-1.0]), g.f32s("space_histogram_zero", &[1], vec![0.0]));
    let below_one = g.op(Op::Max, &[&minus_z, &minus_one]);
    let below_one = g.op(Op::Sub, &[&zero, &below_one]);
    let share = g.op(Op::Max, &[&below_one, &zero]);
    let last = g.i64s("space_histogram_pixel_axis", &[1], vec![-1]);
    let above = g.node(Op::ReduceSum, &[&share, &last], vec![int("keepdims", 1)], None);
    let per_edge = g.i64s("space_histogram_edges", &[3], vec![-1, colours as i64, bins as i64 - 1]);
    let above = g.op(Op::Reshape, &[&above, &per_edge]);
    let (d, first) = space::histogram_matrix(bins);
    let d = g.f32s("space_histogram_differences", &[bins - 1, bins], d.iter().map(|v| (v / n as f64) as f32).collect());
    let first = g.f32s("space_histogram_first", &[bins], first.iter().map(|v| *v as f32).collect());
    let histogram = g.op(Op::MatMul, &[&above, &d]);
    g.op(Op::Add, &[&histogram, &first])
}

/// Each colour's level, ring powers (their logarithms, with `spectral_log_frames`), histograms
/// and pixels (with `spectral_pixels`) of every frame, [`HEAD_FEATURES`] `[b · frames, colours,
/// 1 + bands + bins + pixels]`, from
/// the file's input cut into frames ([`HEAD_FRAMES`]), [`normalised`]: every op after the cut
/// reads one frame's row alone, so that a streaming runtime runs them on each frame as it
/// arrives.
fn per_frame(g: &mut Graph, m: &BakedPvt3, norm: &Normalization) -> String {
    let c = &m.config;
    let (h, w, colours, frames, bands) = (c.height, c.width, c.channels, c.frames, c.spectral_bands());
    let k = space::width_bins(w);
    let dims = |v: &[usize]| v.iter().map(|d| *d as i64).collect::<Vec<_>>();
    let shape = g.i64s("space_window", &[5], [vec![-1], dims(&[h, w, colours, frames])].concat());
    let x = g.op(Op::Reshape, &[INPUT, &shape]);
    let x = g.node(Op::Transpose, &[&x], vec![ints("perm", &[0, 4, 1, 2, 3])], None);
    let rows = g.i64s("space_frame_rows", &[4], [vec![-1], dims(&[h, w, colours])].concat());
    g.node(Op::Reshape, &[&x, &rows], vec![], Some(HEAD_FRAMES));
    let x = normalised(g, m, norm);
    // [n, colours, h, w]: a frame's colour is one matrix.
    let x = g.node(Op::Transpose, &[&x], vec![ints("perm", &[0, 3, 1, 2])], None);
    let pixels = g.i64s("space_pixels", &[3], [vec![-1], dims(&[colours, h * w])].concat());
    let flat = g.op(Op::Reshape, &[&x, &pixels]);
    let mean_column = g.f32s("space_mean_column", &[h * w, 1], vec![1.0 / (h * w) as f32; h * w]);
    let level = g.op(Op::MatMul, &[&flat, &mean_column]);
    let across = g.f32s("space_width_dft", &[w, 2 * k], space::cos_sin_matrix(w, k).iter().map(|v| *v as f32).collect());
    let rows = g.op(Op::MatMul, &[&x, &across]);
    let rows = g.node(Op::Transpose, &[&rows], vec![ints("perm", &[0, 1, 3, 2])], None);
    let down = g.f32s("space_height_dft", &[h, 2 * h], space::cos_sin_matrix(h, h).iter().map(|v| *v as f32).collect());
    let z = g.op(Op::MatMul, &[&rows, &down]);
    // The four blocks [kx, ky] of the products: cos or sin across, cos or sin down.
    let axes = g.i64s("space_block_axes", &[2], vec![2, 3]);
    let block = |g: &mut Graph, i: usize, j: usize| {
        let start = g.i64s(&format!("space_block_{i}{j}_start"), &[2], dims(&[i * k, j * h]));
        let end = g.i64s(&format!("space_block_{i}{j}_end"), &[2], dims(&[(i + 1) * k, (j + 1) * h]));
        g.op(Op::Slice, &[&z, &start, &end, &axes])
    };
    let (cc, cs, sc, ss) = (block(g, 0, 0), block(g, 0, 1), block(g, 1, 0), block(g, 1, 1));
    let real = g.op(Op::Sub, &[&cc, &ss]);
    let imaginary = g.op(Op::Add, &[&cs, &sc]);
    let real = g.op(Op::Mul, &[&real, &real]);
    let imaginary = g.op(Op::Mul, &[&imaginary, &imaginary]);
    let power = g.op(Op::Add, &[&real, &imaginary]);
    let bins = g.i64s("space_bins", &[3], [vec![-1], dims(&[colours, k * h])].concat());
    let power = g.op(Op::Reshape, &[&power, &bins]);
    let rings = space::ring_means(h, w, bands).expect("a validated configuration").iter().map(|v| *v as f32).collect();
    let rings = g.f32s("space_rings", &[k * h, bands], rings);
    let power = g.op(Op::MatMul, &[&power, &rings]);
    let power = if c.spectral_log_frames() { super::log(g, &power) } else { power };
    let mut parts = vec![level, power];
    if c.spectral_histogram() > 0 {
        parts.push(histograms(g, c, &x, &flat));
    }
    if c.spectral_pixels() {
        parts.push(flat);
    }
    g.node(Op::Concat, &parts.iter().map(String::as_str).collect::<Vec<_>>(), vec![int("axis", 2)], Some(HEAD_FEATURES))
}
