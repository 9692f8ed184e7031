//! `pvt3 bench train`: training throughput of a configuration in candle, timed on the very step
//! function the trainer uses, on random inputs. `bench/train_speed.sh` runs it side by side with
//! the identical model in PyTorch.

use std::time::Instant;

use candle_core::{Device, Tensor};
use pvt3_models::{Config, Rng};
use serde::Serialize;

use crate::options::TrainOptions;
use crate::train::Learner;
use crate::Result;

#[derive(Debug, Serialize)]
pub struct TrainSpeed {
    pub framework: &'static str,
    pub batch_size: usize,
    pub steps: usize,
    pub seconds_per_step: f64,
    pub samples_per_second: f64,
}

/// Times `steps` optimiser steps after `warmup` untimed ones.
pub fn train_speed(cfg: &Config, opts: &TrainOptions, warmup: usize, steps: usize) -> Result<TrainSpeed> {
    let mut learner = Learner::new(cfg, opts, None)?;
    let mut rng = Rng::new(opts.seed);
    let mut shape = vec![opts.optimization.batch_size];
    shape.extend(cfg.sample_shape());
    let n: usize = shape.iter().product();
    let x = Tensor::from_vec((0..n).map(|_| rng.normal()).collect::<Vec<f32>>(), shape, &Device::Cpu)?;
    let labels: Vec<u32> = (0..opts.optimization.batch_size).map(|i| (i % cfg.classes) as u32).collect();
    let y = Tensor::new(labels, &Device::Cpu)?;
    for _ in 0..warmup {
        learner.step(&x, &y, opts, opts.optimization.lr, &mut rng)?;
    }
    let started = Instant::now();
    for _ in 0..steps {
        learner.step(&x, &y, opts, opts.optimization.lr, &mut rng)?;
    }
    let seconds_per_step = started.elapsed().as_secs_f64() / steps.max(1) as f64;
    Ok(TrainSpeed {
        framework: "candle",
        batch_size: opts.optimization.batch_size,
        steps,
        seconds_per_step,
        samples_per_second: opts.optimization.batch_size as f64 / seconds_per_step,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn reports_a_positive_rate() {
        let cfg = pvt3_models::Config { space_depth: 1, time_depth: 1, ..pvt3_models::Config::icub20() };
        let mut opts = crate::options::TrainOptions::default();
        opts.optimization.batch_size = 4;
        let s = super::train_speed(&cfg, &opts, 1, 2).unwrap();
        assert!(s.samples_per_second > 0.0 && s.seconds_per_step > 0.0);
    }
}
