//! One window cut into PVT³'s patches as it is read: the values and order of
//! [`super::Pvt3::patchify`], from a window's own values. A trainer that batches a camera's
//! windows this way holds the batch as f32 once (cut), not twice (as read, and cut).

use crate::Config;

/// Appends window `x` (`[height, width, (channels,) frames]` of `cfg`) to `out` as its patches,
/// `[time_tokens, num_patches, patch_dim]`.
pub fn cut_into(cfg: &Config, x: &[f32], out: &mut Vec<f32>) {
    let (ph, pw, c, tubelet) = (cfg.patch_height, cfg.patch_width, cfg.channels, cfg.tubelet);
    let (w, t, patches, pd) = (cfg.width, cfg.frames, cfg.num_patches(), cfg.patch_dim());
    assert_eq!(x.len(), cfg.height * w * c * t, "a window of {cfg:?}");
    let start = out.len();
    out.resize(start + x.len(), 0.0);
    let out = &mut out[start..];
    // Row by row of the image: a row's values (every column, colour and frame) are read from
    // cache, and each frame's columns of a patch are written as one run.
    for (y, row) in x.chunks_exact(w * c * t).enumerate() {
        let (gy, dy) = (y / ph, y % ph);
        for f in 0..t {
            let (k, dt) = (f / tubelet, f % tubelet);
            for (gx, columns) in row.chunks_exact(pw * c * t).enumerate() {
                let at = (k * patches + gy * (w / pw) + gx) * pd + (dt * ph + dy) * pw * c;
                for (o, v) in out[at..at + pw * c].iter_mut().zip(columns.iter().skip(f).step_by(t)) {
                    *o = *v;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use super::*;
    use crate::Pvt3;

    #[test]
    fn a_window_cut_as_read_is_what_patchify_makes_of_it() {
        let colour =
            Config { height: 6, width: 8, channels: 3, frames: 6, patch_height: 3, patch_width: 2, tubelet: 2, ..Config::gelsight() };
        let grey = Config { height: 6, width: 10, channels: 1, frames: 8, patch_height: 3, patch_width: 5, tubelet: 4, ..Config::icub20() };
        for cfg in [colour, grey] {
            let (model, _) = Pvt3::init(&cfg, 0).unwrap();
            let mut shape = vec![2];
            shape.extend(cfg.sample_shape());
            let values: Vec<f32> = (0..shape.iter().product::<usize>()).map(|v| v as f32).collect();
            let want = model.patchify(&Tensor::from_vec(values.clone(), shape, &Device::Cpu).unwrap()).unwrap();
            let mut cut = Vec::new();
            for window in values.chunks_exact(values.len() / 2) {
                cut_into(&cfg, window, &mut cut);
            }
            assert_eq!(cut, want.flatten_all().unwrap().to_vec1::<f32>().unwrap(), "{cfg:?}");
        }
    }
}
