//! Every network the trainer can fit, behind one type: PVT³ and the paper's two baselines (ViT
//! and RAEC), chosen by [`Config::network`]. Pruning, baking and export are PVT³'s alone. (The
//! robot's `pvt3_runtime::Classifier` runs an exported file; this is the trainable model.)

use candle_core::Tensor;
use candle_nn::{VarBuilder, VarMap};

use crate::raec::Raec;
use crate::vit::Vit;
use crate::{Architecture, Config, Pvt3, Result, Rng};

#[derive(Clone, Debug)]
pub enum Model {
    Pvt3(Pvt3),
    Vit(Vit),
    Raec(Raec),
}

impl Model {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        Ok(match cfg.architecture() {
            Architecture::Pvt3 => Self::Pvt3(Pvt3::new(cfg, vb)?),
            Architecture::Vit => Self::Vit(Vit::new(cfg, vb)?),
            Architecture::Raec => Self::Raec(Raec::new(cfg, vb)?),
        })
    }

    /// A fresh model on the CPU with its variables in a new [`VarMap`], seeded by `seed`.
    pub fn init(cfg: &Config, seed: u64) -> Result<(Self, VarMap)> {
        crate::init::seeded(cfg, seed, Self::new)
    }

    /// Logits `[b, classes]` and the model's own extra training loss (RAEC's weighted
    /// reconstruction error). Pass an `rng` to train (dropout on), `None` to evaluate.
    pub fn forward_with_loss(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<(Tensor, Option<Tensor>)> {
        match self {
            Self::Pvt3(m) => Ok((m.forward(x, rng)?, None)),
            Self::Vit(m) => Ok((m.forward(x, rng)?, None)),
            Self::Raec(m) => m.forward_with_loss(x, rng),
        }
    }

    /// Logits `[b, classes]`.
    pub fn forward(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        Ok(self.forward_with_loss(x, rng)?.0)
    }

    /// The PVT³ network, for what only it does (provisional answers from a prefix of the touch).
    pub fn pvt3(&self, what: &str) -> Result<&Pvt3> {
        match self {
            Self::Pvt3(m) => Ok(m),
            Self::Vit(_) => Err(pvt3_spec::config::pvt3_only(what, Architecture::Vit).into()),
            Self::Raec(_) => Err(pvt3_spec::config::pvt3_only(what, Architecture::Raec).into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use super::Model;
    use crate::{Config, Pvt3Config, Rng};

    /// Gradients reach every parameter (masks included) of every network, through the full
    /// training loss: no op without a backward pass on the way.
    #[test]
    fn every_parameter_gets_a_finite_nonzero_gradient() {
        let configs = [
            Config::icub20(),
            Config { heads: 2, dim_head: 8, tubelet: 3, dropout: 0.1, ..Config::icub20() },
            Config { network: Pvt3Config { spectral_bands: 4, ..Default::default() }.into(), ..Config::icub20() },
            Config { dropout: 0.1, ..Config::preset("vit-icub20").unwrap() },
            Config { dropout: 0.1, ..Config::preset("raec-icub20").unwrap() },
            Config { frames: 40, ..Config::preset("raec-biotac20").unwrap() },
        ];
        for cfg in configs {
            let (model, varmap) = Model::init(&cfg, 1).unwrap();
            let mut rng = Rng::new(2);
            let mut shape = vec![4];
            shape.extend(cfg.sample_shape());
            let data: Vec<f32> = (0..shape.iter().product()).map(|_| rng.normal()).collect();
            let x = Tensor::from_vec(data, shape, &Device::Cpu).unwrap();
            let labels = Tensor::new(&[0u32, 3, 7, 19], &Device::Cpu).unwrap();
            let (logits, extra) = model.forward_with_loss(&x, Some(&mut rng)).unwrap();
            let mut loss = candle_nn::loss::cross_entropy(&logits, &labels).unwrap();
            if let Some(extra) = extra {
                loss = (loss + extra).unwrap();
            }
            let grads = loss.backward().unwrap();
            for (name, var) in varmap.data().lock().unwrap().iter() {
                let g = grads.get(var).unwrap_or_else(|| panic!("{:?} {name} has no gradient", cfg.architecture()));
                let g: Vec<f32> = g.flatten_all().unwrap().to_vec1().unwrap();
                assert!(g.iter().all(|v| v.is_finite()), "{:?} {name} has a non-finite gradient", cfg.architecture());
                assert!(g.iter().any(|v| *v != 0.0), "{:?} {name} has an all-zero gradient", cfg.architecture());
            }
        }
    }
}
