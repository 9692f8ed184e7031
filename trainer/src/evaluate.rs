//! Evaluation: loss, accuracy and predictions of a model on normalised windows
//! ([`Samples`]), in batches; a touch read as several windows answers with the mean of their
//! probabilities; [`levels`] its accuracy at each level of the touches' conditions.

pub mod levels;

use pvt3_models::Model;

use crate::data::windows::Samples;
use crate::Result;

/// What a model did on a set of touches.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// Mean cross-entropy over the windows.
    pub loss: f64,
    /// Share of touches whose answer is their label.
    pub accuracy: f64,
    /// Each touch's answer: the class of its window's largest logit, or of its windows' mean
    /// probabilities.
    pub predictions: Vec<u32>,
    /// Each touch's label.
    pub labels: Vec<u32>,
}

/// Windows an evaluation batch holds at most.
const EVAL_BATCH: usize = 100;
/// Values an evaluation batch holds at most (256 MB as f32): a hundred windows of a tactile
/// array, eleven of a camera's 25 frames of 240 × 320 RGB, whose hundred would take 2.3 GB and
/// as much again cut into patches.
const EVAL_VALUES: usize = 1 << 26;

/// How many of `samples`' windows an evaluation batch takes; the spectral head's fit reads its
/// windows in batches of this size too (`spectrum_fit`).
pub fn eval_batch(samples: &Samples) -> usize {
    (EVAL_VALUES / samples.sample_len().max(1)).clamp(1, EVAL_BATCH)
}

pub fn evaluate(model: &Model, samples: &Samples) -> Result<Evaluation> {
    let mut loss_sum = 0.0;
    let mut logits = vec![Vec::new(); samples.len()];
    for (tokens, rows) in by_answer(samples, model)? {
        for chunk in rows.chunks(eval_batch(samples)) {
            let (x, y) = samples.batch(chunk, |_| {})?;
            let l = match tokens {
                None => model.forward(&x, None)?,
                Some(k) => model.pvt3("a prefix")?.forward_prefix(&x, k, None)?,
            };
            loss_sum += candle_nn::loss::cross_entropy(&l, &y)?.to_scalar::<f32>()? as f64 * chunk.len() as f64;
            for (&r, row) in chunk.iter().zip(l.to_vec2::<f32>()?) {
                logits[r] = row;
            }
        }
    }
    let (mut predictions, mut labels) = (Vec::new(), Vec::new());
    let mut w = 0;
    while w < logits.len() {
        let end = (w..logits.len()).find(|&v| samples.touches[v] != samples.touches[w]).unwrap_or(logits.len());
        predictions.push(touch_answer(&logits[w..end]));
        labels.push(samples.labels[w]);
        w = end;
    }
    let correct = predictions.iter().zip(&labels).filter(|(p, l)| p == l).count();
    Ok(Evaluation {
        loss: loss_sum / samples.len().max(1) as f64,
        accuracy: correct as f64 / labels.len().max(1) as f64,
        predictions,
        labels,
    })
}

/// A touch's class from its windows' logits: the largest logit's for one window, the largest
/// mean probability's for several.
fn touch_answer(windows: &[Vec<f32>]) -> u32 {
    let argmax = |v: &[f64]| v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map_or(0, |(k, _)| k as u32);
    if let [one] = windows {
        return argmax(&one.iter().map(|v| *v as f64).collect::<Vec<_>>());
    }
    let mut mean = vec![0f64; windows[0].len()];
    for l in windows {
        let top = l.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
        let e: Vec<f64> = l.iter().map(|v| (*v as f64 - top).exp()).collect();
        let z: f64 = e.iter().sum();
        mean.iter_mut().zip(&e).for_each(|(m, e)| *m += e / z);
    }
    argmax(&mean)
}

/// The rows grouped by what `model` answers them from: `None` the whole window (every row,
/// in order, unless a touch is shorter than the window), `Some(k)` its first `k` temporal
/// tokens, PVT³'s provisional answer, as a robot's stream peeks when a touch ends early.
fn by_answer(samples: &Samples, model: &Model) -> Result<Vec<(Option<usize>, Vec<usize>)>> {
    let frames = *samples.sample_shape.last().expect("a frame axis");
    if samples.filled.iter().all(|f| *f == frames) {
        return Ok(vec![(None, (0..samples.len()).collect())]);
    }
    let tubelet = model.pvt3("a touch shorter than the model's window")?.config().tubelet;
    let mut groups: std::collections::BTreeMap<Option<usize>, Vec<usize>> = Default::default();
    for (r, (f, k)) in samples.filled.iter().zip(samples.tokens_filled(tubelet)).enumerate() {
        groups.entry((*f < frames).then_some(k)).or_default().push(r);
    }
    Ok(groups.into_iter().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_touch_answers_with_its_windows_mean_probability() {
        // Two windows: one sure of class 0, one mildly for class 1; the mean favours class 0.
        assert_eq!(touch_answer(&[vec![5.0, 0.0], vec![0.0, 0.5]]), 0);
        assert_eq!(touch_answer(&[vec![0.0, 0.2]]), 1);
    }
}
