//! The learning-rate schedule: linear warm-up, then cosine decay to a floor.

#[derive(Clone, Debug)]
pub struct Schedule {
    pub peak: f64,
    pub floor: f64,
    pub warmup_steps: usize,
    pub total_steps: usize,
}

impl Schedule {
    /// The schedule of a run of `steps_per_epoch` steps an epoch with the options `opts`.
    pub fn new(opts: &crate::options::Optimization, steps_per_epoch: usize) -> Self {
        Schedule {
            peak: opts.lr,
            floor: opts.lr * opts.lr_floor,
            warmup_steps: opts.warmup_epochs * steps_per_epoch,
            total_steps: opts.epochs * steps_per_epoch,
        }
    }

    /// The learning rate for optimiser step `step` (0-based).
    pub fn at(&self, step: usize) -> f64 {
        if step < self.warmup_steps {
            return self.peak * (step + 1) as f64 / self.warmup_steps as f64;
        }
        let span = self.total_steps.saturating_sub(self.warmup_steps).max(1);
        let progress = ((step - self.warmup_steps) as f64 / span as f64).min(1.0);
        self.floor + 0.5 * (self.peak - self.floor) * (1.0 + (std::f64::consts::PI * progress).cos())
    }
}

#[cfg(test)]
mod tests {
    use super::Schedule;

    #[test]
    fn warms_up_then_decays_to_the_floor() {
        let s = Schedule { peak: 1e-3, floor: 1e-5, warmup_steps: 10, total_steps: 110 };
        assert!((s.at(0) - 1e-4).abs() < 1e-12);
        assert!((s.at(9) - 1e-3).abs() < 1e-12);
        assert!((s.at(10) - 1e-3).abs() < 1e-12);
        assert!((s.at(60) - (1e-3 + 1e-5) / 2.0).abs() < 1e-9);
        assert!((s.at(110) - 1e-5).abs() < 1e-12);
        assert!((1..110).all(|i| s.at(i) <= s.at(i - 1) || i < 10));
    }

    /// A floor at the peak (`--lr-floor 1`) holds the rate after the warm-up.
    #[test]
    fn a_floor_at_the_peak_is_a_constant_rate() {
        let s = Schedule { peak: 5e-4, floor: 5e-4, warmup_steps: 0, total_steps: 100 };
        assert!((0..150).all(|i| (s.at(i) - 5e-4).abs() < 1e-15));
    }
}
