//! `pvt3 bench stress`: the robot runtime's f32 output against the baked model's f64 reference on
//! inputs a sensor should never send but might: scaled far outside the normal range, all zero,
//! constant, one hot taxel, int16 extremes, noise, and weights near overflow after folding large
//! mask values. Reports the worst absolute and relative logit error and any non-finite output.

use std::path::Path;

use pvt3_models::Rng;
use pvt3_spec::baked::BakedPvt3;
use pvt3_spec::reference;
use serde::Serialize;

use crate::checkpoint::BakedFile;
use crate::Result;

/// One stress case's outcome over its windows.
#[derive(Clone, Debug, Serialize)]
pub struct StressRow {
    pub case: String,
    pub worst_abs: f64,
    /// Worst absolute error over the largest reference logit of the window.
    pub worst_rel: f64,
    pub non_finite: usize,
    /// Windows where runtime and reference pick the same class.
    pub same_class: usize,
    pub windows: usize,
}

/// A case: a name, the windows (raw units), and the factor folded into the mask-scaled weights.
struct Case {
    name: String,
    windows: Vec<Vec<f32>>,
    mask_scale: f32,
}

/// The cases for a model whose normal input is `mean + std · z` per channel.
fn cases(file: &BakedFile, windows: usize, quick: bool) -> Vec<Case> {
    let norm = &file.normalization;
    let len: usize = file.baked.config.sample_shape().iter().product();
    let frames = norm.frames;
    let mut rng = Rng::new(7);
    let typical: Vec<Vec<f32>> =
        (0..windows).map(|_| (0..len).map(|i| norm.mean[i / frames] + norm.std[i / frames] * rng.normal()).collect()).collect();
    let scaled = |s: f32| typical.iter().map(|w| w.iter().map(|v| v * s).collect()).collect();
    let case = |name: &str, windows: Vec<Vec<f32>>| Case { name: name.into(), windows, mask_scale: 1.0 };
    let mut out = vec![case("normal range (mean + std · N(0,1) per channel)", typical.clone())];
    let scales: &[f32] = if quick { &[1e-3, 1e4] } else { &[1e-3, 1e-2, 1e-1, 10.0, 1e2, 1e3, 1e4] };
    out.extend(scales.iter().map(|&s| case(&format!("normal range × {s:e}"), scaled(s))));
    out.push(case("all zero", vec![vec![0.0; len]]));
    let frame: Vec<f32> = (0..len / frames).map(|_| 100.0 * rng.normal()).collect();
    out.push(case("constant frames (one random frame repeated)", vec![(0..len).map(|i| frame[i / frames]).collect()]));
    out.push(case("constant 1000 everywhere", vec![vec![1000.0; len]]));
    let mut hot = vec![0.0; len];
    hot[len / 2 / frames * frames..(len / 2 / frames + 1) * frames].fill(32767.0);
    out.push(case("one hot taxel at 32767, others 0", vec![hot]));
    out.push(case(
        "int16 extremes (±32767/32768 at random)",
        (0..windows).map(|_| (0..len).map(|_| if rng.uniform() < 0.5 { -32768.0 } else { 32767.0 }).collect()).collect(),
    ));
    out.push(case(
        "uniform noise in [-1000, 1000]",
        (0..windows).map(|_| (0..len).map(|_| 2000.0 * rng.uniform() - 1000.0).collect()).collect(),
    ));
    let folds: &[f32] = if quick { &[1e3] } else { &[10.0, 1e2, 1e3] };
    for &f in folds {
        out.push(Case { name: format!("mask values × {f:e} folded into q, k, v and fc2"), windows: typical.clone(), mask_scale: f });
    }
    out
}

/// The model with every q/k/v row and fc2 column scaled by `f`, as if its mask values were `f`
/// times larger (what baking folds into the weights).
fn fold_mask_scale(m: &BakedPvt3, f: f32) -> BakedPvt3 {
    let mut m = m.clone();
    for layer in m.space.layers.iter_mut().chain(m.temporal.layers.iter_mut()) {
        for dense in [&mut layer.attn.q, &mut layer.attn.k, &mut layer.attn.v, &mut layer.ffn.fc2] {
            dense.weight.iter_mut().for_each(|w| *w *= f);
        }
    }
    m
}

/// Runs every case through the exported model in the runtime and through the f64 reference.
pub fn stress(file: &BakedFile, windows: usize, quick: bool, scratch: &Path) -> Result<Vec<StressRow>> {
    let mut rows = Vec::new();
    let mut loaded: Option<(f32, pvt3_runtime::Classifier)> = None;
    for case in cases(file, windows, quick) {
        let baked = fold_mask_scale(&file.baked, case.mask_scale);
        if loaded.as_ref().map(|(s, _)| *s) != Some(case.mask_scale) {
            let path = scratch.join(format!("stress-{}.onnx", case.mask_scale));
            pvt3_export::write(&pvt3_export::export(&baked, &file.normalization, &file.metadata())?, &path)?;
            loaded = Some((case.mask_scale, pvt3_runtime::Classifier::load(&path)?));
        }
        let classifier = &loaded.as_ref().expect("loaded above").1;
        let mut row =
            StressRow { case: case.name, worst_abs: 0.0, worst_rel: 0.0, non_finite: 0, same_class: 0, windows: case.windows.len() };
        for window in &case.windows {
            let (got, _) = classifier.run(window, 1)?;
            // The reference gets the normalised window computed in f64.
            let norm = &file.normalization;
            let normalised: Vec<f32> = window
                .iter()
                .enumerate()
                .map(|(i, v)| ((*v as f64 - norm.mean[i / norm.frames] as f64) / norm.std[i / norm.frames] as f64) as f32)
                .collect();
            let expected = reference::forward(&baked, &normalised, 1)?.remove(0);
            row.non_finite += got.iter().filter(|v| !v.is_finite()).count();
            let abs = got.iter().zip(&expected).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
            let scale = expected.iter().map(|v| v.abs()).fold(0.0, f64::max).max(1e-30);
            row.worst_abs = row.worst_abs.max(abs);
            row.worst_rel = row.worst_rel.max(abs / scale);
            let argmax = |v: &[f64]| v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map_or(0, |(i, _)| i);
            row.same_class += usize::from(argmax(&got.iter().map(|v| *v as f64).collect::<Vec<_>>()) == argmax(&expected));
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The rows as a markdown table.
pub fn table(rows: &[StressRow]) -> String {
    let mut out = String::from("| input | worst abs error | worst rel error | non-finite | same class |\n|---|---:|---:|---:|---:|\n");
    for r in rows {
        out += &format!("| {} | {:.2e} | {:.2e} | {} | {}/{} |\n", r.case, r.worst_abs, r.worst_rel, r.non_finite, r.same_class, r.windows);
    }
    out
}

#[cfg(test)]
mod tests;
