//! Each augmentation of a window changes what it says it changes, and nothing else.

use pvt3_models::Rng;

use super::*;
use crate::options::TrainOptions;

#[test]
fn scaling_multiplies_the_raw_readings_of_every_channel_alike() {
    let opts = Augmentation { scale: 1.0, gain: 0.0, noise: 0.0, ..TrainOptions::default().augmentation };
    let norm = Normalization { mean: vec![100.0, -4.0], std: vec![10.0, 2.0], frames: 3 };
    let raw = [90.0, 100.0, 130.0, -6.0, -4.0, 0.0];
    let mut sample = Vec::new();
    norm.apply_into(&raw, &mut sample);
    let mut rng = Rng::new(5);
    let mut factors = Vec::new();
    for _ in 0..40 {
        let mut s = sample.clone();
        augment(&mut s, &norm, [norm.mean.len(), 1, 1], &opts, &mut rng);
        // Back to raw readings: each is the original times one factor k in [1/2, 2].
        let back: Vec<f32> = s.iter().enumerate().map(|(i, z)| z * norm.std[i / 3] + norm.mean[i / 3]).collect();
        let k = back[0] / raw[0];
        assert!((0.5..=2.0).contains(&k), "{k}");
        for (b, r) in back.iter().zip(raw) {
            assert!((b - k * r).abs() < 1e-3, "{back:?} is not {k} × {raw:?}");
        }
        factors.push(k);
    }
    assert!(factors.iter().any(|k| *k < 0.8) && factors.iter().any(|k| *k > 1.25), "{factors:?}");
}

#[test]
fn channel_scaling_multiplies_each_channels_raw_readings_by_a_factor_of_its_own() {
    let opts = Augmentation { channel_scale: 0.2, gain: 0.0, noise: 0.0, ..TrainOptions::default().augmentation };
    let norm = Normalization { mean: vec![100.0, -4.0, 50.0], std: vec![10.0, 2.0, 5.0], frames: 3 };
    let raw = [90.0, 100.0, 130.0, -6.0, -4.0, -1.0, 40.0, 55.0, 60.0];
    let mut sample = Vec::new();
    norm.apply_into(&raw, &mut sample);
    let mut rng = Rng::new(5);
    let mut apart = 0;
    for _ in 0..40 {
        let mut s = sample.clone();
        augment(&mut s, &norm, [norm.mean.len(), 1, 1], &opts, &mut rng);
        let back: Vec<f32> = s.iter().enumerate().map(|(i, z)| z * norm.std[i / 3] + norm.mean[i / 3]).collect();
        let factors: Vec<f32> = (0..3).map(|c| back[3 * c] / raw[3 * c]).collect();
        for (c, k) in factors.iter().enumerate() {
            assert!((1.0 / 1.2 - 1e-4..=1.2 + 1e-4).contains(k), "{k}");
            for t in 0..3 {
                let (b, r) = (back[3 * c + t], raw[3 * c + t]);
                assert!((b - k * r).abs() < 1e-3, "channel {c}: {back:?} is not {k} × {raw:?}");
            }
        }
        apart += usize::from((factors[0] - factors[2]).abs() > 0.02);
    }
    assert!(apart > 20, "the channels' factors differ: {apart} of 40");
}

#[test]
fn vibration_scales_each_channel_about_its_window_mean_and_keeps_the_level() {
    let opts = Augmentation { vibration: 1.0, gain: 0.0, noise: 0.0, ..TrainOptions::default().augmentation };
    let norm = Normalization { mean: vec![0.0; 2], std: vec![1.0; 2], frames: 4 };
    let sample = [1.0, 3.0, 2.0, 6.0, -1.0, -1.0, 1.0, 5.0];
    let mut rng = Rng::new(9);
    let mut factors = Vec::new();
    for _ in 0..40 {
        let mut s = sample;
        augment(&mut s, &norm, [norm.mean.len(), 1, 1], &opts, &mut rng);
        let k = (s[1] - s[0]) / (sample[1] - sample[0]);
        assert!((0.5..=2.0).contains(&k), "{k}");
        for (row, original) in s.chunks(4).zip(sample.chunks(4)) {
            let (mean, was) = (row.iter().sum::<f32>() / 4.0, original.iter().sum::<f32>() / 4.0);
            assert!((mean - was).abs() < 1e-5, "the level is kept: {mean} against {was}");
            for (v, o) in row.iter().zip(original) {
                assert!((v - mean - k * (o - was)).abs() < 1e-5, "{row:?} is not {original:?} about its mean × {k}");
            }
        }
        factors.push(k);
    }
    assert!(factors.iter().any(|k| *k < 0.8) && factors.iter().any(|k| *k > 1.25), "{factors:?}");
}

#[test]
fn time_shift_moves_frames_and_repeats_the_edge() {
    let opts = Augmentation { shift: 2, gain: 0.0, noise: 0.0, ..TrainOptions::default().augmentation };
    let mut rng = Rng::new(1);
    let mut seen = std::collections::BTreeSet::new();
    for _ in 0..50 {
        let mut sample: Vec<f32> = (0..10).map(|t| t as f32).collect(); // two channels of 5 frames
        augment(&mut sample, &Normalization { mean: vec![0.0; 2], std: vec![1.0; 2], frames: 5 }, [2, 1, 1], &opts, &mut rng);
        let shift = 2 - sample[2] as isize;
        let expected: Vec<f32> = (0..10).map(|i| ((i % 5) as isize - shift).clamp(0, 4) as f32 + (i / 5 * 5) as f32).collect();
        assert_eq!(sample, expected);
        seen.insert(shift);
    }
    assert_eq!(seen.into_iter().collect::<Vec<_>>(), vec![-2, -1, 0, 1, 2]);
}

#[test]
fn reversal_plays_each_channel_backwards_as_often_as_asked() {
    let opts = Augmentation { reverse: 0.5, gain: 0.0, noise: 0.0, ..TrainOptions::default().augmentation };
    let norm = Normalization { mean: vec![0.0; 2], std: vec![1.0; 2], frames: 5 };
    let forward: Vec<f32> = (0..10).map(|t| t as f32).collect(); // two channels of 5 frames
    let backward = [4.0, 3.0, 2.0, 1.0, 0.0, 9.0, 8.0, 7.0, 6.0, 5.0];
    let mut rng = Rng::new(3);
    let mut reversed = 0;
    for _ in 0..200 {
        let mut sample = forward.clone();
        augment(&mut sample, &norm, [norm.mean.len(), 1, 1], &opts, &mut rng);
        if sample == backward {
            reversed += 1;
        } else {
            assert_eq!(sample, forward);
        }
    }
    assert!((70..=130).contains(&reversed), "{reversed} of 200 reversed");
    // Off, it draws nothing: the gain's draw is the only one, as before the option was.
    let off = Augmentation { reverse: 0.0, ..opts };
    let (mut a, mut b) = (Rng::new(9), Rng::new(9));
    augment(&mut forward.clone(), &norm, [norm.mean.len(), 1, 1], &off, &mut a);
    b.uniform();
    assert_eq!(a.uniform(), b.uniform());
}

/// A 3 × 4 image of `colours` colours and 2 frames, each pixel's raw value 10 · row + column
/// (+ 100 · colour + the frame) and normalised with its own mean and deviation, augmented 200
/// times as `opts` asks; for each, the (row, column) moves of `moves` whose source pixels, read
/// back raw, it shows.
fn images_found<M: Copy + Ord + std::fmt::Debug>(
    opts: &Augmentation,
    colours: usize,
    moves: &[M],
    source: impl Fn(M, usize, usize) -> (usize, usize),
) -> std::collections::BTreeSet<M> {
    let (h, w, frames) = (3, 4, 2);
    let channels = h * w * colours;
    let mean: Vec<f32> = (0..channels).map(|p| p as f32).collect();
    let std: Vec<f32> = (0..channels).map(|p| 1.0 + p as f32 / 4.0).collect();
    let norm = Normalization { mean, std, frames };
    let raw = |y: usize, x: usize, colour: usize, t: usize| (10 * y + x + 100 * colour + t) as f32;
    let pixel = |p: usize| (p / (w * colours), p / colours % w, p % colours);
    let image: Vec<f32> = (0..channels)
        .flat_map(|p| (0..frames).map(move |t| (p, t)))
        .map(|(p, t)| {
            let (y, x, colour) = pixel(p);
            raw(y, x, colour, t)
        })
        .collect();
    let mut sample = Vec::new();
    norm.apply_into(&image, &mut sample);
    let mut rng = Rng::new(5);
    (0..200)
        .map(|_| {
            let mut s = sample.clone();
            augment(&mut s, &norm, [h, w, colours], opts, &mut rng);
            let back: Vec<f32> = s.iter().enumerate().map(|(i, z)| z * norm.std[i / frames] + norm.mean[i / frames]).collect();
            *moves
                .iter()
                .find(|&&m| {
                    (0..channels * frames).all(|i| {
                        let ((y, x, colour), t) = (pixel(i / frames), i % frames);
                        let (sy, sx) = source(m, y, x);
                        (back[i] - raw(sy, sx, colour, t)).abs() < 1e-4
                    })
                })
                .expect("the image is one of the moves")
        })
        .collect()
}

#[test]
fn translation_moves_the_raw_image_and_normalises_each_pixel_as_its_own() {
    let opts = Augmentation { translate: 2, gain: 0.0, noise: 0.0, ..TrainOptions::default().augmentation };
    let moves: Vec<(isize, isize)> = (-2..=2).flat_map(|dy| (-2..=2).map(move |dx| (dy, dx))).collect();
    // Moved by (dy, dx), edge pixels repeated.
    let from = |at: usize, len: isize, by: isize| (at as isize - by).clamp(0, len - 1) as usize;
    let found = images_found(&opts, 1, &moves, |(dy, dx), y, x| (from(y, 3, dy), from(x, 4, dx)));
    assert_eq!(found.len(), 25, "every move of up to 2 pixels each way drawn: {found:?}");
}

#[test]
fn mirroring_flips_the_raw_image_by_rows_columns_or_both_and_keeps_its_colours() {
    let opts = Augmentation { flip: 0.5, gain: 0.0, noise: 0.0, ..TrainOptions::default().augmentation };
    let mirrors = [(false, false), (false, true), (true, false), (true, true)];
    let found = images_found(&opts, 2, &mirrors, |(rows, columns), y, x| (if rows { 2 - y } else { y }, if columns { 3 - x } else { x }));
    assert_eq!(found.len(), 4, "as it was, and mirrored left to right, top to bottom and both: {found:?}");
}

/// A camera-sized window's noise is drawn in parallel parts, each from where it falls in the
/// stream: bit for bit the values, and the generator's state after, of drawing them in order.
#[test]
fn noise_drawn_in_parts_is_noise_drawn_in_order() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
    let (gain, noise) = (1.1_f32, 0.05_f32);
    let window: Vec<f32> = (0..3 * NOISE_PART + 17).map(|i| (i % 101) as f32 / 7.0).collect();
    let mut in_order = Rng::new(9);
    let expected: Vec<f32> = window.iter().map(|v| v * gain + noise * in_order.normal()).collect();
    let mut in_parts = Rng::new(9);
    let mut drawn = window.clone();
    pool.install(|| gain_and_noise(&mut drawn, gain, noise, &mut in_parts));
    assert!(drawn.iter().zip(&expected).all(|(a, b)| a.to_bits() == b.to_bits()));
    assert_eq!(in_parts.next_u64(), in_order.next_u64());
}
