//! Every shape of touch a user may bring trains, exports and runs: a camera's still images to
//! long clips (sides from 16, odd, portrait, grey and RGB) and tactile arrays from one frame to
//! hundreds. Each case is a data file as a user's would be, trained an epoch by `pvt3 train
//! --export` with the layout derived for it, and every form of the model it wrote answers as
//! the f64 reference does (≤ 1e-5): candle, the runtime whole and frame by frame, tract's ONNX
//! loader and onnxruntime.

use std::path::{Path, PathBuf};

use ndarray::{Array1, ArrayD, IxDyn};
use ndarray_npy::NpzWriter;
use pvt3_runtime::Classifier;
use pvt3_spec::reference;
use pvt3_trainer::checkpoint::{self, BakedFile};

#[path = "support/onnx_check.rs"]
mod onnx_check;
#[path = "support/pvt3_command.rs"]
#[allow(dead_code)] // the other end-to-end tests use the rest of it
mod pvt3_command;
#[path = "support/tract_check.rs"]
mod tract_check;
#[path = "support/workspace.rs"]
mod workspace;

use pvt3_command::{scratch, succeeds};

/// Touches of each case: two classes of five, one of each class in every fold.
const TOUCHES: usize = 10;

/// A sample's `[height, width, channels, frames]`; a camera's frames are 8-bit, as `pvt3
/// import` stores them.
struct Case {
    shape: [usize; 4],
    camera: bool,
}

const fn camera(h: usize, w: usize, c: usize, t: usize) -> Case {
    Case { shape: [h, w, c, t], camera: true }
}

const fn array(h: usize, w: usize, t: usize) -> Case {
    Case { shape: [h, w, 1, t], camera: false }
}

/// Every frame count of the sweep among the camera's (one a still image), its sides from
/// the least an image has (16) to odd and portrait ones, grey and RGB; arrays from one frame to
/// a BioTac's 400.
const CASES: [Case; 11] = [
    camera(16, 16, 1, 1),
    camera(17, 23, 3, 2),
    camera(40, 30, 1, 5),
    camera(30, 40, 3, 12),
    camera(16, 16, 3, 24),
    camera(17, 23, 1, 25),
    camera(20, 24, 3, 60),
    array(6, 10, 1),
    array(6, 10, 2),
    array(19, 1, 60),
    array(3, 4, 400),
];

impl Case {
    fn name(&self) -> String {
        let [h, w, c, t] = self.shape;
        format!("{}-{h}x{w}x{c}-{t}", if self.camera { "camera" } else { "array" })
    }

    /// `x`'s shape in the file: a grey camera's or an array's frames have no channel axis.
    fn x_shape(&self) -> Vec<usize> {
        let [h, w, c, t] = self.shape;
        match c {
            1 => vec![TOUCHES, h, w, t],
            _ => vec![TOUCHES, h, w, c, t],
        }
    }

    /// Every touch's values back to back: each class its own pattern over the frame and in
    /// time, with noise; a camera's rounded to 8 bits.
    fn values(&self) -> Vec<f32> {
        let [h, w, c, t] = self.shape;
        let mut rng = pvt3_spec::Rng::new(7);
        let per = h * w * c * t;
        (0..TOUCHES * per)
            .map(|i| {
                let (touch, at) = (i / per, i % per);
                let (pixel, frame) = (at / t, at % t);
                let class = (touch % 2) as f32;
                // Each touch its own phase, as presses differ.
                let phase = touch as f32 * 2.3;
                let pattern = ((pixel as f32 * (0.3 + class) + frame as f32 * 0.7 + phase).sin() + 1.0) * 60.0;
                let v = 40.0 + pattern + 20.0 * rng.normal();
                if self.camera {
                    v.round().clamp(0.0, 255.0)
                } else {
                    v / 100.0
                }
            })
            .collect()
    }

    /// The data file of this case in `dir`.
    fn write(&self, dir: &Path, values: &[f32]) -> PathBuf {
        let path = dir.join(format!("{}.npz", self.name()));
        let mut npz = NpzWriter::new(std::fs::File::create(&path).unwrap());
        let shape = IxDyn(&self.x_shape());
        if self.camera {
            let bytes: Vec<u8> = values.iter().map(|v| *v as u8).collect();
            npz.add_array("x", &ArrayD::from_shape_vec(shape, bytes).unwrap()).unwrap();
        } else {
            npz.add_array("x", &ArrayD::from_shape_vec(shape, values.to_vec()).unwrap()).unwrap();
        }
        npz.add_array("y", &Array1::from_iter((0..TOUCHES).map(|i| (i % 2) as i64))).unwrap();
        npz.finish().unwrap();
        path
    }
}

#[test]
fn every_shape_of_touch_trains_exports_and_runs_as_the_reference() {
    let dir = scratch("shapes");
    for case in &CASES {
        forms_agree(case, &dir);
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Trains `case` an epoch, exports it, and holds every form to the f64 reference on two touches.
fn forms_agree(case: &Case, dir: &Path) {
    let values = case.values();
    let data = case.write(dir, &values);
    let per: usize = case.shape.iter().product();
    trained_forms_agree(&case.name(), &data, &values[..2 * per], case.shape[3], dir);
}

/// Trains the data set `data` an epoch into `dir/name`, exports it, and holds every form to the
/// f64 reference on `raw`, two touches of `frames` frames as the data set holds them.
fn trained_forms_agree(name: &str, data: &Path, raw: &[f32], frames: usize, dir: &Path) {
    let run = dir.join(name);
    let onnx = run.join("model.onnx");
    let (d, r, o) = (data.to_str().unwrap(), run.to_str().unwrap(), onnx.to_str().unwrap());
    let small = ["--set", "space_depth=1", "--set", "time_depth=1"];
    succeeds(&[&["train", "--data", d, "--out", r, "--epochs", "1", "--export", o][..], &small].concat());

    let baked = BakedFile::from_checkpoint(&run).unwrap();
    let (per, t) = (raw.len() / 2, frames);
    let mut normalised = Vec::new();
    raw.chunks(per).for_each(|sample| baked.normalization.apply_into(sample, &mut normalised));
    let reference = reference::forward(&baked.baked, &normalised, 2).unwrap();
    let expected: Vec<f32> = reference.iter().flatten().map(|v| *v as f32).collect();
    let within = |got: &[f32], form: &str| {
        assert_eq!(got.len(), expected.len(), "{name}: {form}'s logits");
        let worst = got.iter().zip(reference.iter().flatten()).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-5, "{name}: {form} against the f64 reference: {worst:e}");
    };

    let (_, model, _) = checkpoint::load(&run).unwrap();
    let sample: Vec<usize> = std::iter::once(2).chain(baked.baked.config.sample_shape()).collect();
    let x = candle_core::Tensor::from_vec(normalised.clone(), sample.as_slice(), &candle_core::Device::Cpu).unwrap();
    within(&model.forward(&x, None).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap(), "candle");

    let classifier = Classifier::load(&onnx).unwrap();
    within(&classifier.run(raw, 2).unwrap().0, "the runtime");
    tract_check::tract_onnx_agrees(&onnx, &classifier, raw, 2);
    let msg = onnx_check::assert_onnxruntime_matches(&onnx, (&sample, raw), &expected, 1e-5, None);
    assert!(msg.starts_with("ok"), "{name}: {msg}");

    // Frame by frame, as a robot's stream: the same answer as the whole window.
    let whole = classifier.classify_batch(raw, 2).unwrap();
    let mut session = classifier.session().unwrap();
    for (touch, expected) in raw.chunks(per).zip(&whole) {
        for frame in 0..t {
            session.push_frame(&(0..per / t).map(|i| touch[i * t + frame]).collect::<Vec<_>>()).unwrap();
        }
        let streamed = session.finish().unwrap();
        let worst = streamed.probabilities.iter().zip(&expected.probabilities).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(worst <= 1e-5 && streamed.class == expected.class, "{name}: streamed against the whole window: {worst:e}");
    }
}

/// A camera's still images as still-image sets lay them out (a folder of image files a class, one
/// image a touch), at the camera's full 240 × 320, imported shrunk to 30 × 40: each is one frame,
/// read once, and the model trained on them runs as the reference in every form.
#[test]
fn a_camera_s_still_images_import_as_one_frame_each_and_run_as_the_reference() {
    let dir = scratch("stills");
    let images = dir.join("images");
    let mut rng = pvt3_spec::Rng::new(3);
    for class in ["flat", "ridged"] {
        std::fs::create_dir_all(images.join(class)).unwrap();
        for touch in 0..5 {
            // Each press its own: the ridges' spacing and where they fall.
            let ridges = if class == "ridged" { 0.2 } else { 0.02 } * (1.0 + 0.2 * rng.normal());
            let phase = 6.0 * rng.normal();
            let pixels: Vec<u8> = (0..240 * 320 * 3)
                .map(|i| ((i / 3 % 320) as f32 * ridges + phase).sin() * 50.0 + 120.0 + 25.0 * rng.normal())
                .map(|v| v.round().clamp(0.0, 255.0) as u8)
                .collect();
            let file = std::fs::File::create(images.join(class).join(format!("{touch}.png"))).unwrap();
            let mut png = png::Encoder::new(std::io::BufWriter::new(file), 320, 240);
            png.set_color(png::ColorType::Rgb);
            png.write_header().unwrap().write_image_data(&pixels).unwrap();
        }
    }
    let data = dir.join("stills.npz");
    let out = succeeds(&["import", images.to_str().unwrap(), "--size", "30x40", "--out", data.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("10 touches of 2 classes (5 to 5 touches a class): each one still image of 30 × 40 RGB, read as one frame"),
        "{said}"
    );
    let x: ArrayD<u8> = ndarray_npy::NpzReader::new(std::fs::File::open(&data).unwrap()).unwrap().by_name("x").unwrap();
    assert_eq!(x.shape(), [10, 30, 40, 3, 1]);
    let raw: Vec<f32> = x.iter().take(2 * 30 * 40 * 3).map(|v| f32::from(*v)).collect();
    trained_forms_agree("stills", &data, &raw, 1, &dir);
    std::fs::remove_dir_all(dir).unwrap();
}
