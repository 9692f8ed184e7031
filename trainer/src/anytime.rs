//! Provisional answers from part of a touch: how well the first k temporal tokens classify, and
//! the stopping rule a robot applies to the runtime's `Session::peek`. The rule
//! ([`StopRule`]) stops a touch at the first token whose provisional top class probability
//! reaches a threshold while the answers after the [`AGREEING`]` - 1` tokens before agree on the
//! class. The trainer calibrates the threshold on the validation fold so that stopping costs no
//! accuracy there (docs/anytime.md: a 0.5-point allowance on about 200 validation samples, one
//! sample, did not hold on the test fold), and the exporter writes the rule into the file
//! (`pvt3.stop_rule`).

use pvt3_format::StopRule;
use pvt3_models::Pvt3;
use serde::{Deserialize, Serialize};

use crate::evaluate::{Samples, EVAL_BATCH};
use crate::Result;

/// Answers in a row that must agree on the class before a touch stops: a single confident
/// answer early in a touch was often wrong (docs/anytime.md).
pub const AGREEING: usize = 3;

/// Every sample's provisional answer after each number of temporal tokens, 1 to all of them.
#[derive(Clone, Debug)]
pub struct Prefixes {
    /// `[sample][tokens - 1]`: the top class probability.
    pub top: Vec<Vec<f32>>,
    /// `[sample][tokens - 1]`: the most probable class.
    pub class: Vec<Vec<u32>>,
    pub labels: Vec<u32>,
    pub tokens: usize,
}

/// The stopping rule and what it did on the samples it was calibrated (or measured) on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stopping {
    pub rule: StopRule,
    /// Accuracy with the whole touch.
    pub full_accuracy: f64,
    /// Accuracy when stopping by the rule.
    pub accuracy: f64,
    /// The share of the touch used before stopping, on average (1: the whole touch).
    pub mean_share: f64,
}

/// Every sample's provisional class probabilities after 1, 2, … every temporal token
/// (`pvt3 eval --anytime --answers FILE` writes them, to study other stopping rules).
#[derive(Clone, Debug, Serialize)]
pub struct Answers {
    /// `[sample][tokens - 1][class]`.
    pub probabilities: Vec<Vec<Vec<f32>>>,
    pub labels: Vec<u32>,
    pub tokens: usize,
}

/// The provisional answers of `model` on `samples`: the spatial stage once per window, the
/// temporal one per prefix (as `Session::peek` runs it).
pub fn answers(model: &Pvt3, samples: &Samples) -> Result<Answers> {
    let tokens = model.config().time_tokens();
    let mut probabilities = vec![Vec::with_capacity(tokens); samples.len()];
    let rows: Vec<usize> = (0..samples.len()).collect();
    for chunk in rows.chunks(EVAL_BATCH) {
        let (x, _) = samples.batch(chunk, |_| {})?;
        let sequence = model.sequence(&x, None)?;
        for k in 1..=tokens {
            let p = candle_nn::ops::softmax_last_dim(&model.classify_sequence(&model.prefix(&sequence, k)?, None)?)?.to_vec2::<f32>()?;
            for (row, &r) in p.into_iter().zip(chunk) {
                probabilities[r].push(row);
            }
        }
    }
    Ok(Answers { probabilities, labels: samples.labels.clone(), tokens })
}

/// The provisional answers of `model` on `samples`, as the stopping rule reads them.
pub fn prefixes(model: &Pvt3, samples: &Samples) -> Result<Prefixes> {
    Ok(Prefixes::from(&answers(model, samples)?))
}

impl From<&Answers> for Prefixes {
    fn from(a: &Answers) -> Self {
        let best = |p: &Vec<f32>| {
            let (class, top) = pvt3_format::top_class(p);
            (class as u32, top)
        };
        let (class, top) = a.probabilities.iter().map(|sample| sample.iter().map(best).unzip()).unzip();
        Prefixes { top, class, labels: a.labels.clone(), tokens: a.tokens }
    }
}

impl Prefixes {
    fn samples(&self) -> f64 {
        self.top.len().max(1) as f64
    }

    /// Accuracy from the first `k` tokens alone.
    pub fn accuracy_at(&self, k: usize) -> f64 {
        self.class.iter().zip(&self.labels).filter(|(c, l)| c[k - 1] == **l).count() as f64 / self.samples()
    }

    /// The number of tokens after which sample `i` stops by `rule` (all of them if never).
    fn stops_after(&self, i: usize, rule: StopRule) -> usize {
        let (top, class) = (&self.top[i], &self.class[i]);
        (rule.agreeing..=self.tokens)
            .find(|&k| top[k - 1] >= rule.top_probability && class[k - rule.agreeing..k].iter().all(|c| *c == class[k - 1]))
            .unwrap_or(self.tokens)
    }

    /// Accuracy and mean share of the touch when each sample stops by `rule`.
    pub fn stop_by(&self, rule: StopRule) -> Stopping {
        let (mut right, mut used) = (0usize, 0usize);
        for i in 0..self.top.len() {
            let k = self.stops_after(i, rule);
            right += usize::from(self.class[i][k - 1] == self.labels[i]);
            used += k;
        }
        Stopping {
            rule,
            full_accuracy: self.accuracy_at(self.tokens),
            accuracy: right as f64 / self.samples(),
            mean_share: used as f64 / (self.samples() * self.tokens as f64),
        }
    }

    /// The lowest threshold (the earliest stops) such that no threshold from it up to 1 loses
    /// accuracy against the whole touch, with [`AGREEING`] answers agreeing. Candidates are the
    /// top probabilities seen; requiring the whole range above to hold keeps one lucky threshold
    /// from being chosen.
    pub fn calibrate(&self) -> Stopping {
        let mut candidates: Vec<f32> = self.top.iter().flatten().copied().filter(|p| *p > 0.0).collect();
        candidates.push(1.0);
        candidates.sort_by(|a, b| b.total_cmp(a));
        candidates.dedup();
        let rule = |top_probability| StopRule { top_probability, agreeing: AGREEING };
        let mut chosen = self.stop_by(rule(1.0));
        for t in candidates {
            let s = self.stop_by(rule(t));
            if s.accuracy < s.full_accuracy - 1e-12 {
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

    /// Stopping reads each sample's first confident token whose class the answers before agree
    /// on; the calibration stops before the first threshold that costs accuracy.
    #[test]
    fn the_rule_stops_at_the_first_confident_agreed_token_and_calibration_keeps_accuracy() {
        let p = Prefixes {
            top: vec![vec![0.3, 0.9, 0.95, 0.99], vec![0.6, 0.7, 0.97, 0.98], vec![0.95, 0.4, 0.5, 0.99]],
            class: vec![vec![1, 0, 0, 0], vec![1, 1, 0, 0], vec![1, 2, 2, 2]],
            labels: vec![0, 0, 2],
            tokens: 4,
        };
        assert_eq!(p.accuracy_at(1), 0.0);
        assert_eq!(p.accuracy_at(4), 1.0);
        let rule = |top_probability, agreeing| StopRule { top_probability, agreeing };
        // One answer: the third sample stops wrongly on its first token.
        let s = p.stop_by(rule(0.9, 1));
        assert_eq!((s.accuracy, s.mean_share), (2.0 / 3.0, (2.0 + 3.0 + 1.0) / 12.0));
        // Two agreeing answers: the first sample waits a token, the third to the end.
        let s = p.stop_by(rule(0.9, 2));
        assert_eq!((s.accuracy, s.mean_share), (1.0, (3.0 + 4.0 + 4.0) / 12.0));
        // With three, 0.95 keeps every answer; 0.9 lets the first sample stop at token 3 (right),
        // still no loss; nothing below 0.9 is seen but for stops at wrong tokens that lose.
        let c = p.calibrate();
        assert_eq!(c.rule.agreeing, AGREEING);
        assert!(c.accuracy == 1.0 && c.rule.top_probability <= 0.95, "{c:?}");
    }
}
