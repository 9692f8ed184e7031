//! A small seeded random number generator (SplitMix64). candle cannot seed its CPU generator, so
//! everything random in training (initialisation, dropout, shuffling, augmentation) draws from this
//! one, which makes a fixed seed give the same run.

/// SplitMix64: tiny, fast and good enough for initialisation, dropout and shuffling. Its state
/// moves by one constant a draw, so any point of its stream is reached at once ([`Rng::ahead`]).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Rng {
    state: u64,
}

/// What SplitMix64 adds to its state at each draw.
const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self { state: seed ^ 0x5DEE_CE66_D1CE_4E5B }
    }

    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GAMMA);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// The generator as it will be after `draws` more draws of [`Rng::next_u64`], without
    /// drawing them: a long stream can be drawn in parts that start where they fall in it, each
    /// part's values those of drawing in order.
    pub fn ahead(&self, draws: u64) -> Self {
        Self { state: self.state.wrapping_add(GAMMA.wrapping_mul(draws)) }
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// The draws of [`Rng::next_u64`] one [`Rng::normal`] takes.
    pub const NORMAL_DRAWS: u64 = 2;

    /// Standard normal (Box–Muller), from [`Rng::NORMAL_DRAWS`] draws.
    pub fn normal(&mut self) -> f32 {
        let u1 = 1.0 - self.uniform(); // (0, 1]
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()
    }

    /// Uniform index in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * n as f64) as usize
    }

    /// Fisher–Yates shuffle.
    pub fn shuffle<T>(&mut self, items: &mut [T]) {
        for i in (1..items.len()).rev() {
            items.swap(i, self.below(i + 1));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Rng;

    #[test]
    fn same_seed_same_stream_and_sane_moments() {
        let (mut a, mut b) = (Rng::new(7), Rng::new(7));
        assert!((0..100).all(|_| a.next_u64() == b.next_u64()));
        let n = 20_000;
        let xs: Vec<f32> = (0..n).map(|_| a.normal()).collect();
        let mean = xs.iter().sum::<f32>() / n as f32;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / n as f32;
        assert!(mean.abs() < 0.03 && (var - 1.0).abs() < 0.05, "mean {mean} var {var}");
        let mut v: Vec<usize> = (0..50).collect();
        a.shuffle(&mut v);
        assert_ne!(v, (0..50).collect::<Vec<_>>());
        v.sort();
        assert_eq!(v, (0..50).collect::<Vec<_>>());
    }

    /// A generator moved ahead draws what the one it came from draws after as many draws,
    /// normals included, and drawing on from there agrees too.
    #[test]
    fn ahead_is_where_drawing_in_order_gets_to() {
        let mut a = Rng::new(11);
        let start = a.clone();
        let drawn: Vec<f32> = (0..1000).map(|_| a.normal()).collect();
        let mut part = start.ahead(Rng::NORMAL_DRAWS * 600);
        assert!(drawn[600..].iter().all(|v| v.to_bits() == part.normal().to_bits()));
        let mut b = start.ahead(Rng::NORMAL_DRAWS * 1000);
        assert!((0..10).all(|_| a.next_u64() == b.next_u64()));
        assert_ne!(start.ahead(1).next_u64(), start.clone().next_u64());
    }
}
