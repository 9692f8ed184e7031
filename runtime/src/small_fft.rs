//! [`RealFft`]: a forward FFT of real rows of one fixed length, planned once, for the runtime built
//! without rustfft (`--no-default-features`, the small robot library): mixed-radix Cooley–Tukey,
//! decimation in time, radices 4, 2, 3 and 5 and any other prime factor by its definition, its
//! twiddles computed in f64 once. The spectral head's lengths are a touch's frames (BioTac's
//! 400 = 4 · 4 · 5 · 5, iCub's 75 = 3 · 5 · 5), where it costs `n · Σ radices` products, not the
//! definition's `n²`; a row of even length is transformed as a complex row of half its length
//! (its even values the real parts, its odd ones the imaginary), then the two halves' transforms
//! are separated. Rows are transformed [`LANES`] at a time, side by side, so that each butterfly
//! is one vector operation for all of them (a touch's channels are the rows: BioTac's 19). rustfft
//! is faster still and larger; what each costs: docs/deploy.md.

use std::array;

use wide::f32x4;

/// How many rows are transformed side by side: one SIMD register of f32 on x86-64 (SSE) and
/// on aarch64 (NEON).
const LANES: usize = 4;

/// A complex constant: real and imaginary parts.
#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f32,
    im: f32,
}

impl Complex {
    /// `e^{−2πi j / len}`, computed in f64.
    fn root(j: usize, len: usize) -> Complex {
        let angle = -2.0 * std::f64::consts::PI * j as f64 / len as f64;
        Complex { re: angle.cos() as f32, im: angle.sin() as f32 }
    }
}

/// One complex value of [`LANES`] rows: each operation is one vector instruction or two.
#[derive(Clone, Copy, Default)]
struct Lanes {
    re: f32x4,
    im: f32x4,
}

impl Lanes {
    fn mul(self, w: Complex) -> Lanes {
        let (wr, wi) = (f32x4::splat(w.re), f32x4::splat(w.im));
        Lanes { re: self.re * wr - self.im * wi, im: self.re * wi + self.im * wr }
    }

    fn add(self, o: Lanes) -> Lanes {
        Lanes { re: self.re + o.re, im: self.im + o.im }
    }

    fn sub(self, o: Lanes) -> Lanes {
        Lanes { re: self.re - o.re, im: self.im - o.im }
    }

    fn conj(self) -> Lanes {
        Lanes { re: self.re, im: -self.im }
    }

    fn scale(self, v: f32) -> Lanes {
        let v = f32x4::splat(v);
        Lanes { re: self.re * v, im: self.im * v }
    }

    /// `self · (−i)`.
    fn times_minus_i(self) -> Lanes {
        Lanes { re: self.im, im: -self.re }
    }
}

/// The forward transform `X_f = Σ x_k e^{−2πi f k / n}` of rows of `n` values.
#[derive(Clone, Debug)]
struct SmallFft {
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

impl SmallFft {
    fn new(n: usize) -> Self {
        let mut len = n;
        let levels = factors(n)
            .into_iter()
            .map(|p| {
                let m = len / p;
                let twiddles = (0..m * p).map(|i| Complex::root((i % p) * (i / p), len)).collect();
                let roots = (0..p * p).map(|i| Complex::root((i % p) * (i / p) % p, p)).collect();
                len = m;
                Level { p, m, twiddles, roots }
            })
            .collect();
        Self { n, levels }
    }

    /// The transform of `input` (`n` values) into `out` (`n` values).
    fn transform(&self, input: &[Lanes], out: &mut [Lanes]) {
        assert!(input.len() == self.n && out.len() == self.n, "rows of the planned length");
        match self.n {
            0 => {}
            1 => out[0] = input[0],
            _ => self.step(input, 1, out, 0),
        }
    }

    /// The transform at `level` of the values `input[0], input[stride], …` into `out`.
    fn step(&self, input: &[Lanes], stride: usize, out: &mut [Lanes], level: usize) {
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
        match p {
            2 => butterflies(out, m, twiddles, |[a, b]| [a.add(b), a.sub(b)]),
            3 => butterflies(out, m, twiddles, radix_3),
            4 => butterflies(out, m, twiddles, radix_4),
            5 => butterflies(out, m, twiddles, radix_5),
            _ => {
                let mut column = vec![Lanes::default(); p];
                for (k, w) in twiddles.chunks_exact(p).enumerate() {
                    for (q, c) in column.iter_mut().enumerate() {
                        *c = out[q * m + k].mul(w[q]);
                    }
                    for (r, roots) in roots.chunks_exact(p).enumerate() {
                        out[k + r * m] = column.iter().zip(roots).skip(1).fold(column[0], |s, (c, w)| s.add(c.mul(*w)));
                    }
                }
            }
        }
    }
}

/// The butterflies of radix `P` over `out`'s `P` transforms of length `m`: for each `k`, the
/// `k`th value of each, times its twiddle, combined by `radix`.
#[inline(always)]
fn butterflies<const P: usize>(out: &mut [Lanes], m: usize, twiddles: &[Complex], radix: impl Fn([Lanes; P]) -> [Lanes; P]) {
    for k in 0..m {
        let mut x = [Lanes::default(); P];
        for q in 0..P {
            x[q] = out[q * m + k].mul(twiddles[k * P + q]);
        }
        let y = radix(x);
        for r in 0..P {
            out[r * m + k] = y[r];
        }
    }
}

/// The radix-3 butterfly; `e^{−2πi/3} = −½ − i √3/2`.
#[inline(always)]
fn radix_3([x0, x1, x2]: [Lanes; 3]) -> [Lanes; 3] {
    let (b, d) = (x1.add(x2), x1.sub(x2));
    let t = x0.sub(b.scale(0.5));
    let u = d.scale(SIN_THIRD).times_minus_i();
    [x0.add(b), t.add(u), t.sub(u)]
}

/// The radix-4 butterfly; `e^{−2πi q r / 4}`: 1, −i, −1, i.
#[inline(always)]
fn radix_4([x0, x1, x2, x3]: [Lanes; 4]) -> [Lanes; 4] {
    let (a, b) = (x0.add(x2), x0.sub(x2));
    let (c, d) = (x1.add(x3), x1.sub(x3).times_minus_i());
    [a.add(c), b.add(d), a.sub(c), b.sub(d)]
}

/// The radix-5 butterfly, by the symmetry of `e^{−2πi q r / 5}` in `q` and `5 − q`.
#[inline(always)]
fn radix_5([x0, x1, x2, x3, x4]: [Lanes; 5]) -> [Lanes; 5] {
    let (b1, b2) = (x1.add(x4), x2.add(x3));
    let (d1, d2) = (x1.sub(x4), x2.sub(x3));
    let t1 = x0.add(b1.scale(COS_FIFTH[0])).add(b2.scale(COS_FIFTH[1]));
    let t2 = x0.add(b1.scale(COS_FIFTH[1])).add(b2.scale(COS_FIFTH[0]));
    let u1 = d1.scale(SIN_FIFTH[0]).add(d2.scale(SIN_FIFTH[1])).times_minus_i();
    let u2 = d1.scale(SIN_FIFTH[1]).sub(d2.scale(SIN_FIFTH[0])).times_minus_i();
    [x0.add(b1).add(b2), t1.add(u1), t2.add(u2), t2.sub(u2), t1.sub(u1)]
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
            true => Inner::Half { fft: SmallFft::new(n / 2), twiddles: (0..n / 2).map(|f| Complex::root(f, n)).collect() },
            false => Inner::Whole(SmallFft::new(n)),
        };
        Self { n, inner }
    }

    /// The transform of each row of `n` values of `x` into `out`: row by row, frequency by
    /// frequency, its real and imaginary parts in turn (`2 · x.len()` values).
    pub(crate) fn transform(&self, x: &[f32], out: &mut [f32]) {
        let n = self.n;
        assert!(x.len().is_multiple_of(n.max(1)) && out.len() == 2 * x.len(), "rows of the planned length");
        if n == 0 {
            return;
        }
        // A last group's missing rows read zeros and write where no one reads.
        let (zeros, mut unused) = (vec![0.0; n], vec![0.0; 2 * n * LANES]);
        let (mut columns, mut scratch, mut spectrum) = (Vec::new(), Scratch::default(), vec![Lanes::default(); n]);
        for (rows, outs) in x.chunks(LANES * n).zip(out.chunks_mut(2 * LANES * n)) {
            let mut rows = rows.chunks_exact(n);
            let rows: [&[f32]; LANES] = array::from_fn(|_| rows.next().unwrap_or(&zeros));
            let (mut outs, mut spare) = (outs.chunks_exact_mut(2 * n), unused.chunks_exact_mut(2 * n));
            let mut outs: [&mut [f32]; LANES] = array::from_fn(|_| outs.next().or_else(|| spare.next()).expect("a row for each lane"));
            side_by_side(&rows, &mut columns);
            self.spectrum(&columns, &mut scratch, &mut spectrum);
            write_rows(&spectrum, &mut outs);
        }
    }

    /// The spectrum of [`LANES`] rows from their values side by side (`columns[k]`: the rows'
    /// `k`th values).
    fn spectrum(&self, columns: &[f32x4], scratch: &mut Scratch, spectrum: &mut [Lanes]) {
        let Scratch { values, transformed } = scratch;
        values.clear();
        match &self.inner {
            Inner::Whole(fft) => {
                values.extend(columns.iter().map(|re| Lanes { re: *re, im: f32x4::ZERO }));
                fft.transform(values, spectrum);
            }
            Inner::Half { fft, twiddles } => {
                let half = self.n / 2;
                values.extend(columns.chunks_exact(2).map(|v| Lanes { re: v[0], im: v[1] }));
                transformed.resize(half, Lanes::default());
                fft.transform(values, transformed);
                // The even values' transform E_f and the odd ones' O_f from Z_f and
                // Z_{half − f}*: X_f = E_f + W^f O_f, X_{f + half} = E_f − W^f O_f.
                for (f, w) in twiddles.iter().enumerate() {
                    let (a, b) = (transformed[f], transformed[(half - f) % half].conj());
                    let even = a.add(b).scale(0.5);
                    let odd = a.sub(b).times_minus_i().scale(0.5).mul(*w);
                    spectrum[f] = even.add(odd);
                    spectrum[f + half] = even.sub(odd);
                }
            }
        }
    }
}

/// What [`RealFft::spectrum`] reuses from one group of rows to the next.
#[derive(Default)]
struct Scratch {
    /// The complex values transformed.
    values: Vec<Lanes>,
    /// Their transform, of an even length's half.
    transformed: Vec<Lanes>,
}

/// Each row's spectrum (`spectrum[f]`: the rows' `f`th frequency) into its row of `outs`, real
/// and imaginary parts in turn: two frequencies at a time, since `[re f, im f, re f + 1,
/// im f + 1]` of each row is one transpose of four vectors; an odd length's last frequency alone.
fn write_rows(spectrum: &[Lanes], outs: &mut [&mut [f32]; LANES]) {
    let n = spectrum.len();
    for f in (0..n - n % 2).step_by(2) {
        let (a, b) = (spectrum[f], spectrum[f + 1]);
        for (row, values) in outs.iter_mut().zip(f32x4::transpose([a.re, a.im, b.re, b.im])) {
            let to: &mut [f32; 4] = (&mut row[2 * f..2 * f + 4]).try_into().expect("four values");
            *to = values.to_array();
        }
    }
    if n % 2 == 1 {
        let (re, im) = (spectrum[n - 1].re.to_array(), spectrum[n - 1].im.to_array());
        for (l, row) in outs.iter_mut().enumerate() {
            (row[2 * n - 2], row[2 * n - 1]) = (re[l], im[l]);
        }
    }
}

/// The rows' values side by side into `out`, the rows' `k`th values at `[k]`: four values of each
/// row at a time, by one transpose.
fn side_by_side(rows: &[&[f32]; LANES], out: &mut Vec<f32x4>) {
    let n = rows[0].len();
    out.clear();
    for at in (0..n - n % 4).step_by(4) {
        out.extend(f32x4::transpose([four(rows[0], at), four(rows[1], at), four(rows[2], at), four(rows[3], at)]));
    }
    out.extend((n - n % 4..n).map(|k| f32x4::new([rows[0][k], rows[1][k], rows[2][k], rows[3][k]])));
}

/// `row[at..at + 4]`.
#[inline(always)]
fn four(row: &[f32], at: usize) -> f32x4 {
    f32x4::new([row[at], row[at + 1], row[at + 2], row[at + 3]])
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

    /// The definition's transform of a complex row, in f64.
    fn definition(x: &[(f64, f64)]) -> Vec<(f64, f64)> {
        let n = x.len();
        (0..n)
            .map(|f| {
                x.iter().enumerate().fold((0.0, 0.0), |(re, im), (k, (a, b))| {
                    let angle = -2.0 * std::f64::consts::PI * ((f * k) % n) as f64 / n as f64;
                    (re + a * angle.cos() - b * angle.sin(), im + a * angle.sin() + b * angle.cos())
                })
            })
            .collect()
    }

    /// Every length's transform is the definition's, in every lane, for lengths of every radix,
    /// of primes above them, and the spectral head's.
    #[test]
    fn every_length_transforms_as_the_definition() {
        for n in [1, 2, 3, 4, 5, 6, 7, 8, 11, 12, 16, 25, 49, 75, 77, 100, 121, 400] {
            let row = |l: usize| -> Vec<(f64, f64)> {
                (0..n).map(|i| (((i * 7 + l) % 5) as f64 - 1.5, ((i * 3 + 2 * l) % 4) as f64 * 0.25)).collect()
            };
            let x: Vec<Lanes> = (0..n)
                .map(|i| Lanes { re: array::from_fn(|l| row(l)[i].0 as f32).into(), im: array::from_fn(|l| row(l)[i].1 as f32).into() })
                .collect();
            let mut out = vec![Lanes::default(); n];
            SmallFft::new(n).transform(&x, &mut out);
            for l in 0..LANES {
                for (f, (re, im)) in definition(&row(l)).into_iter().enumerate() {
                    let got = (out[f].re.to_array()[l] as f64, out[f].im.to_array()[l] as f64);
                    let tolerance = 1e-5 * (n as f64).max(10.0);
                    assert!(
                        (got.0 - re).abs() < tolerance && (got.1 - im).abs() < tolerance,
                        "n {n}, lane {l}, frequency {f}: {got:?} against {re} {im}"
                    );
                }
            }
        }
    }

    /// Real rows, of even and odd lengths and as many as fill the lanes or not, transform as
    /// complex ones, each in its place.
    #[test]
    fn real_rows_transform_as_complex_ones() {
        for (rows, n) in [(1, 1), (1, 2), (3, 3), (5, 10), (19, 75), (4, 76), (19, 400)] {
            let x: Vec<f32> = (0..rows * n).map(|i| ((i * 7) % 5) as f32 - 1.5 + (i / n) as f32 * 0.125).collect();
            let mut got = vec![0.0; 2 * rows * n];
            RealFft::new(n).transform(&x, &mut got);
            for (r, values) in x.chunks_exact(n).enumerate() {
                let want = definition(&values.iter().map(|v| (*v as f64, 0.0)).collect::<Vec<_>>());
                for (f, (re, im)) in want.into_iter().enumerate() {
                    let at = 2 * (r * n + f);
                    let tolerance = 1e-5 * (n as f64).max(10.0);
                    assert!(
                        (got[at] as f64 - re).abs() < tolerance && (got[at + 1] as f64 - im).abs() < tolerance,
                        "{rows} rows of {n}: row {r}, frequency {f}: {} {} against {re} {im}",
                        got[at],
                        got[at + 1]
                    );
                }
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
