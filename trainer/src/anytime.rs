//! Provisional answers from part of a touch: how well the first k temporal tokens classify, and
//! the stopping rule a robot applies to the runtime's `Session::peek`. The rule stops a touch at
//! the first token whose provisional top class probability reaches a threshold; the trainer
//! calibrates that threshold on the validation fold, so that stopping costs at most
//! [`MAX_LOSS`] of accuracy there, and the exporter writes it into the file
//! (`pvt3.stop_threshold`).

use candle_core::D;
use pvt3_models::Pvt3;
use serde::{Deserialize, Serialize};

use crate::evaluate::{Samples, EVAL_BATCH};
use crate::Result;

/// The accuracy the stopping rule may cost on the validation fold, against the whole touch.
pub const MAX_LOSS: f64 = 0.005;

/// Every sample's provisional answer after each number of temporal tokens, 1 to all of them.
#[derive(Clone, Debug)]
pub struct Prefixes {
    /// `[sample][tokens - 1]`: the top class probability.
    pub top: Vec<Vec<f32>>,
    /// `[sample][tokens - 1]`: whether the most probable class is the label.
    pub correct: Vec<Vec<bool>>,
    pub tokens: usize,
}

/// The stopping rule and what it did on the samples it was calibrated (or measured) on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stopping {
    /// Stop at the first token whose top probability reaches this.
    pub threshold: f32,
    /// Accuracy with the whole touch.
    pub full_accuracy: f64,
    /// Accuracy when stopping by the rule.
    pub accuracy: f64,
    /// The share of the touch used before stopping, on average (1: the whole touch).
    pub mean_share: f64,
}

/// The provisional answers of `model` on `samples` after 1, 2, … every temporal token: the
/// spatial stage once per window, the temporal one per prefix (as `Session::peek` runs it).
pub fn prefixes(model: &Pvt3, samples: &Samples) -> Result<Prefixes> {
    let tokens = model.config().time_tokens();
    let (mut top, mut correct) = (vec![Vec::with_capacity(tokens); samples.len()], vec![Vec::with_capacity(tokens); samples.len()]);
    let rows: Vec<usize> = (0..samples.len()).collect();
    for chunk in rows.chunks(EVAL_BATCH) {
        let (x, y) = samples.batch(chunk, |_| {})?;
        let labels = y.to_vec1::<u32>()?;
        let sequence = model.sequence(&x, None)?;
        for k in 1..=tokens {
            let probabilities = candle_nn::ops::softmax_last_dim(&model.classify_sequence(&model.prefix(&sequence, k)?, None)?)?;
            let best = probabilities.argmax(D::Minus1)?.to_vec1::<u32>()?;
            let p = probabilities.max(D::Minus1)?.to_vec1::<f32>()?;
            for (i, &r) in chunk.iter().enumerate() {
                top[r].push(p[i]);
                correct[r].push(best[i] == labels[i]);
            }
        }
    }
    Ok(Prefixes { top, correct, tokens })
}

impl Prefixes {
    fn samples(&self) -> f64 {
        self.top.len().max(1) as f64
    }

    /// Accuracy from the first `k` tokens alone.
    pub fn accuracy_at(&self, k: usize) -> f64 {
        self.correct.iter().filter(|c| c[k - 1]).count() as f64 / self.samples()
    }

    /// Accuracy and mean share of the touch when each sample stops at its first token whose top
    /// probability reaches `threshold` (or at the end).
    pub fn stop_at(&self, threshold: f32) -> Stopping {
        let (mut right, mut used) = (0usize, 0usize);
        for (top, correct) in self.top.iter().zip(&self.correct) {
            let k = top.iter().position(|p| *p >= threshold).unwrap_or(self.tokens - 1);
            right += usize::from(correct[k]);
            used += k + 1;
        }
        Stopping {
            threshold,
            full_accuracy: self.accuracy_at(self.tokens),
            accuracy: right as f64 / self.samples(),
            mean_share: used as f64 / (self.samples() * self.tokens as f64),
        }
    }

    /// The lowest threshold (the earliest stops) such that no threshold from it up to 1 costs
    /// more than [`MAX_LOSS`] of accuracy against the whole touch. Candidates are the top
    /// probabilities seen; requiring the whole range above to hold keeps one lucky threshold
    /// from being chosen.
    pub fn calibrate(&self) -> Stopping {
        let mut candidates: Vec<f32> = self.top.iter().flatten().copied().filter(|p| *p > 0.0).collect();
        candidates.push(1.0);
        candidates.sort_by(|a, b| b.total_cmp(a));
        candidates.dedup();
        let mut chosen = self.stop_at(1.0);
        for t in candidates {
            let s = self.stop_at(t);
            if s.accuracy < s.full_accuracy - MAX_LOSS - 1e-12 {
                break;
            }
            chosen = s;
        }
        chosen
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prefixes(top: Vec<Vec<f32>>, correct: Vec<Vec<bool>>) -> Prefixes {
        Prefixes { tokens: top[0].len(), top, correct }
    }

    /// Stopping reads each sample's first confident token; the calibration stops before the
    /// first threshold that costs accuracy.
    #[test]
    fn the_rule_stops_at_the_first_confident_token_and_calibration_keeps_accuracy() {
        let p = prefixes(
            vec![vec![0.3, 0.9, 0.95, 0.99], vec![0.6, 0.7, 0.97, 0.98], vec![0.2, 0.4, 0.5, 0.99]],
            vec![vec![false, true, true, true], vec![false, false, true, true], vec![false, false, false, true]],
        );
        assert_eq!(p.accuracy_at(1), 0.0);
        assert_eq!(p.accuracy_at(4), 1.0);
        let s = p.stop_at(0.9);
        assert_eq!((s.accuracy, s.mean_share), (1.0, (2.0 + 3.0 + 4.0) / 12.0));
        let s = p.stop_at(0.6);
        assert_eq!((s.accuracy, s.mean_share), (2.0 / 3.0, (2.0 + 1.0 + 4.0) / 12.0));
        // 0.9 keeps every answer; 0.7 already loses the second sample, so nothing lower is tried.
        let c = p.calibrate();
        assert_eq!((c.threshold, c.accuracy, c.full_accuracy), (0.9, 1.0, 1.0));
    }
}
