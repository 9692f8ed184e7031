//! Resampling a touch in time: what a touch at another sliding speed would have recorded. The
//! robot reads its touches by distance travelled with it ([`crate::read_touch`]), and the trainer
//! with the same code: its import (`pvt3 import --per-distance`) and its time-stretch
//! augmentation (`--aug-stretch`). A frame is the mean of the source over its span (the source read
//! as straight lines between its frames, sampled at about one point per source frame of the span),
//! so that reading faster averages rather than skips: a box filter against aliasing.

/// Fills `out` from `src`, one channel's frames: output frame `t` spans the source from
/// `start + t * step` to `start + (t + 1) * step` (in frames; source frame `j` spans `j..j + 1`,
/// its value at its middle), the ends held beyond the first and last frames.
pub fn resample_into(src: &[f32], start: f64, step: f64, out: &mut [f32]) {
    let last = src.len().saturating_sub(1);
    for (t, o) in out.iter_mut().enumerate() {
        *o = span_mean(|j| src[j], last, start + t as f64 * step, step);
    }
}

/// The mean of a source with frames `0..=last`, read by `value`, over the span from `from` to
/// `from + step`: about one point per source frame of the span, the source read as straight
/// lines between its frames, held beyond its ends.
pub(crate) fn span_mean(value: impl Fn(usize) -> f32, last: usize, from: f64, step: f64) -> f32 {
    let at = |x: f64| -> f64 {
        let x = (x - 0.5).clamp(0.0, last as f64);
        let j = x.floor() as usize;
        let f = x - j as f64;
        value(j) as f64 * (1.0 - f) + value((j + 1).min(last)) as f64 * f
    };
    let points = points(step);
    let sum: f64 = (0..points).map(|k| at(position(from, step, points, k))).sum();
    (sum / points as f64) as f32
}

/// The last source frame [`span_mean`] reads for the span from `from` to `from + step`, the
/// source's end not reached: the span can be read once that frame has arrived, as a stream
/// reads it ([`crate::TouchReader`]).
pub(crate) fn span_reads_up_to(from: f64, step: f64) -> usize {
    let points = points(step);
    let x = position(from, step, points, points - 1) - 0.5;
    x.max(0.0).floor() as usize + 1
}

/// Points averaged per output frame: about one per source frame it spans.
fn points(step: f64) -> usize {
    step.ceil().max(1.0) as usize
}

fn position(from: f64, step: f64, points: usize, k: usize) -> f64 {
    from + (k as f64 + 0.5) / points as f64 * step
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The whole of `src` as `len` frames.
    fn resample(src: &[f32], len: usize) -> Vec<f32> {
        let mut out = vec![0.0; len];
        resample_into(src, 0.0, src.len() as f64 / len as f64, &mut out);
        out
    }

    #[test]
    fn the_same_rate_copies_and_halving_it_averages_pairs() {
        let src = [1.0, 3.0, 2.0, 6.0, 4.0, 0.0];
        assert_eq!(resample(&src, 6), src);
        assert_eq!(resample(&src, 3), [2.0, 4.0, 2.0]);
    }

    #[test]
    fn a_sine_keeps_its_cycles_per_touch_at_any_length() {
        // A touch of 400 frames holding 10 cycles, read as 100 and as 1000 frames: still 10 cycles
        // (9 rising zero crossings after the first), its amplitude about kept (a box of 4 frames
        // of a 40-frame cycle keeps 0.98 of it, and 10 frames a cycle sample its peak within 18°).
        let rising = |v: &[f32]| v.windows(2).filter(|w| w[0] < 0.0 && w[1] >= 0.0).count();
        let src: Vec<f32> = (0..400).map(|t| (2.0 * std::f32::consts::PI * 10.0 * (t as f32 + 0.5) / 400.0).sin()).collect();
        assert_eq!(rising(&src), 9);
        for (len, least) in [(100, 0.9), (1000, 0.99)] {
            let out = resample(&src, len);
            assert_eq!(rising(&out), 9, "{len} frames");
            let peak = out.iter().fold(0f32, |m, v| m.max(v.abs()));
            assert!(peak > least && peak <= 1.0, "{len} frames: peak {peak}");
        }
    }

    #[test]
    fn a_window_reads_from_its_start_at_its_step() {
        let src: Vec<f32> = (0..20).map(|t| t as f32).collect();
        let mut out = [0.0; 4];
        // A ramp read at half speed from frame 4: frames 4, 4.5, 5, 5.5 (their middles).
        resample_into(&src, 4.0, 0.5, &mut out);
        assert_eq!(out, [3.75, 4.25, 4.75, 5.25]);
    }
}
