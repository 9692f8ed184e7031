//! Inverted dropout drawing its mask from the seeded [`Rng`], so that training is reproducible
//! (candle's own dropout uses an unseedable generator).

use candle_core::{Result, Tensor};

use crate::Rng;

/// Dropout with probability `p`; the identity when `rng` is `None` (evaluation) or `p == 0`.
#[derive(Clone, Debug)]
pub struct Dropout {
    p: f32,
}

impl Dropout {
    pub fn new(p: f64) -> Self {
        Self { p: p as f32 }
    }

    pub fn p(&self) -> f32 {
        self.p
    }

    /// This step's mask for `n` values (each 0 or `1 / (1 - p)`), or `None` when dropout is off.
    /// Each draw of the generator gives two 24-bit uniform values.
    pub fn mask(&self, n: usize, rng: Option<&mut Rng>) -> Option<Vec<f32>> {
        let rng = rng.filter(|_| self.p > 0.0)?;
        let scale = 1.0 / (1.0 - self.p);
        // u < p for u = k / 2^24 exactly when k < ⌈p · 2^24⌉.
        let threshold = (self.p as f64 * (1u64 << 24) as f64).ceil() as u64;
        let keep = |k: u64| if k < threshold { 0.0 } else { scale };
        let mut mask = Vec::with_capacity(n + 1);
        while mask.len() < n {
            let bits = rng.next_u64();
            mask.extend([keep(bits >> 40), keep((bits >> 16) & 0xFF_FFFF)]);
        }
        mask.truncate(n);
        Some(mask)
    }

    pub fn forward(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        match self.mask(x.elem_count(), rng) {
            Some(mask) => x * Tensor::from_vec(mask, x.shape(), x.device())?,
            None => Ok(x.clone()),
        }
    }
}
