//! Windows: each touch of a split read as the windows of the model's frames, normalised, ready
//! to batch. A touch longer than the window is evaluated as windows every half window
//! ([`window_starts`]; its answer is the mean of their probabilities, [`crate::evaluate`]);
//! training instead draws one window at random from each touch every epoch
//! ([`Samples::cropped`]), an augmentation of where the touch is read.

use candle_core::{Device, Tensor};
use pvt3_models::pvt3::patches::cut_into;
use pvt3_models::{Config, Rng};

use super::augment::log_uniform_factor;
use super::normalization::Normalization;
use super::Dataset;
use crate::Result;

/// The windows of one split: which touch each reads and where, read and normalised only as a
/// batch takes them, so that a camera's 8-bit touches are never held again as f32.
#[derive(Clone, Debug)]
pub struct Samples<'a> {
    data: &'a Dataset,
    norm: Normalization,
    windows: Vec<(usize, Window)>,
    /// Each window's label.
    pub labels: Vec<u32>,
    pub sample_shape: Vec<usize>,
    /// Each window's touch, numbered from 0 in the order of the split (rising, a touch's
    /// windows together).
    pub touches: Vec<usize>,
    /// Each window's frames that are its touch's: all of the window's, but for a test touch
    /// shorter than it, which is answered from the temporal tokens it fills ([`evaluate`]).
    pub filled: Vec<usize>,
}

/// Where in its touch a window reads.
#[derive(Clone, Copy, Debug)]
enum Window {
    /// The model's frames from this one.
    At(usize),
    /// From this (fractional) frame, this many of the touch's frames a model frame, resampled.
    Stretched(f64, f64),
}

/// Where the windows of `frames` frames that evaluate a touch of `len` frames start: every half
/// window from the first frame, and one more that ends at the touch's last frame; one window
/// for a touch of exactly `frames` or fewer.
pub fn window_starts(len: usize, frames: usize) -> Vec<usize> {
    if len <= frames {
        return vec![0];
    }
    let stride = (frames / 2).max(1);
    let last = len - frames;
    let mut starts: Vec<usize> = (0..=last).step_by(stride).collect();
    if starts.last() != Some(&last) {
        starts.push(last);
    }
    starts
}

impl<'a> Samples<'a> {
    /// The `indices` touches of `data`, each read as its evaluation windows ([`window_starts`])
    /// of the `norm.frames` frames the model reads, normalised.
    pub fn new(data: &'a Dataset, indices: &[usize], norm: &Normalization) -> Self {
        let picks = indices.iter().flat_map(|&i| window_starts(data.lengths[i], norm.frames).into_iter().map(move |s| (i, Window::At(s))));
        Self::from_windows(data, picks, norm)
    }

    /// One window of each of the `indices` touches, where `rng` draws it (the whole touch, and
    /// no draw, when it is exactly one window long). With `stretch` > 0 each window is also read
    /// at a random speed, as if the touch had been made faster or slower: it spans `r` times the
    /// model's frames of the touch, `r` log-uniform in [1 / (1 + stretch), 1 + stretch] (at most
    /// the whole touch), resampled to the model's frames ([`pvt3_format::resample`]).
    pub fn cropped(data: &'a Dataset, indices: &[usize], norm: &Normalization, stretch: f64, rng: &mut Rng) -> Self {
        let draw = |i: usize, rng: &mut Rng| {
            let len = data.lengths[i];
            if stretch > 0.0 {
                let r = log_uniform_factor(stretch, rng).min(len as f64 / norm.frames as f64);
                return Window::Stretched(rng.uniform() as f64 * (len as f64 - r * norm.frames as f64), r);
            }
            let spare = len - norm.frames;
            Window::At(if spare == 0 { 0 } else { rng.below(spare + 1) })
        };
        let picks: Vec<(usize, Window)> = indices.iter().map(|&i| (i, draw(i, rng))).collect();
        Self::from_windows(data, picks, norm)
    }

    /// The windows `picks` names, each a touch and where in it; a touch's windows come together.
    fn from_windows(data: &'a Dataset, picks: impl IntoIterator<Item = (usize, Window)>, norm: &Normalization) -> Self {
        let mut sample_shape = data.sample_shape.clone();
        *sample_shape.last_mut().expect("a frame axis") = norm.frames;
        let (mut windows, mut labels, mut touches, mut filled) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (i, at) in picks {
            let touch = match (windows.last(), touches.last()) {
                (Some((p, _)), Some(t)) if *p == i => *t,
                (Some(_), Some(t)) => t + 1,
                _ => 0,
            };
            windows.push((i, at));
            labels.push(data.labels[i]);
            filled.push(data.lengths[i].min(norm.frames));
            touches.push(touch);
        }
        Self { data, norm: norm.clone(), windows, labels, sample_shape, touches, filled }
    }

    /// Appends window `w` as read from its touch, before normalising, to the empty `raw`.
    fn read_into(&self, w: usize, raw: &mut Vec<f32>) {
        let (data, frames) = (self.data, self.norm.frames);
        match self.windows[w] {
            (i, Window::At(start)) => data.window_into(i, start, frames, raw),
            (i, Window::Stretched(start, r)) => {
                let len = data.lengths[i];
                raw.resize(data.sample_len() / data.max_frames() * frames, 0.0);
                for (row, out) in data.sample(i).chunks(data.max_frames()).zip(raw.chunks_mut(frames)) {
                    pvt3_format::resample::resample_into(&row[..len], start, r, out);
                }
            }
        }
    }

    /// Every touch of `data` as one window, as it is: what a test feeds a model.
    #[cfg(test)]
    pub(crate) fn unnormalised(data: &'a Dataset) -> Self {
        let channels = data.sample_len() / data.max_frames();
        let norm = Normalization { mean: vec![0.0; channels], std: vec![1.0; channels], frames: data.max_frames() };
        Self::new(data, &(0..data.len()).collect::<Vec<_>>(), &norm)
    }

    pub fn len(&self) -> usize {
        self.labels.len()
    }

    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    /// A window's image: height, width and colours (1 for a grid of taxels).
    pub fn grid(&self) -> [usize; 3] {
        match self.sample_shape[..] {
            [h, w, c, _] => [h, w, c],
            [h, w, ..] => [h, w, 1],
            _ => unreachable!("a sample shape has 3 or 4 axes"),
        }
    }

    /// Values of one window.
    pub fn sample_len(&self) -> usize {
        self.sample_shape.iter().product()
    }

    /// The temporal tokens of `tubelet` frames each window fills.
    pub fn tokens_filled(&self, tubelet: usize) -> impl Iterator<Item = usize> + '_ {
        self.filled.iter().map(move |f| f / tubelet)
    }

    /// The windows at `rows`, normalised and each passed to `transform`, as a tensor
    /// `[rows, …sample_shape]`, and a label tensor.
    pub fn batch(&self, rows: &[usize], transform: impl FnMut(&mut [f32])) -> Result<(Tensor, Tensor)> {
        self.gather(rows, None, transform)
    }

    /// [`Self::batch`] with each window cut into `cfg`'s patches as it is read,
    /// `[rows, time_tokens, num_patches, patch_dim]`: what [`pvt3_models::Pvt3::patchify`] makes
    /// of the other, without the batch ever being held both ways.
    pub fn cut_batch(&self, rows: &[usize], cfg: &Config, transform: impl FnMut(&mut [f32])) -> Result<(Tensor, Tensor)> {
        self.gather(rows, Some(cfg), transform)
    }

    fn gather(&self, rows: &[usize], cut: Option<&Config>, mut transform: impl FnMut(&mut [f32])) -> Result<(Tensor, Tensor)> {
        let l = self.sample_len();
        let (mut x, mut raw, mut window) = (Vec::with_capacity(rows.len() * l), Vec::with_capacity(l), Vec::new());
        for &r in rows {
            raw.clear();
            self.read_into(r, &mut raw);
            match cut {
                None => {
                    let start = x.len();
                    self.norm.apply_into(&raw, &mut x);
                    transform(&mut x[start..]);
                }
                Some(cfg) => {
                    window.clear();
                    self.norm.apply_into(&raw, &mut window);
                    transform(&mut window);
                    cut_into(cfg, &window, &mut x);
                }
            }
        }
        let mut shape = vec![rows.len()];
        match cut {
            None => shape.extend_from_slice(&self.sample_shape),
            Some(cfg) => shape.extend([cfg.time_tokens(), cfg.num_patches(), cfg.patch_dim()]),
        }
        let labels: Vec<u32> = rows.iter().map(|&r| self.labels[r]).collect();
        Ok((Tensor::from_vec(x, shape, &Device::Cpu)?, Tensor::new(labels, &Device::Cpu)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::frames::Frames;

    #[test]
    fn windows_cover_the_touch_every_half_window_and_end_at_its_end() {
        assert_eq!(window_starts(75, 75), vec![0]);
        assert_eq!(window_starts(10, 4), vec![0, 2, 4, 6]);
        assert_eq!(window_starts(11, 4), vec![0, 2, 4, 6, 7]);
        assert_eq!(window_starts(5, 1), vec![0, 1, 2, 3, 4]);
    }

    #[test]
    fn stretched_windows_read_the_touch_at_another_speed() {
        // One touch of two channels, a ramp of 100 frames (the second the ramp's negative); the
        // model reads 20. A stretched window is a ramp still, its slope the speed it was read at.
        let ramp: Vec<f32> = (0..100).map(|t| t as f32).chain((0..100).map(|t| -(t as f32))).collect();
        let data = Dataset::in_memory(ramp, vec![2, 1, 100], vec![0]);
        let norm = Normalization { mean: vec![0.0; 2], std: vec![1.0; 2], frames: 20 };
        let mut rng = Rng::new(3);
        let mut slopes = Vec::new();
        for _ in 0..30 {
            let s = Samples::cropped(&data, &[0], &norm, 1.0, &mut rng);
            let (x, _) = s.batch(&[0], |_| {}).unwrap();
            assert_eq!((x.dims(), s.sample_shape.as_slice()), (&[1, 2, 1, 20][..], &[2, 1, 20][..]));
            let s = x.flatten_all().unwrap().to_vec1::<f32>().unwrap();
            let slope = (s[19] - s[0]) / 19.0;
            assert!((0.5 - 1e-4..=2.0 + 1e-4).contains(&slope), "{slope}");
            assert!(s[..20].windows(2).all(|w| (w[1] - w[0] - slope).abs() < 1e-3), "a straight ramp: {:?}", &s[..20]);
            assert!(s[..20].iter().all(|v| (0.0..=99.0).contains(v)), "read from within the touch");
            assert!(s[20..].iter().zip(&s[..20]).all(|(b, a)| (a + b).abs() < 1e-4), "every channel alike");
            slopes.push(slope);
        }
        assert!(slopes.iter().any(|s| *s < 0.8) && slopes.iter().any(|s| *s > 1.25), "{slopes:?}");
    }

    #[test]
    fn a_cut_batch_is_the_patches_of_the_batch_each_window_transformed_alike() {
        // Three 8-bit touches of 4 × 6 RGB and 9 frames; the model reads 6 frames in tubelets of 2,
        // patches of 2 × 3. The transform draws from its generator, window by window.
        let cfg = Config { height: 4, width: 6, channels: 3, frames: 6, patch_height: 2, patch_width: 3, tubelet: 2, ..Config::gelsight() };
        let x = Frames::U8 { x: (0..3 * 4 * 6 * 3 * 9).map(|v| (v * 7 % 251) as u8).collect(), background: None };
        let data = Dataset::in_memory(x, vec![4, 6, 3, 9], vec![0, 1, 0]);
        let norm = Normalization { mean: vec![10.0; 72], std: vec![2.0; 72], frames: 6 };
        let set = Samples::cropped(&data, &[0, 1, 2], &norm, 0.0, &mut Rng::new(1));
        let (mut a, mut b) = (Rng::new(2), Rng::new(2));
        let (whole, labels) = set.batch(&[2, 0, 1], |w| w.iter_mut().for_each(|v| *v += a.normal())).unwrap();
        let (cut, cut_labels) = set.cut_batch(&[2, 0, 1], &cfg, |w| w.iter_mut().for_each(|v| *v += b.normal())).unwrap();
        let (model, _) = pvt3_models::Pvt3::init(&cfg, 0).unwrap();
        assert_eq!(cut.dims(), &[3, 3, 4, 36]);
        assert_eq!(
            cut.flatten_all().unwrap().to_vec1::<f32>().unwrap(),
            model.patchify(&whole).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap()
        );
        assert_eq!(cut_labels.to_vec1::<u32>().unwrap(), labels.to_vec1::<u32>().unwrap());
    }
}
