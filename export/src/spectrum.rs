//! The spectral head (`pvt3_models::spectrum` in training, `pvt3_spec::spectrum` for its band maths) as ONNX nodes, from the file's input: each
//! channel's frames normalised, its level, the Fourier transform of the detrended frames (the
//! `DFT` op, an FFT in tract and onnxruntime, where the trainer multiplies by the transform's
//! matrix), the band sums of the squared transform, their logarithms, the standardisation and
//! the linear map. Its output, logits, is named [`SPECTRAL_LOGITS`]: the seam by which a
//! streaming runtime knows the model needs the whole window.

use pvt3_format::{INPUT, SPECTRAL_LOGITS};
use pvt3_spec::baked::{BakedPvt3, BakedSpectrum};
use pvt3_spec::normalization::Normalization;
use pvt3_spec::spectrum::{band_matrix, bins, POWER_FLOOR};

use pvt3_format::onnx::{int, ints, Op};

use crate::graph::Graph;
use crate::layers::linear;

/// The spectral head's logits `[batch, classes]`, named [`SPECTRAL_LOGITS`].
pub(crate) fn spectral_logits(g: &mut Graph, m: &BakedPvt3, s: &BakedSpectrum, norm: &Normalization) -> String {
    let c = &m.config;
    let (channels, frames, bands) = (c.sensor_channels(), c.frames, c.spectral_bands());
    let k = bins(frames);
    let rows = g.i64s("spectral_rows", &[3], vec![-1, channels as i64, frames as i64]);
    let x = g.op(Op::Reshape, &[INPUT, &rows]);
    let mean = g.f32s("spectral_norm_mean", &[channels, 1], norm.mean.clone());
    let std = g.f32s("spectral_norm_std", &[channels, 1], norm.std.clone());
    let x = g.op(Op::Sub, &[&x, &mean]);
    let x = g.op(Op::Div, &[&x, &std]);
    let level = g.node(Op::ReduceMean, &[&x], vec![ints("axes", &[2]), int("keepdims", 1)], None);
    let centred = g.op(Op::Sub, &[&x, &level]);
    // A real signal for the DFT op: [b, channels, frames, 1] → [b, channels, frames, 2].
    let real = g.i64s("spectral_real", &[4], vec![-1, channels as i64, frames as i64, 1]);
    let centred = g.op(Op::Reshape, &[&centred, &real]);
    let transform = g.node(Op::Dft, &[&centred], vec![int("axis", 2)], None);
    let (start, end, axis) = (g.i64s("zero", &[1], vec![0]), g.i64s("bins", &[1], vec![k as i64]), g.i64s("two", &[1], vec![2]));
    let one_sided = g.op(Op::Slice, &[&transform, &start, &end, &axis]);
    let squares = g.op(Op::Mul, &[&one_sided, &one_sided]);
    let parts = g.i64s("spectral_parts", &[3], vec![-1, channels as i64, 2 * k as i64]);
    let squares = g.op(Op::Reshape, &[&squares, &parts]);
    // Band sums of re² + im² (rows interleaved per frequency here), with the trainer's 1/frames.
    let sums = band_matrix(frames, bands);
    let interleaved: Vec<f32> = (0..k)
        .flat_map(|f| [f, k + f])
        .flat_map(|row| sums[row * bands..(row + 1) * bands].iter().map(|v| (*v / frames as f64) as f32).collect::<Vec<_>>())
        .collect();
    let sums = g.f32s("spectral_bands", &[2 * k, bands], interleaved);
    let power = g.op(Op::MatMul, &[&squares, &sums]);
    let floor = g.f32s("power_floor", &[1], vec![POWER_FLOOR as f32]);
    let power = g.op(Op::Add, &[&power, &floor]);
    let log_power = g.op(Op::Log, &[&power]);
    let features = g.node(Op::Concat, &[&level, &log_power], vec![int("axis", 2)], None);
    let flat = g.i64s("spectral_features", &[2], vec![-1, c.spectral_features() as i64]);
    let features = g.op(Op::Reshape, &[&features, &flat]);
    let scale = g.f32s("spectral_scale", &[s.scale.len()], s.scale.clone());
    let shift = g.f32s("spectral_shift", &[s.shift.len()], s.shift.clone());
    let features = g.op(Op::Mul, &[&features, &scale]);
    let features = g.op(Op::Add, &[&features, &shift]);
    let logits = linear(g, &features, &s.linear, "spectral_linear");
    g.node(Op::Identity, &[&logits], vec![], Some(SPECTRAL_LOGITS))
}
