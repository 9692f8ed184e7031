//! Provisional answers from part of a touch: how well the first k temporal tokens classify, and
//! the stopping rule a robot applies to the runtime's `Session::peek`. The rule
//! ([`StopRule`]) stops a touch at the first token whose provisional top class probability
//! reaches a threshold while the answers after the `agreeing - 1` tokens before agree on the
//! class. A single run (`pvt3 train`) calibrates the threshold on its validation fold so that
//! stopping costs no accuracy there, with [`AGREEING`] answers (docs/anytime.md: a 0.5-point
//! allowance on about 200 validation samples, one sample, did not hold on the test fold). A
//! cross-validation (`pvt3 cv`) calibrates one rule on the validation answers of all its runs
//! together, thousands of samples, where the 0.5 points ([`POOLED_ALLOWANCE`]) are many
//! samples and the agreement length can be chosen too ([`Prefixes::calibrate_pooled`]). The
//! exporter writes the rule into the file (`pvt3.stop_rule`).

use pvt3_format::{answers_agree, StopRule};
use pvt3_models::Pvt3;
use serde::Serialize;

use crate::provenance::{CalibratedOn, Stopping};
use crate::Result;
use crate::{data::windows::Samples, evaluate::eval_batch};

/// Answers in a row that must agree on the class before a touch stops: a single confident
/// answer early in a touch was often wrong (docs/anytime.md).
pub const AGREEING: usize = 3;

/// The agreement lengths a cross-validation's calibration chooses among.
pub const AGREEMENT_LENGTHS: [usize; 7] = [2, 3, 4, 5, 6, 8, 12];

/// The accuracy (a share of the samples) a cross-validation's calibration may lose against the
/// whole touch on its pooled validation answers: the 0.5 points.
pub const POOLED_ALLOWANCE: f64 = 0.005;

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

/// Every sample's provisional class probabilities after 1, 2, … every temporal token
/// (`pvt3 eval --anytime --answers FILE` writes them, to study other stopping rules).
#[derive(Clone, Debug, Serialize)]
pub struct Answers {
    /// `[sample][tokens - 1][class]`.
    pub probabilities: Vec<Vec<Vec<f32>>>,
    pub labels: Vec<u32>,
    pub tokens: usize,
}

/// The PVT³ network of `model`, which gives provisional answers; `None` for another network.
pub fn answering(model: &pvt3_models::Model) -> Option<&Pvt3> {
    model.pvt3("provisional answers").ok()
}

/// The provisional answers of `model` on `samples`: the spatial stage once per window, the
/// temporal one per prefix (as `Session::peek` runs it).
pub fn answers(model: &Pvt3, samples: &Samples) -> Result<Answers> {
    let tokens = model.config().time_tokens();
    let mut probabilities = vec![Vec::with_capacity(tokens); samples.len()];
    let rows: Vec<usize> = (0..samples.len()).collect();
    for chunk in rows.chunks(eval_batch(samples)) {
        let (x, _) = samples.batch(chunk, |_| {})?;
        let sequence = model.sequence(&x, None)?;
        for k in 1..=tokens {
            let p = candle_nn::ops::softmax_last_dim(&model.classify_prefix(&x, &sequence, k, None)?.0)?.to_vec2::<f32>()?;
            for (row, &r) in p.into_iter().zip(chunk) {
                probabilities[r].push(row);
            }
        }
    }
    // A touch shorter than the window answers from the tokens it fills until its end, and
    // then keeps its last answer.
    for (answers, filled) in probabilities.iter_mut().zip(samples.tokens_filled(model.config().tubelet)) {
        if (1..tokens).contains(&filled) {
            let last = answers[filled - 1].clone();
            answers[filled..].iter_mut().for_each(|a| *a = last.clone());
        }
    }
    Ok(Answers { probabilities, labels: samples.labels.clone(), tokens })
}

/// The provisional answers of `model` on `samples`, as the stopping rule reads them.
pub fn prefixes(model: &Pvt3, samples: &Samples) -> Result<Prefixes> {
    Ok(Prefixes::from(&answers(model, samples)?))
}

/// The stopping rule the checkpoint `meta` carries; one trained before there was a rule is
/// calibrated here as training calibrates it, on its validation fold of `data`.
pub fn carried_rule(model: &Pvt3, meta: &crate::checkpoint::Meta, data: &crate::data::Dataset) -> Result<Stopping> {
    match &meta.provenance.stopping {
        Some(carried) => Ok(carried.clone()),
        None => {
            let val = Samples::new(data, &data.split_for(meta.provenance.val_fold)?.val, &meta.normalization);
            Ok(prefixes(model, &val)?.calibrate())
        }
    }
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

/// A sample's classes after each token as [`pvt3_format::StopRule::stops`] asks for them.
fn answered(class: &[u32]) -> impl FnMut(usize) -> std::result::Result<usize, std::convert::Infallible> + '_ {
    |j| Ok(class[j - 1] as usize)
}

impl Prefixes {
    fn samples(&self) -> f64 {
        self.top.len().max(1) as f64
    }

    /// Accuracy after each tenth of the touch: the share, the tokens read (at least one), the
    /// accuracy.
    pub fn tenths(&self) -> Vec<(f64, usize, f64)> {
        (1..=10)
            .map(|tenth| {
                let k = (tenth * self.tokens).div_ceil(10).max(1);
                (tenth as f64 / 10.0, k, self.accuracy_at(k))
            })
            .collect()
    }

    /// Accuracy from the first `k` tokens alone.
    pub fn accuracy_at(&self, k: usize) -> f64 {
        self.class.iter().zip(&self.labels).filter(|(c, l)| c[k - 1] == **l).count() as f64 / self.samples()
    }

    /// The number of tokens after which sample `i` stops by `rule` (all of them if never).
    fn stops_after(&self, i: usize, rule: StopRule) -> usize {
        let (top, class) = (&self.top[i], &self.class[i]);
        (1..=self.tokens).find(|&k| rule.stops(k, class[k - 1] as usize, top[k - 1], answered(class)) == Ok(true)).unwrap_or(self.tokens)
    }

    /// For each sample, the number of tokens after which `rule` stops it (all of them if never),
    /// and whether its answer then is right.
    pub fn stops(&self, rule: StopRule) -> Vec<(usize, bool)> {
        (0..self.top.len())
            .map(|i| {
                let k = self.stops_after(i, rule);
                (k, self.class[i][k - 1] == self.labels[i])
            })
            .collect()
    }

    /// Accuracy and mean share of the touch when each sample stops by `rule`.
    pub fn stop_by(&self, rule: StopRule) -> Stopping {
        let stops = self.stops(rule);
        let right = stops.iter().filter(|(_, right)| *right).count();
        let used: usize = stops.iter().map(|(k, _)| k).sum();
        Stopping {
            rule,
            full_accuracy: self.accuracy_at(self.tokens),
            accuracy: right as f64 / self.samples(),
            mean_share: used as f64 / (self.samples() * self.tokens as f64),
            calibrated_on: CalibratedOn::ValidationFold,
        }
    }

    /// The rule of a single run: [`AGREEING`] answers, the lowest threshold that loses no
    /// accuracy here ([`Prefixes::calibrate_with`]).
    pub fn calibrate(&self) -> Stopping {
        self.calibrate_with(AGREEING, 0.0)
    }

    /// The rule of a cross-validation, on its runs' validation answers [`Prefixes::pooled`]:
    /// for each of [`AGREEMENT_LENGTHS`] the lowest threshold that loses at most
    /// [`POOLED_ALLOWANCE`] here, and of those the one that stops earliest here.
    pub fn calibrate_pooled(&self, runs: usize) -> Stopping {
        let best = AGREEMENT_LENGTHS
            .iter()
            .filter(|&&a| a <= self.tokens)
            .map(|&a| self.calibrate_with(a, POOLED_ALLOWANCE))
            .min_by(|a, b| a.mean_share.total_cmp(&b.mean_share))
            .unwrap_or_else(|| self.calibrate_with(1, POOLED_ALLOWANCE));
        Stopping { calibrated_on: CalibratedOn::CrossValidation { runs, samples: self.top.len() }, ..best }
    }

    /// The lowest threshold (the earliest stops) such that no threshold from it up to 1 loses
    /// more than `allowance` (a share of the samples) against the whole touch, with `agreeing`
    /// answers agreeing. Candidates are the top probabilities seen; requiring the whole range
    /// above to hold keeps one lucky threshold from being chosen.
    ///
    /// One sweep down the thresholds: a sample's stop moves to an earlier token only where the
    /// threshold passes a score that beats every earlier agreed token's, so only those scores
    /// (a few per sample) change the accuracy, and each moves one sample.
    pub fn calibrate_with(&self, agreeing: usize, allowance: f64) -> Stopping {
        let (n, last, agreeing) = (self.top.len(), self.tokens, agreeing.max(1));
        let mut moves: Vec<(f32, usize, usize)> = Vec::new();
        for i in 0..n {
            let mut record = f32::NEG_INFINITY;
            for k in agreeing..=last {
                let agreed = answers_agree(agreeing, k, self.class[i][k - 1] as usize, answered(&self.class[i])) == Ok(true);
                if agreed && self.top[i][k - 1] > record {
                    record = self.top[i][k - 1];
                    moves.push((record, i, k));
                }
            }
        }
        moves.sort_by(|a, b| b.0.total_cmp(&a.0));
        let right_at = |i: usize, k: usize| usize::from(self.class[i][k - 1] == self.labels[i]);
        let mut stop = vec![last; n];
        let full = (0..n).map(|i| right_at(i, last)).sum::<usize>();
        let mut right = full;
        let loses = |right: usize| right as f64 / self.samples() < full as f64 / self.samples() - allowance - 1e-12;
        let mut failed_at = None;
        for group in moves.chunk_by(|a, b| a.0 == b.0) {
            for &(_, i, k) in group {
                right = right - right_at(i, stop[i]) + right_at(i, k);
                stop[i] = k;
            }
            if loses(right) {
                failed_at = Some(group[0].0);
                break;
            }
        }
        // Every top probability seen is a candidate: the lowest one above the first that loses.
        let candidates = self.top.iter().flatten().copied().filter(|p| *p > 0.0);
        let threshold = match failed_at {
            Some(t) => candidates.filter(|p| *p > t).min_by(f32::total_cmp).unwrap_or(1.0),
            None => candidates.min_by(f32::total_cmp).unwrap_or(1.0),
        };
        self.stop_by(StopRule { top_probability: threshold, agreeing })
    }

    /// The answers of several runs' samples as one set (runs of one configuration).
    pub fn pooled(parts: impl IntoIterator<Item = Prefixes>) -> Result<Prefixes> {
        let mut all: Option<Prefixes> = None;
        for p in parts {
            match &mut all {
                None => all = Some(p),
                Some(a) if a.tokens != p.tokens => {
                    return Err(crate::Error::Usage(format!(
                        "runs with {} and {} temporal tokens cannot be calibrated together",
                        a.tokens, p.tokens
                    )))
                }
                Some(a) => {
                    a.top.extend(p.top);
                    a.class.extend(p.class);
                    a.labels.extend(p.labels);
                }
            }
        }
        all.ok_or_else(|| crate::Error::Usage("no runs' answers to calibrate a stopping rule on".into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Dataset;

    /// The answers after each token are the model's on the touch so far, a spectral head's over
    /// the frames received (`Pvt3::forward_prefix`), and the last is the whole window's.
    #[test]
    fn the_answers_are_the_model_on_each_prefix_with_a_spectral_head() {
        let cfg = pvt3_models::Config {
            frames: 12,
            tubelet: 3,
            network: pvt3_models::Pvt3Config { spectral_bands: 4, ..Default::default() }.into(),
            ..pvt3_models::Config::icub20()
        };
        let (model, _) = Pvt3::init(&cfg, 5).unwrap();
        let mut rng = pvt3_models::Rng::new(8);
        let n = 3;
        let x: Vec<f32> = (0..n * 60 * 12).map(|_| rng.normal()).collect();
        let data = Dataset::in_memory(x, cfg.sample_shape(), vec![0; n]);
        let samples = Samples::unnormalised(&data);
        let a = answers(&model, &samples).unwrap();
        assert_eq!(a.tokens, 4);
        let (x, _) = samples.batch(&[0, 1, 2], |_| {}).unwrap();
        for tokens in 1..=4 {
            let logits = if tokens == 4 { model.forward(&x, None) } else { model.forward_prefix(&x, tokens, None) };
            let expected = candle_nn::ops::softmax_last_dim(&logits.unwrap()).unwrap().to_vec2::<f32>().unwrap();
            for (sample, row) in expected.iter().enumerate() {
                let got = &a.probabilities[sample][tokens - 1];
                assert!(got.iter().zip(row).all(|(g, e)| (g - e).abs() < 1e-6), "{tokens} tokens, sample {sample}");
            }
        }
        // The head reads the frames received: the first token's answer is not the whole window's.
        assert_ne!(a.probabilities[0][0], a.probabilities[0][3]);
    }

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

    #[test]
    fn each_tenth_reads_the_tokens_that_cover_it_and_at_least_one() {
        let p = Prefixes { top: vec![vec![0.9; 4]; 2], class: vec![vec![1, 0, 0, 0], vec![1, 1, 0, 1]], labels: vec![0, 1], tokens: 4 };
        let t = p.tenths();
        assert_eq!(t.len(), 10);
        assert_eq!(t[0], (0.1, 1, 0.5), "a tenth of four tokens reads one");
        assert_eq!(t[2], (0.3, 2, 1.0), "three tenths read 1.2 tokens' worth: two");
        assert_eq!(t[5], (0.6, 3, 0.5));
        assert_eq!(t[9], (1.0, 4, 1.0));
    }

    /// The definition `calibrate_with` sweeps: try every top probability seen, from 1 down, and
    /// keep the last before the first that loses more than the allowance.
    fn calibrate_by_trying_every_threshold(p: &Prefixes, agreeing: usize, allowance: f64) -> Stopping {
        let mut candidates: Vec<f32> = p.top.iter().flatten().copied().filter(|p| *p > 0.0).collect();
        candidates.push(1.0);
        candidates.sort_by(|a, b| b.total_cmp(a));
        candidates.dedup();
        let rule = |top_probability| StopRule { top_probability, agreeing };
        let mut chosen = p.stop_by(rule(1.0));
        for t in candidates {
            let s = p.stop_by(rule(t));
            if s.accuracy < s.full_accuracy - allowance - 1e-12 {
                break;
            }
            chosen = s;
        }
        chosen
    }

    /// Answers of `n` samples over `tokens` tokens, drawn so that classes change along a touch,
    /// early answers are often wrong and probabilities repeat (ties between samples).
    fn random_prefixes(rng: &mut pvt3_models::Rng, n: usize, tokens: usize) -> Prefixes {
        let labels: Vec<u32> = (0..n).map(|_| rng.below(3) as u32).collect();
        let (mut top, mut class) = (Vec::new(), Vec::new());
        for &label in &labels {
            let (mut t, mut c) = (Vec::new(), Vec::new());
            for k in 0..tokens {
                let right = rng.uniform() < 0.3 + 0.6 * k as f32 / tokens as f32;
                c.push(if right { label } else { rng.below(3) as u32 });
                t.push(0.4 + 0.05 * rng.below(13) as f32);
            }
            top.push(t);
            class.push(c);
        }
        Prefixes { top, class, labels, tokens }
    }

    /// The sweep chooses what trying every threshold chooses, for every agreement length and
    /// allowance, on many random sets of answers.
    #[test]
    fn the_sweep_calibrates_as_trying_every_threshold() {
        let mut rng = pvt3_models::Rng::new(7);
        for case in 0..200 {
            let p = random_prefixes(&mut rng, 1 + case % 40, 1 + case % 9);
            for agreeing in 1..=4 {
                for allowance in [0.0, 0.02, 0.1] {
                    let fast = p.calibrate_with(agreeing, allowance);
                    assert_eq!(
                        fast,
                        calibrate_by_trying_every_threshold(&p, agreeing, allowance),
                        "case {case}, {agreeing} agreeing, {allowance}"
                    );
                }
            }
        }
    }

    /// Pooling concatenates the runs' samples; the pooled rule loses at most the allowance on
    /// them, stops no later than any agreement length would, and says where it was calibrated.
    #[test]
    fn the_pooled_rule_chooses_the_earliest_agreement_within_the_allowance() {
        let mut rng = pvt3_models::Rng::new(11);
        let parts: Vec<Prefixes> = (0..3).map(|_| random_prefixes(&mut rng, 300, 16)).collect();
        let pooled = Prefixes::pooled(parts.clone()).unwrap();
        assert_eq!(pooled.labels.len(), 900);
        assert_eq!(pooled.labels[300..600], parts[1].labels[..]);
        let rule = pooled.calibrate_pooled(3);
        assert_eq!(rule.calibrated_on, CalibratedOn::CrossValidation { runs: 3, samples: 900 });
        assert!(rule.accuracy >= rule.full_accuracy - POOLED_ALLOWANCE - 1e-12, "{rule:?}");
        assert!(rule.mean_share < 1.0, "random answers leave room to stop early: {rule:?}");
        for a in AGREEMENT_LENGTHS {
            assert!(rule.mean_share <= pooled.calibrate_with(a, POOLED_ALLOWANCE).mean_share);
        }
        let other = random_prefixes(&mut rng, 2, 5);
        assert!(Prefixes::pooled([parts[0].clone(), other]).is_err(), "different token counts are refused");
        assert!(Prefixes::pooled([]).is_err());
    }
}
