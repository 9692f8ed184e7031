//! Evaluation: loss, accuracy and predictions of a model on normalised samples, in batches.

use candle_core::{Device, Tensor, D};
use pvt3_models::Classifier;

use crate::data::Dataset;
use crate::normalization::Normalization;
use crate::Result;

/// Normalised samples of one split, ready to batch.
#[derive(Clone, Debug)]
pub struct Samples {
    pub x: Vec<f32>,
    pub labels: Vec<u32>,
    pub sample_shape: Vec<usize>,
}

impl Samples {
    /// The `indices` samples of `data`, normalised.
    pub fn new(data: &Dataset, indices: &[usize], norm: &Normalization) -> Self {
        let mut x = Vec::with_capacity(indices.len() * data.sample_len());
        for &i in indices {
            norm.apply_into(data.sample(i), &mut x);
        }
        let labels = indices.iter().map(|&i| data.labels[i]).collect();
        Self { x, labels, sample_shape: data.sample_shape.clone() }
    }

    pub fn len(&self) -> usize {
        self.labels.len()
    }

    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    fn sample_len(&self) -> usize {
        self.sample_shape.iter().product()
    }

    /// The samples at `rows` as a tensor `[rows, …sample_shape]` and a label tensor.
    pub fn batch(&self, rows: &[usize], transform: impl FnMut(&mut [f32])) -> Result<(Tensor, Tensor)> {
        let l = self.sample_len();
        let mut x = Vec::with_capacity(rows.len() * l);
        for &r in rows {
            x.extend_from_slice(&self.x[r * l..(r + 1) * l]);
        }
        x.chunks_mut(l).for_each(transform);
        let mut shape = vec![rows.len()];
        shape.extend_from_slice(&self.sample_shape);
        let labels: Vec<u32> = rows.iter().map(|&r| self.labels[r]).collect();
        Ok((Tensor::from_vec(x, shape, &Device::Cpu)?, Tensor::new(labels, &Device::Cpu)?))
    }
}

/// What a model did on a set of samples.
#[derive(Clone, Debug)]
pub struct Evaluation {
    pub loss: f64,
    pub accuracy: f64,
    pub predictions: Vec<u32>,
}

pub const EVAL_BATCH: usize = 100;

pub fn evaluate(model: &Classifier, samples: &Samples) -> Result<Evaluation> {
    let mut loss_sum = 0.0;
    let mut predictions = Vec::with_capacity(samples.len());
    let rows: Vec<usize> = (0..samples.len()).collect();
    for chunk in rows.chunks(EVAL_BATCH) {
        let (x, y) = samples.batch(chunk, |_| {})?;
        let logits = model.forward(&x, None)?;
        loss_sum += candle_nn::loss::cross_entropy(&logits, &y)?.to_scalar::<f32>()? as f64 * chunk.len() as f64;
        predictions.extend(logits.argmax(D::Minus1)?.to_vec1::<u32>()?);
    }
    let correct = predictions.iter().zip(&samples.labels).filter(|(p, l)| p == l).count();
    let n = samples.len().max(1) as f64;
    Ok(Evaluation { loss: loss_sum / n, accuracy: correct as f64 / n, predictions })
}
