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

    pub fn forward(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        let Some(rng) = rng.filter(|_| self.p > 0.0) else {
            return Ok(x.clone());
        };
        let scale = 1.0 / (1.0 - self.p);
        let p = self.p;
        let mask: Vec<f32> = (0..x.elem_count()).map(|_| if rng.uniform() < p { 0.0 } else { scale }).collect();
        x * Tensor::from_vec(mask, x.shape(), x.device())?
    }
}
