//! A plain-Rust f64 forward of a [`BakedPvt3`]: the numerical yardstick every other form of the
//! model (candle, ONNX in tract and in onnxruntime) is compared with. Written for clarity, not
//! speed: loops over tokens and channels, no candle.

use crate::baked::{BakedAttention, BakedFeedForward, BakedPvt3, BakedSpectrum, BakedTransformer, Dense, Norm};
use crate::spectrum;
use crate::{Error, Result};

fn dense(l: &Dense, x: &[f64]) -> Vec<f64> {
    (0..l.rows)
        .map(|r| {
            let w = &l.weight[r * l.cols..(r + 1) * l.cols];
            let dot: f64 = w.iter().zip(x).map(|(w, x)| *w as f64 * x).sum();
            dot + l.bias.as_ref().map_or(0.0, |b| b[r] as f64)
        })
        .collect()
}

fn layer_norm(n: &Norm, x: &[f64], eps: f64) -> Vec<f64> {
    let len = x.len() as f64;
    let mean = x.iter().sum::<f64>() / len;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / len;
    let inv = 1.0 / (var + eps).sqrt();
    x.iter().enumerate().map(|(i, v)| (v - mean) * inv * n.weight[i] as f64 + n.bias[i] as f64).collect()
}

fn gelu(x: f64) -> f64 {
    0.5 * x * (1.0 + libm::erf(x / std::f64::consts::SQRT_2))
}

/// Self-attention over `rows` (each already normalised).
fn attention(a: &BakedAttention, rows: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let q: Vec<Vec<f64>> = rows.iter().map(|r| dense(&a.q, r)).collect();
    let k: Vec<Vec<f64>> = rows.iter().map(|r| dense(&a.k, r)).collect();
    let v: Vec<Vec<f64>> = rows.iter().map(|r| dense(&a.v, r)).collect();
    let (hd, scale) = (a.head_dim, a.scale as f64);
    let mut mixed = vec![vec![0.0; a.heads * hd]; rows.len()];
    for h in 0..a.heads {
        let ch = h * hd..(h + 1) * hd;
        for (i, qi) in q.iter().enumerate() {
            let scores: Vec<f64> = k.iter().map(|kj| ch.clone().map(|c| qi[c] * kj[c]).sum::<f64>() * scale).collect();
            let max = scores.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let exp: Vec<f64> = scores.iter().map(|s| (s - max).exp()).collect();
            let total: f64 = exp.iter().sum();
            for (j, e) in exp.iter().enumerate() {
                for c in ch.clone() {
                    mixed[i][c] += e / total * v[j][c];
                }
            }
        }
    }
    mixed.iter().map(|m| dense(&a.out, m)).collect()
}

fn feed_forward(f: &BakedFeedForward, x: &[f64]) -> Vec<f64> {
    let hidden: Vec<f64> = dense(&f.fc1, x).into_iter().map(gelu).collect();
    dense(&f.fc2, &hidden)
}

/// Runs a transformer over `tokens` (`len` rows of `dim`) and returns its normalised first token.
pub fn transformer_cls(t: &BakedTransformer, tokens: &[f64], len: usize, dim: usize, eps: f64) -> Vec<f64> {
    let mut x: Vec<Vec<f64>> = (0..len).map(|i| tokens[i * dim..(i + 1) * dim].to_vec()).collect();
    for b in &t.layers {
        let normed: Vec<Vec<f64>> = x.iter().map(|r| layer_norm(&b.attn_norm, r, eps)).collect();
        for (r, a) in x.iter_mut().zip(attention(&b.attn, &normed)) {
            r.iter_mut().zip(a).for_each(|(v, a)| *v += a);
        }
        for r in x.iter_mut() {
            let f = feed_forward(&b.ffn, &layer_norm(&b.ffn_norm, r, eps));
            r.iter_mut().zip(f).for_each(|(v, f)| *v += f);
        }
    }
    layer_norm(&t.norm, &x[0], eps)
}

/// Patch vectors of temporal token `k` of one raw sample (`[h, w, (c,) t]`), of the kept patches.
fn patches(m: &BakedPvt3, sample: &[f32], k: usize) -> Vec<Vec<f64>> {
    let c = &m.config;
    let (gw, frames) = (c.width / c.patch_width, c.frames);
    m.kept_patches
        .iter()
        .map(|&p| {
            let (pr, pc) = (p / gw, p % gw);
            let mut v = Vec::with_capacity(c.patch_dim());
            for dt in 0..c.tubelet {
                for dy in 0..c.patch_height {
                    for dx in 0..c.patch_width {
                        for ci in 0..c.channels {
                            let (y, x) = (pr * c.patch_height + dy, pc * c.patch_width + dx);
                            let t = k * c.tubelet + dt;
                            v.push(sample[((y * c.width + x) * c.channels + ci) * frames + t] as f64);
                        }
                    }
                }
            }
            v
        })
        .collect()
}

/// The spectral head's logits for one sample from the frames of its first `tokens` temporal
/// tokens that the model keeps: per channel, the level (unless off) and the log band powers of the detrended
/// frames by the transform's definition (`spectrum`'s docs), standardised, then the linear map.
fn spectral_logits(m: &BakedPvt3, s: &BakedSpectrum, sample: &[f32], tokens: usize) -> Vec<f64> {
    let c = &m.config;
    let (frames, bands) = (c.frames, c.spectral_bands());
    let weights = spectrum::frame_weights(frames, c.tubelet, tokens, |t| m.kept_tokens.contains(&t));
    let weighed = spectrum::weighed_frames(&weights);
    if c.spectral_space() {
        let standard: Vec<f64> = space_features(m, sample, &weights, weighed)
            .iter()
            .enumerate()
            .map(|(i, v)| v * s.scale[i] as f64 + s.shift[i] as f64)
            .collect();
        return dense(&s.linear, &standard);
    }
    // Over each channel's frames (a head over an image's space reads no frequencies of frames).
    let (k, dft, band) = (spectrum::bins(frames), spectrum::dft_matrix(frames), spectrum::band_matrix(frames, bands));
    let mut features = Vec::with_capacity(s.scale.len());
    for row in sample.chunks(frames) {
        let level = row.iter().zip(&weights).map(|(v, w)| *v as f64 * w).sum::<f64>() / weighed;
        let parts: Vec<f64> = (0..2 * k)
            .map(|f| row.iter().zip(&weights).enumerate().map(|(n, (v, w))| w * (*v as f64 - level) * dft[n * 2 * k + f]).sum())
            .collect();
        if c.spectral_levels() {
            features.push(level);
        }
        features.extend((0..bands).map(|j| {
            let power: f64 = parts.iter().enumerate().map(|(f, p)| p * p * band[f * bands + j]).sum();
            (power * frames as f64 / weighed + spectrum::POWER_FLOOR).ln()
        }));
    }
    let standard: Vec<f64> = features.iter().enumerate().map(|(i, v)| v * s.scale[i] as f64 + s.shift[i] as f64).collect();
    dense(&s.linear, &standard)
}

/// The features of a spectral head over the image's space, by `spectrum::space`'s definition:
/// per colour, its weighted mean level (unless off), then the log of each ring's weighted mean
/// power (with `spectral_log_frames`, the weighted mean of each frame's log), the transform
/// summed term by term, then each bin's weighted mean share of the pixels (and of the gradients
/// across and down, with `spectral_gradients`), then (with `spectral_pixels`) each pixel's
/// weighted mean; a pruned patch's pixels read as 0
/// (`spectrum::space::kept_pixels`).
fn space_features(m: &BakedPvt3, sample: &[f32], weights: &[f64], weighed: f64) -> Vec<f64> {
    let c = &m.config;
    let (h, w, colours, frames, bands) = (c.height, c.width, c.channels, c.frames, c.spectral_bands());
    let bins = c.spectral_histogram();
    let (edges, width) = (spectrum::space::histogram_edges(bins), spectrum::space::histogram_width(bins));
    // Bin j's share of a value: its share above the bin's lower edge less that above its upper.
    let share = |v: f64, j: usize| -> f64 {
        let lower = if j == 0 { 1.0 } else { spectrum::space::share_above(v, edges[j - 1], width) };
        let upper = if j + 1 == bins { 0.0 } else { spectrum::space::share_above(v, edges[j], width) };
        lower - upper
    };
    let of = spectrum::space::band_of(h, w, bands).expect("a validated configuration");
    let sizes = spectrum::space::band_sizes(&of, bands);
    let log_frames = c.spectral_log_frames();
    let kept = spectrum::space::kept_pixels(c, &m.kept_patches);
    let mut features = Vec::with_capacity(c.spectral_features());
    for ci in 0..colours {
        let kinds = c.spectral_histograms();
        let (mut level, mut power, mut histogram) = (0.0, vec![0.0; bands], vec![0.0; kinds.len() * bins]);
        let mut pixel_sums = vec![0.0; c.spectral_pixel_count()];
        for (t, wt) in weights.iter().enumerate().filter(|(_, wt)| **wt != 0.0) {
            let v = |y: usize, x: usize| if kept[y * w + x] { sample[((y * w + x) * colours + ci) * frames + t] as f64 } else { 0.0 };
            let pixels = || (0..h).flat_map(|y| (0..w).map(move |x| (y, x))).map(|(y, x)| v(y, x));
            level += wt * pixels().sum::<f64>() / (h * w) as f64;
            for (sum, p) in pixel_sums.iter_mut().zip(pixels()) {
                *sum += wt * p;
            }
            for (kind, of_kind) in kinds.iter().zip(histogram.chunks_mut(bins.max(1))) {
                let (rows, columns) = kind.shape(h, w);
                let values = || (0..rows).flat_map(|y| (0..columns).map(move |x| (y, x))).map(|(y, x)| kind.at(v, y, x));
                for (j, bin) in of_kind.iter_mut().enumerate() {
                    *bin += wt * values().map(|p| share(p, j)).sum::<f64>() / (rows * columns) as f64;
                }
            }
            for (sum, p) in power.iter_mut().zip(ring_powers(v, (h, w), &of, &sizes)) {
                *sum += wt * if log_frames { (p + spectrum::POWER_FLOOR).ln() } else { p };
            }
        }
        if c.spectral_levels() {
            features.push(level / weighed);
        }
        features.extend(power.iter().map(|p| if log_frames { p / weighed } else { (p / weighed + spectrum::POWER_FLOOR).ln() }));
        features.extend(histogram.iter().map(|b| b / weighed));
        features.extend(pixel_sums.iter().map(|p| p / weighed));
    }
    features
}

/// Each ring's mean power in one frame `v(y, x)` of `h × w` values, by the transform's definition:
/// a frequency `(ky, kx)` of the kept half-plane (`width_bins` of `w` across) belongs to the ring
/// `of` names (or none), whose `sizes` are its frequencies' counts.
fn ring_powers(v: impl Fn(usize, usize) -> f64, (h, w): (usize, usize), of: &[Option<usize>], sizes: &[usize]) -> Vec<f64> {
    let k = spectrum::space::width_bins(w);
    let tau = 2.0 * std::f64::consts::PI;
    let mut frame = vec![0.0; sizes.len()];
    for ky in 0..h {
        for kx in 0..k {
            let Some(j) = of[ky * k + kx] else { continue };
            let (mut re, mut im) = (0.0, 0.0);
            for y in 0..h {
                for x in 0..w {
                    let angle = tau * (((ky * y) % h) as f64 / h as f64 + ((kx * x) % w) as f64 / w as f64);
                    re += v(y, x) * angle.cos();
                    im -= v(y, x) * angle.sin();
                }
            }
            frame[j] += (re * re + im * im) / (h * w) as f64 / sizes[j] as f64;
        }
    }
    frame
}

/// Logits `[batch][classes]` for `batch` raw samples laid out back to back.
pub fn forward(m: &BakedPvt3, x: &[f32], batch: usize) -> Result<Vec<Vec<f64>>> {
    forward_prefix(m, x, batch, m.config.time_tokens())
}

/// Logits `[batch][classes]` from the first `tokens` temporal tokens of each sample alone (a
/// touch so far, pruned tokens included as their constants): the temporal transformer runs over
/// the CLS token and those, and a spectral head reads the kept frames among them.
pub fn forward_prefix(m: &BakedPvt3, x: &[f32], batch: usize, tokens: usize) -> Result<Vec<Vec<f64>>> {
    let mut logits = transformer_logits(m, x, batch, tokens)?;
    if let Some(s) = &m.spectrum {
        let sample_len = x.len() / batch;
        for (l, sample) in logits.iter_mut().zip(x.chunks(sample_len)) {
            l.iter_mut().zip(spectral_logits(m, s, sample, tokens)).for_each(|(l, s)| *l += s);
        }
    }
    Ok(logits)
}

/// The transformer's logits from the first `tokens` temporal tokens.
fn transformer_logits(m: &BakedPvt3, x: &[f32], batch: usize, tokens: usize) -> Result<Vec<Vec<f64>>> {
    let c = &m.config;
    let sample_len: usize = c.sample_shape().iter().product();
    if x.len() != batch * sample_len {
        return Err(Error::InputShape { got: vec![x.len()], expected: format!("{batch} × {sample_len} values") });
    }
    c.check_prefix(tokens)?;
    let (n, d, eps) = (m.kept_patches.len(), c.dim, c.layer_norm_eps);
    x.chunks(sample_len)
        .map(|sample| {
            let mut sequence = m.temporal_cls.iter().map(|v| *v as f64).collect::<Vec<_>>();
            let mut encodings: Vec<f64> = m.pruned_encodings.iter().map(|v| *v as f64).collect();
            for (kk, &k) in m.kept_tokens.iter().enumerate().filter(|(_, k)| **k < tokens) {
                let pos = &m.pos_embed[kk * (n + 1) * d..(kk + 1) * (n + 1) * d];
                let mut tokens: Vec<f64> = m.space_cls.iter().map(|v| *v as f64).collect();
                for (p, scale) in patches(m, sample, k).iter().zip(&m.patch_scale) {
                    let scale = m.token_scale[kk] as f64 * *scale as f64;
                    tokens.extend(dense(&m.patch_embed, p).into_iter().map(|e| e * scale));
                }
                tokens.iter_mut().zip(pos).for_each(|(t, p)| *t += *p as f64);
                let enc = transformer_cls(&m.space, &tokens, n + 1, d, eps);
                encodings[k * d..(k + 1) * d].copy_from_slice(&enc);
            }
            sequence.extend(&encodings[..tokens * d]);
            let pooled = transformer_cls(&m.temporal, &sequence, tokens + 1, d, eps);
            Ok(dense(&m.head, &layer_norm(&m.head_norm, &pooled, eps)))
        })
        .collect()
}
