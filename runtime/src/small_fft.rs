//! [`RealFft`]: a forward FFT of real rows of one fixed length, planned once, for the runtime built
//! without rustfft (`--no-default-features`, the small robot library): mixed-radix Cooley–Tukey,
//! decimation in time, radices 4, 2, 3 and 5 and any other prime factor by its definition, its
//! twiddles computed in f64 once. The spectral head's lengths are a touch's frames (BioTac's
//! 400 = 4 · 4 · 5 · 5, iCub's 75 = 3 · 5 · 5), where it costs `n · Σ radices` products, not the
//! definition's `n²`; a row of even length is transformed as a complex row of half its length
//! (its even values the real parts, its odd ones the imaginary), then the two halves' transforms
//! are separated. rustfft is faster still and larger; what each costs: docs/deploy.md.

/// A complex value: real and imaginary parts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Complex {
    pub re: f32,
    pub im: f32,
}

impl Complex {
    fn mul(self, o: Complex) -> Complex {
        Complex { re: self.re * o.re - self.im * o.im, im: self.re * o.im + self.im * o.re }
    }

    fn add(self, o: Complex) -> Complex {
        Complex { re: self.re + o.re, im: self.im + o.im }
    }

    fn sub(self, o: Complex) -> Complex {
        Complex { re: self.re - o.re, im: self.im - o.im }
    }

    fn conj(self) -> Complex {
        Complex { re: self.re, im: -self.im }
    }

    fn scale(self, v: f32) -> Complex {
        Complex { re: self.re * v, im: self.im * v }
    }

    /// `self · (−i)`.
    fn times_minus_i(self) -> Complex {
        Complex { re: self.im, im: -self.re }
    }
}

/// The forward transform `X_f = Σ x_k e^{−2πi f k / n}` of rows of `n` values.
#[derive(Clone, Debug)]
pub(crate) struct SmallFft {
    n: usize,
    /// Each level of the recursion, the whole length's first.
    levels: Vec<Level>,
}

/// One level of the recursion: `p` transforms of length `m` combined into one of `p · m`.
#[derive(Clone, Debug)]
struct Level {
    p: usize,
    m: usize,
    /// `W^{q k}` (`W = e^{−2πi / (p m)}`) at `[k · p + q]`: what the `q`th transform's `k`th value
    /// is multiplied by.
    twiddles: Vec<Complex>,
    /// `e^{−2πi q r / p}` at `[r · p + q]`.
    roots: Vec<Complex>,
}

/// `sin(2π/3)`, and `cos` and `sin` of `2π/5` and `4π/5`: the radix-3 and radix-5 butterflies'
/// constants (f64's, rounded).
const SIN_THIRD: f32 = 0.866_025_4;
const COS_FIFTH: [f32; 2] = [0.309_017, -0.809_017];
const SIN_FIFTH: [f32; 2] = [0.951_056_5, 0.587_785_24];

/// The widest radix a butterfly combines on the stack; a wider prime factor takes the heap.
const STACK_RADIX: usize = 8;

impl SmallFft {
    pub(crate) fn new(n: usize) -> Self {
        let root = |j: usize, len: usize| {
            let angle = -2.0 * std::f64::consts::PI * j as f64 / len as f64;
            Complex { re: angle.cos() as f32, im: angle.sin() as f32 }
        };
        let mut len = n;
        let levels = factors(n)
            .into_iter()
            .map(|p| {
                let m = len / p;
                let twiddles = (0..m * p).map(|i| root((i % p) * (i / p), len)).collect();
                let roots = (0..p * p).map(|i| root((i % p) * (i / p) % p, p)).collect();
                len = m;
                Level { p, m, twiddles, roots }
            })
            .collect();
        Self { n, levels }
    }

    /// The transform of `input` (`n` values) into `out` (`n` values).
    pub(crate) fn transform(&self, input: &[Complex], out: &mut [Complex]) {
        assert!(input.len() == self.n && out.len() == self.n, "rows of the planned length");
        match self.n {
            0 => {}
            1 => out[0] = input[0],
            _ => self.step(input, 1, out, 0),
        }
    }

    /// The transform at `level` of the values `input[0], input[stride], …` into `out`.
    fn step(&self, input: &[Complex], stride: usize, out: &mut [Complex], level: usize) {
        let Level { p, m, twiddles, roots } = &self.levels[level];
        let (p, m) = (*p, *m);
        // The p transforms of length m, of the values q, q + p, q + 2p, … (by `stride`); of
        // length 1 at the last level, the values themselves.
        for q in 0..p {
            match level + 1 < self.levels.len() {
                true => self.step(&input[q * stride..], stride * p, &mut out[q * m..(q + 1) * m], level + 1),
                false => out[q] = input[q * stride],
            }
        }
        // Their butterflies: X[k + r m] = Σ_q e^{−2πi q r / p} · W^{q k} Y_q[k].
        let mut stack = [Complex::default(); STACK_RADIX];
        let mut heap = Vec::new();
        let column: &mut [Complex] = match p <= STACK_RADIX {
            true => &mut stack[..p],
            false => {
                heap.resize(p, Complex::default());
                &mut heap
            }
        };
        for (k, w) in twiddles.chunks_exact(p).enumerate() {
            // W^{q k} is 1 for q = 0 and for k = 0.
            column[0] = out[k];
            for (q, c) in column.iter_mut().enumerate().skip(1) {
                *c = if k == 0 { out[q * m] } else { out[q * m + k].mul(w[q]) };
            }
            match p {
                2 => {
                    out[k] = column[0].add(column[1]);
                    out[k + m] = column[0].sub(column[1]);
                }
                4 => {
                    // e^{−2πi q r / 4}: 1, −i, −1, i.
                    let (a, b) = (column[0].add(column[2]), column[0].sub(column[2]));
                    let (c, d) = (column[1].add(column[3]), column[1].sub(column[3]).times_minus_i());
                    out[k] = a.add(c);
                    out[k + m] = b.add(d);
                    out[k + 2 * m] = a.sub(c);
                    out[k + 3 * m] = b.sub(d);
                }
                3 => {
                    // e^{−2πi/3} = −½ − i √3/2.
                    let (b, d) = (column[1].add(column[2]), column[1].sub(column[2]));
                    let t = column[0].sub(b.scale(0.5));
                    let u = d.scale(SIN_THIRD).times_minus_i();
                    out[k] = column[0].add(b);
                    out[k + m] = t.add(u);
                    out[k + 2 * m] = t.sub(u);
                }
                5 => {
                    let (b1, b2) = (column[1].add(column[4]), column[2].add(column[3]));
                    let (d1, d2) = (column[1].sub(column[4]), column[2].sub(column[3]));
                    let t1 = column[0].add(b1.scale(COS_FIFTH[0])).add(b2.scale(COS_FIFTH[1]));
                    let t2 = column[0].add(b1.scale(COS_FIFTH[1])).add(b2.scale(COS_FIFTH[0]));
                    let u1 = d1.scale(SIN_FIFTH[0]).add(d2.scale(SIN_FIFTH[1])).times_minus_i();
                    let u2 = d1.scale(SIN_FIFTH[1]).sub(d2.scale(SIN_FIFTH[0])).times_minus_i();
                    out[k] = column[0].add(b1).add(b2);
                    out[k + m] = t1.add(u1);
                    out[k + 2 * m] = t2.add(u2);
                    out[k + 3 * m] = t2.sub(u2);
                    out[k + 4 * m] = t1.sub(u1);
                }
                _ => {
                    for (r, roots) in roots.chunks_exact(p).enumerate() {
                        let sum = column.iter().zip(roots).skip(1).fold(column[0], |s, (c, w)| s.add(c.mul(*w)));
                        out[k + r * m] = sum;
                    }
                }
            }
        }
    }
}

/// The forward transform of real rows of `n` values, all `n` frequencies (the DFT op's two-sided
/// output).
#[derive(Clone, Debug)]
pub(crate) struct RealFft {
    n: usize,
    inner: Inner,
}

#[derive(Clone, Debug)]
enum Inner {
    /// An even length: the complex transform of half of it, and `e^{−2πi f / n}` for `f < n / 2`.
    Half { fft: SmallFft, twiddles: Vec<Complex> },
    /// An odd one: the complex transform of the whole.
    Whole(SmallFft),
}

impl RealFft {
    pub(crate) fn new(n: usize) -> Self {
        let inner = match n >= 2 && n.is_multiple_of(2) {
            true => {
                let twiddles = (0..n / 2)
                    .map(|f| {
                        let angle = -2.0 * std::f64::consts::PI * f as f64 / n as f64;
                        Complex { re: angle.cos() as f32, im: angle.sin() as f32 }
                    })
                    .collect();
                Inner::Half { fft: SmallFft::new(n / 2), twiddles }
            }
            false => Inner::Whole(SmallFft::new(n)),
        };
        Self { n, inner }
    }

    /// The transform of `x` (`n` values) into `out` (`n` values); `scratch` is resized as needed.
    pub(crate) fn transform(&self, x: &[f32], out: &mut [Complex], scratch: &mut Vec<Complex>) {
        assert!(x.len() == self.n && out.len() == self.n, "rows of the planned length");
        match &self.inner {
            Inner::Whole(fft) => {
                scratch.clear();
                scratch.extend(x.iter().map(|v| Complex { re: *v, im: 0.0 }));
                fft.transform(scratch, out);
            }
            Inner::Half { fft, twiddles } => {
                let half = self.n / 2;
                scratch.clear();
                scratch.extend(x.chunks_exact(2).map(|v| Complex { re: v[0], im: v[1] }));
                scratch.resize(2 * half, Complex::default());
                let (z, transformed) = scratch.split_at_mut(half);
                fft.transform(z, transformed);
                // The even values' transform E_f and the odd ones' O_f from Z_f and Z_{half − f}*:
                // X_f = E_f + W^f O_f, X_{f + half} = E_f − W^f O_f.
                for (f, w) in twiddles.iter().enumerate() {
                    let (a, b) = (transformed[f], transformed[(half - f) % half].conj());
                    let even = a.add(b).scale(0.5);
                    let odd = a.sub(b).times_minus_i().scale(0.5).mul(*w);
                    out[f] = even.add(odd);
                    out[f + half] = even.sub(odd);
                }
            }
        }
    }
}

/// `n`'s radices: fours, then twos, threes, fives, then every other prime factor.
fn factors(mut n: usize) -> Vec<usize> {
    let mut found = Vec::new();
    for p in [4, 2, 3, 5] {
        while n > 1 && n.is_multiple_of(p) {
            found.push(p);
            n /= p;
        }
    }
    let mut p = 7;
    while n > 1 {
        while n.is_multiple_of(p) {
            found.push(p);
            n /= p;
        }
        p += 2;
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every length's transform is the definition's, for lengths of every radix, of primes
    /// above them, and the spectral head's.
    #[test]
    fn every_length_transforms_as_the_definition() {
        for n in [1, 2, 3, 4, 5, 6, 7, 8, 11, 12, 16, 25, 49, 75, 77, 100, 121, 400] {
            let x: Vec<Complex> = (0..n).map(|i| Complex { re: ((i * 7) % 5) as f32 - 1.5, im: ((i * 3) % 4) as f32 * 0.25 }).collect();
            let mut out = vec![Complex::default(); n];
            SmallFft::new(n).transform(&x, &mut out);
            for (f, got) in out.iter().enumerate() {
                let (mut re, mut im) = (0.0f64, 0.0f64);
                for (k, v) in x.iter().enumerate() {
                    let angle = -2.0 * std::f64::consts::PI * ((f * k) % n) as f64 / n as f64;
                    re += v.re as f64 * angle.cos() - v.im as f64 * angle.sin();
                    im += v.re as f64 * angle.sin() + v.im as f64 * angle.cos();
                }
                let tolerance = 1e-5 * (n as f64).max(10.0);
                assert!(
                    (got.re as f64 - re).abs() < tolerance && (got.im as f64 - im).abs() < tolerance,
                    "n {n}, frequency {f}: {got:?} against {re} {im}"
                );
            }
        }
    }

    /// A real row's transform, of even and odd lengths, is the complex transform's.
    #[test]
    fn a_real_row_transforms_as_a_complex_one() {
        let mut scratch = Vec::new();
        for n in [1, 2, 3, 10, 75, 76, 400] {
            let x: Vec<f32> = (0..n).map(|i| ((i * 7) % 5) as f32 - 1.5).collect();
            let complex: Vec<Complex> = x.iter().map(|v| Complex { re: *v, im: 0.0 }).collect();
            let (mut want, mut got) = (vec![Complex::default(); n], vec![Complex::default(); n]);
            SmallFft::new(n).transform(&complex, &mut want);
            RealFft::new(n).transform(&x, &mut got, &mut scratch);
            for (f, (a, b)) in got.iter().zip(&want).enumerate() {
                assert!((a.re - b.re).abs() < 1e-3 && (a.im - b.im).abs() < 1e-3, "n {n}, frequency {f}: {a:?} against {b:?}");
            }
        }
    }

    #[test]
    fn lengths_factor_into_small_radices_first() {
        assert_eq!(factors(400), [4, 4, 5, 5]);
        assert_eq!(factors(75), [3, 5, 5]);
        assert_eq!(factors(2 * 7 * 11), [2, 7, 11]);
        assert_eq!(factors(1), Vec::<usize>::new());
    }
}
