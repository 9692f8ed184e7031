//! The spectral head (`pvt3_models::spectrum` in training, `pvt3_spec::spectrum` for its maths)
//! as ONNX nodes, from the file's input and the key bias: the frames' weights ([`FRAME_WEIGHTS`],
//! the kept tokens the bias has not hidden), each channel's weighted level, normalised (a
//! feature unless `spectral_levels` is off), the Fourier transform of the weighted, detrended
//! frames (the `DFT` op, an FFT in tract and onnxruntime, where the trainer multiplies by the
//! transform's matrix), the band sums of the squared transform over the frames weighed and the
//! channel's variance, their logarithms, and the linear map with the standardisation folded in,
//! named [`SPECTRAL_LOGITS`]. A streaming runtime feeds the temporal stage the window so far
//! along with the bias, and the head reads exactly the frames received.

use pvt3_format::{FRAME_WEIGHTS, INPUT, SPECTRAL_LOGITS, TOKEN_BIAS};
use pvt3_spec::baked::{BakedPvt3, BakedSpectrum, Dense};
use pvt3_spec::normalization::Normalization;
use pvt3_spec::spectrum::{band_matrix, bins, POWER_FLOOR};

use pvt3_format::onnx::{int, Op};

use crate::graph::Graph;
use crate::layers::linear;

mod space;

/// The spectral head's logits `[batch, classes]`, named [`SPECTRAL_LOGITS`].
pub(crate) fn spectral_logits(g: &mut Graph, m: &BakedPvt3, s: &BakedSpectrum, norm: &Normalization) -> String {
    let weighed = frame_weights(g, m);
    let logits = match m.config.spectral_space() {
        true => space::logits(g, m, s, norm, &weighed),
        false => frames_logits(g, m, s, norm, &weighed),
    };
    g.node(Op::Identity, &[&logits], vec![], Some(SPECTRAL_LOGITS))
}

/// The logits of a head over the frames' spectrum: each channel's weighted level and the log
/// band powers of its weighted, detrended frames (`weighed`: the weights' sum).
fn frames_logits(g: &mut Graph, m: &BakedPvt3, s: &BakedSpectrum, norm: &Normalization, weighed: &str) -> String {
    let c = &m.config;
    let (channels, frames) = (c.sensor_channels(), c.frames);
    // Every operand of the element-wise ops below is [channels, frames] or [b, channels, 1]: tract
    // runs those in one pass, where a [channels, 1] or [frames] operand broadcast over the other
    // axis takes 10–20 µs an op on BioTac's window (measured with bench/tools' profile).
    // The frames are centred on the training mean, not divided by σ: ((x − μ) minus its weighted
    // level) / σ is the normalised frames' detrended signal, so the level alone is divided by σ
    // and the band powers by σ² once summed, an element-wise op on the window spared. (Centring
    // on the touch's own level alone would lose the f32 digits of a channel's large mean.)
    let rows = g.i64s("spectral_rows", &[3], vec![-1, channels as i64, frames as i64]);
    let x = g.op(Op::Reshape, &[INPUT, &rows]);
    let plane = g.i64s("spectral_plane", &[3], vec![1, channels as i64, frames as i64]);
    let mean = g.f32s("spectral_norm_mean", &[channels, 1], norm.mean.clone());
    let mean = g.op(Op::Expand, &[&mean, &plane]);
    let weights = g.op(Op::Expand, &[FRAME_WEIGHTS, &plane]);
    let x = g.op(Op::Sub, &[&x, &mean]);
    // The weighted sum as a product with the weights' column: a fifth of a ReduceSum's time.
    let column = g.i64s("frames_column", &[2], vec![frames as i64, 1]);
    let column = g.op(Op::Reshape, &[FRAME_WEIGHTS, &column]);
    let level = g.op(Op::MatMul, &[&x, &column]);
    let level = g.op(Op::Div, &[&level, weighed]);
    let centred = g.op(Op::Sub, &[&x, &level]);
    let centred = g.op(Op::Mul, &[&centred, &weights]);
    let level = if c.spectral_levels() {
        let std = g.f32s("spectral_norm_std", &[channels, 1], norm.std.clone());
        g.op(Op::Div, &[&level, &std])
    } else {
        level
    };
    let power = band_powers(g, m, norm, &centred, weighed);
    let log_power = log(g, &power);
    logits_of(g, m, s, &level, &log_power, &[])
}

/// The band powers `[b, channels, bands]` of the weighted, detrended frames `centred`
/// `[b, channels, frames]`, in the normalised frames' units and per unit of weight (`weighed`).
fn band_powers(g: &mut Graph, m: &BakedPvt3, norm: &Normalization, centred: &str, weighed: &str) -> String {
    let c = &m.config;
    let (channels, frames, bands) = (c.sensor_channels(), c.frames, c.spectral_bands());
    let k = bins(frames);
    // A real signal for the DFT op: [b, channels, frames, 1] → [b, channels, frames, 2].
    let real = g.i64s("spectral_real", &[4], vec![-1, channels as i64, frames as i64, 1]);
    let centred = g.op(Op::Reshape, &[centred, &real]);
    let transform = g.node(Op::Dft, &[&centred], vec![int("axis", 2)], None);
    let (start, end, axis) = (g.i64s("zero", &[1], vec![0]), g.i64s("bins", &[1], vec![k as i64]), g.i64s("two", &[1], vec![2]));
    let one_sided = g.op(Op::Slice, &[&transform, &start, &end, &axis]);
    let squares = g.op(Op::Mul, &[&one_sided, &one_sided]);
    let parts = g.i64s("spectral_parts", &[3], vec![-1, channels as i64, 2 * k as i64]);
    let squares = g.op(Op::Reshape, &[&squares, &parts]);
    // Band sums of re² + im² (rows interleaved per frequency here). The op's transform has no
    // 1/√T, so the power (T / N) · |X|² of the trainer's scaled transform is |DFT|² / N.
    let sums = band_matrix(frames, bands);
    let interleaved: Vec<f32> = (0..k)
        .flat_map(|f| [f, k + f])
        .flat_map(|row| sums[row * bands..(row + 1) * bands].iter().map(|v| *v as f32).collect::<Vec<_>>())
        .collect();
    let sums = g.f32s("spectral_bands", &[2 * k, bands], interleaved);
    let power = g.op(Op::MatMul, &[&squares, &sums]);
    let variance: Vec<f32> = norm.std.iter().flat_map(|s| std::iter::repeat_n(s * s, bands)).collect();
    let variance = g.f32s("spectral_norm_variance", &[channels, bands], variance);
    let power = g.op(Op::Div, &[&power, &variance]);
    g.op(Op::Div, &[&power, weighed])
}

/// The logits of per-channel `level`s `[b, channels, 1]` and band powers' logarithms
/// `log_power` `[b, channels, bands]` ([`log`]): the logarithms after the levels unless they are
/// off, then what a head over the image's space reads `after` them (`[b, channels, …]`: its
/// histograms and pixels), then the linear map with the standardisation folded in.
fn logits_of(g: &mut Graph, m: &BakedPvt3, s: &BakedSpectrum, level: &str, log_power: &str, after: &[String]) -> String {
    let c = &m.config;
    let mut parts: Vec<&str> = Vec::with_capacity(2 + after.len());
    if c.spectral_levels() {
        parts.push(level);
    }
    parts.push(log_power);
    parts.extend(after.iter().map(String::as_str));
    let features = match parts.len() {
        1 => log_power.to_string(),
        _ => g.node(Op::Concat, &parts, vec![int("axis", 2)], None),
    };
    let flat = g.i64s("spectral_features", &[2], vec![-1, c.spectral_features() as i64]);
    let features = g.op(Op::Reshape, &[&features, &flat]);
    linear(g, &features, &standardised(s), "spectral_linear")
}

/// The logarithm of `power`, `POWER_FLOOR` added so that a silent band is finite.
fn log(g: &mut Graph, power: &str) -> String {
    let floor = g.f32s("power_floor", &[1], vec![POWER_FLOOR as f32]);
    let power = g.op(Op::Add, &[power, &floor]);
    g.op(Op::Log, &[&power])
}

/// The head's linear map with the standardisation folded in, one op instead of three:
/// `W (f · scale + shift) + b` is `(W · diag(scale)) f + (W shift + b)`, summed in f64.
fn standardised(s: &BakedSpectrum) -> Dense {
    let l = &s.linear;
    let weight = l.weight.chunks(l.cols).flat_map(|row| row.iter().zip(&s.scale).map(|(w, k)| w * k)).collect();
    let bias = l
        .weight
        .chunks(l.cols)
        .enumerate()
        .map(|(r, row)| {
            let b = l.bias.as_ref().map_or(0.0, |b| b[r] as f64);
            (b + row.iter().zip(&s.shift).map(|(w, v)| *w as f64 * *v as f64).sum::<f64>()) as f32
        })
        .collect();
    Dense { weight, bias: Some(bias), ..l.clone() }
}

/// Writes [`FRAME_WEIGHTS`] `[frames]` from the key bias: max(bias + 1, 0) is 1 where the bias is
/// 0 and 0 where it is −∞, times 1 for a kept token, each token's weight repeated over its
/// frames. Returns `N`, the frames weighed, at least 1 (`pvt3_spec::spectrum::weighed_frames`).
fn frame_weights(g: &mut Graph, m: &BakedPvt3) -> String {
    let c = &m.config;
    let (t, tt) = (c.time_tokens(), c.tubelet);
    let bias = g.i64s("spectral_bias_rows", &[1], vec![-1]);
    let bias = g.op(Op::Reshape, &[TOKEN_BIAS, &bias]);
    let (from, to, axis) = (g.i64s("one", &[1], vec![1]), g.i64s("tokens_end", &[1], vec![t as i64 + 1]), g.i64s("axis0", &[1], vec![0]));
    let bias = g.op(Op::Slice, &[&bias, &from, &to, &axis]);
    let one = g.f32s("one", &[1], vec![1.0]);
    let zero = g.f32s("zero", &[1], vec![0.0]);
    let received = g.op(Op::Add, &[&bias, &one]);
    let received = g.op(Op::Max, &[&received, &zero]);
    let kept = g.f32s("kept_token_weights", &[t], (0..t).map(|k| if m.kept_tokens.contains(&k) { 1.0 } else { 0.0 }).collect());
    let weights = g.op(Op::Mul, &[&received, &kept]);
    let column = g.i64s("token_column", &[2], vec![t as i64, 1]);
    let weights = g.op(Op::Reshape, &[&weights, &column]);
    let per_frame = g.i64s("token_frames_shape", &[2], vec![t as i64, tt as i64]);
    let weights = g.op(Op::Expand, &[&weights, &per_frame]);
    let flat_frames = g.i64s("frames_shape", &[1], vec![c.frames as i64]);
    g.node(Op::Reshape, &[&weights, &flat_frames], vec![], Some(FRAME_WEIGHTS));
    let weighed = g.node(Op::ReduceSum, &[FRAME_WEIGHTS, &axis], vec![int("keepdims", 1)], None);
    g.op(Op::Max, &[&weighed, &one])
}
