//! The robot runtime (tract) on exported files: the golden model against the golden logits and
//! the baked f64 reference, batch 1 and 8, and the typed errors bad input and bad files get.

use std::path::PathBuf;

use ndarray::{Array2, Array4};
use ndarray_npy::read_npy;
use pvt3_models::weights::varmap_tensors;
use pvt3_models::{Config, Pvt3};
use pvt3_runtime::{Classifier, Error, StopRule};
use pvt3_spec::bake::bake;
use pvt3_spec::normalization::Normalization;
use pvt3_spec::reference;
use pvt3_spec::weights::read_tensors;

#[path = "support/onnx_check.rs"]
mod onnx_check;
#[path = "support/spectral_case.rs"]
mod spectral_case;
#[path = "support/tract_check.rs"]
mod tract_check;
#[path = "support/workspace.rs"]
mod workspace;

fn golden(file: &str) -> PathBuf {
    workspace::workspace().join("tests/golden/icub20").join(file)
}

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-runtime-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The committed golden model (kept current by an export test), its input, and its baked form.
fn golden_onnx() -> (PathBuf, Vec<f32>, pvt3_spec::baked::BakedPvt3) {
    let baked = bake(&Config::icub20(), &read_tensors(&golden("weights.safetensors")).unwrap()).unwrap();
    let input: Array4<f32> = read_npy(golden("input.npy")).unwrap();
    (golden("model.onnx"), input.iter().copied().collect(), baked)
}

/// A file exported before configurations were split by network (09687eb: its `pvt3.config`
/// holds every network's fields) loads and gives today's file's logits, bit for bit.
#[test]
fn a_file_exported_before_the_configuration_split_runs_as_today_s() {
    let (path, x, _) = golden_onnx();
    let old = workspace::workspace().join("tests/fixtures/model-09687eb.onnx");
    let (before, _) = Classifier::load(&old).unwrap().run(&x, 8).unwrap();
    let (today, _) = Classifier::load(&path).unwrap().run(&x, 8).unwrap();
    assert_eq!(before, today);
}

#[test]
fn golden_logits_from_tract_match_the_golden_and_the_f64_reference() {
    let (path, x, baked) = golden_onnx();
    let expected: Array2<f64> = read_npy(golden("logits.npy")).unwrap();
    let reference = reference::forward(&baked, &x, 8).unwrap();
    let c = Classifier::load(&path).unwrap();
    assert_eq!(c.sample_shape(), &[6, 10, 75]);
    assert_eq!(c.kept_frames().len(), 55);
    assert!(c.streams());
    for batch in [8, 1] {
        let (logits, probabilities) = c.run(&x[..batch * 4500], batch).unwrap();
        let golden_err = logits.iter().zip(expected.iter()).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
        let reference_err = logits.iter().zip(reference.iter().flatten()).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
        assert!(golden_err <= 1e-5 && reference_err <= 1e-5, "batch {batch}: {golden_err:e}, {reference_err:e}");
        for p in probabilities.chunks(20) {
            assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        }
    }
    tract_check::tract_onnx_agrees(&path, &c, &x, 8);
    let p = c.classify(&x[..4500]).unwrap();
    let best = expected.row(0).iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
    assert_eq!((p.class, p.label.as_str()), (best, format!("material_{}", best + 1).as_str()));
    let first = &c.classify_batch(&x, 8).unwrap()[0];
    assert_eq!(first.class, p.class);
    assert!(first.probabilities.iter().zip(&p.probabilities).all(|(a, b)| (a - b).abs() < 1e-6), "plans per batch size agree");
    let (two_threads, _) = Classifier::load(&path).unwrap().with_threads(2).run(&x, 8).unwrap();
    let (one_thread, _) = c.run(&x, 8).unwrap();
    let diff = two_threads.iter().zip(&one_thread).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    assert!(diff < 1e-5, "two threads: {diff:e}");
}

/// Streaming with two heads, tubelets of 3 frames, pruned and scaled tokens and a real
/// normalisation: frame by frame equals the whole window, and both equal the f64 reference.
#[test]
fn streaming_equals_the_whole_window_with_heads_tubelets_and_pruned_tokens() {
    let cfg = Config { heads: 2, dim_head: 16, tubelet: 3, ..Config::icub20() };
    let (_, varmap) = Pvt3::init(&cfg, 5).unwrap();
    let mut tensors = varmap_tensors(&varmap).unwrap();
    let mask = &mut tensors.get_mut("frame_mask").unwrap().1;
    for (t, m) in mask.iter_mut().enumerate() {
        *m = if t % 3 == 1 { 0.0 } else { 0.5 + t as f32 / 25.0 };
    }
    let baked = bake(&cfg, &tensors).unwrap();
    assert_eq!(baked.kept_tokens.len(), 17);
    let norm = Normalization {
        mean: (0..60).map(|i| i as f32 / 60.0).collect(),
        std: (0..60).map(|i| 0.5 + i as f32 / 30.0).collect(),
        frames: 75,
    };
    let meta = pvt3_export::Metadata {
        classes: (0..20).map(|k| format!("c{k}")).collect(),
        provenance: serde_json::json!({}),
        stop_rule: Some(StopRule { top_probability: 0.095, agreeing: 3 }),
        reading: None,
        camera: None,
    };
    for (bad, says) in
        [((0.0, 3), "is not in (0, 1]"), ((1.5, 3), "is not in (0, 1]"), ((f32::NAN, 3), "is not in (0, 1]"), ((0.5, 0), "agreeing = 0")]
    {
        let rule = StopRule { top_probability: bad.0, agreeing: bad.1 };
        let err = pvt3_export::export(&baked, &norm, &pvt3_export::Metadata { stop_rule: Some(rule), ..meta.clone() }).unwrap_err();
        assert!(err.to_string().contains(says), "{err}");
    }
    let dir = scratch("stream");
    let path = dir.join("tubelets.onnx");
    pvt3_export::write(&pvt3_export::export(&baked, &norm, &meta).unwrap(), &path).unwrap();
    let (_, x, _) = golden_onnx();
    let c = Classifier::load(&path).unwrap();
    tract_check::tract_onnx_agrees(&path, &c, &x, 8);
    let whole = c.classify_batch(&x, 8).unwrap();
    let (logits, _) = c.run(&x, 8).unwrap();
    let normalised: Vec<f32> = x
        .chunks(4500)
        .flat_map(|s| {
            let mut out = Vec::new();
            norm.apply_into(s, &mut out);
            out
        })
        .collect();
    let reference = reference::forward(&baked, &normalised, 8).unwrap();
    let worst = logits.iter().zip(reference.iter().flatten()).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
    assert!(worst <= 1e-5, "tract against the f64 reference: {worst:e}");
    assert_eq!(c.stop_rule(), meta.stop_rule);
    let mut session = c.session().unwrap();
    let (mut stops, mut peeks) = (0, 0);
    let mut first_window_stops = Vec::new();
    for ((sample, expected), normalised) in x.chunks(4500).zip(&whole).zip(normalised.chunks(4500)) {
        let mut classes = Vec::new();
        for t in 0..75 {
            session.push_frame(&(0..60).map(|i| sample[i * 75 + t]).collect::<Vec<_>>()).unwrap();
            // A provisional answer after every whole token of 3 frames, pruned ones included, is
            // the f64 reference on the touch so far; between tokens it reads the whole ones.
            let tokens = (t + 1) / 3;
            match session.peek() {
                Err(Error::NoTokenYet { tubelet: 3 }) => assert_eq!(tokens, 0),
                Ok(peek) if t % 3 == 2 => {
                    let logits = &reference::forward_prefix(&baked, normalised, 1, tokens).unwrap()[0];
                    let worst =
                        peek.prediction.probabilities.iter().zip(softmax(logits)).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
                    assert!(worst <= 1e-5, "{tokens} tokens: {worst:e}");
                    assert_eq!(peek.frames, 3 * tokens);
                    // The rule: a top probability of 0.095 or more, and three answers in a row
                    // (after this token and the two before) on one class.
                    let class = peek.prediction.class;
                    classes.push(class);
                    let agreed = tokens >= 3 && classes[tokens - 3..].iter().all(|c| *c == class);
                    assert_eq!(peek.stop, peek.prediction.probabilities[class] >= 0.095 && agreed, "{tokens} tokens");
                    (stops, peeks) = (stops + usize::from(peek.stop), peeks + 1);
                    if first_window_stops.len() < 25 && peeks <= 25 {
                        first_window_stops.push(peek.stop);
                    }
                }
                Ok(peek) => assert_eq!(peek.frames, 3 * tokens),
                Err(e) => panic!("{e}"),
            }
        }
        let streamed = session.finish().unwrap();
        let worst = streamed.probabilities.iter().zip(&expected.probabilities).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(worst <= 1e-5 && streamed.class == expected.class, "streamed against whole window: {worst:e}");
    }
    assert!(stops > 0 && stops < peeks, "the stopping rule is met by some provisional answers ({stops} of {peeks}), not all");
    // A session that peeks only now and then gets the same verdict: it computes the answers
    // before that it was not asked for.
    let sample = &x[..4500];
    for tokens in [2, 9, 17, 25] {
        let mut sparse = c.session().unwrap();
        for t in 0..3 * tokens {
            sparse.push_frame(&(0..60).map(|i| sample[i * 75 + t]).collect::<Vec<_>>()).unwrap();
        }
        assert_eq!(sparse.peek().unwrap().stop, first_window_stops[tokens - 1], "{tokens} tokens");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

fn softmax(logits: &[f64]) -> Vec<f64> {
    let max = logits.iter().copied().fold(f64::MIN, f64::max);
    let e: Vec<f64> = logits.iter().map(|l| (l - max).exp()).collect();
    let sum: f64 = e.iter().sum();
    e.into_iter().map(|v| v / sum).collect()
}

#[test]
fn bad_input_and_bad_files_are_typed_errors() {
    let dir = scratch("errors");
    let (path, x, _) = golden_onnx();
    let c = Classifier::load(&path).unwrap();
    assert!(matches!(c.classify(&x[..4499]), Err(Error::InputLength { got: 4499, expected: 4500, .. })));
    assert!(matches!(c.classify_batch(&x, 7), Err(Error::InputLength { expected: 31500, .. })));
    assert!(matches!(c.classify_batch(&[], 0), Err(Error::EmptyBatch)));
    let mut nan = x[..4500].to_vec();
    nan[17] = f32::NAN;
    assert!(matches!(c.classify(&nan), Err(Error::NonFinite { index: 17, .. })));
    nan[17] = f32::INFINITY;
    assert!(matches!(c.classify(&nan), Err(Error::NonFinite { index: 17, .. })));

    let bytes = std::fs::read(&path).unwrap();
    let truncated = dir.join("truncated.onnx");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let err = Classifier::load(&truncated).err().expect("a truncated file fails");
    assert!(matches!(err, Error::Corrupted { .. }), "{err}");
    let text = dir.join("text.onnx");
    std::fs::write(&text, "not a model").unwrap();
    assert!(matches!(Classifier::load(&text), Err(Error::Corrupted { .. })));
    assert!(matches!(Classifier::load(dir.join("absent.onnx")), Err(Error::Io { .. })));
    std::fs::remove_dir_all(dir).unwrap();
}

/// A model with a spectral head (a third of its tokens pruned) runs in tract (its DFT op an FFT)
/// as the f64 reference computes it, at batch 1 and 3, and streams: a session's provisional
/// answer after every token is the reference's on the touch so far, the head reading the kept
/// frames received and nothing else, and its final answer is the whole window's. A head that
/// reads no levels runs as the reference too.
#[test]
fn a_spectral_head_runs_in_tract_as_the_reference_and_streams() {
    let spectral_case::SpectralCase { baked, norm, raw: x, normalised } = spectral_case::spectral_case(3, true);
    let reference = reference::forward(&baked, &normalised, 3).unwrap();
    let meta = pvt3_export::Metadata {
        classes: (0..20).map(|k| format!("c{k}")).collect(),
        provenance: serde_json::json!({"data": "synthetic"}),
        stop_rule: Some(StopRule { top_probability: 0.5, agreeing: 2 }),
        reading: None,
        camera: None,
    };
    let dir = scratch("spectral");
    let path = dir.join("spectral.onnx");
    pvt3_export::write(&pvt3_export::export(&baked, &norm, &meta).unwrap(), &path).unwrap();
    let c = Classifier::load(&path).unwrap();
    let as_reference = |c: &Classifier, x: &[f32], reference: &[Vec<f64>], batch: usize| {
        let (logits, _) = c.run(&x[..batch * 7600], batch).unwrap();
        let worst = logits.iter().zip(reference.iter().flatten()).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-5, "batch {batch}: tract against the f64 reference: {worst:e}");
    };
    for batch in [3, 1] {
        as_reference(&c, &x, &reference, batch);
    }
    let no_levels = spectral_case::spectral_case(3, false);
    let no_levels_path = dir.join("no-levels.onnx");
    pvt3_export::write(&pvt3_export::export(&no_levels.baked, &no_levels.norm, &meta).unwrap(), &no_levels_path).unwrap();
    let expected = reference::forward(&no_levels.baked, &no_levels.normalised, 3).unwrap();
    as_reference(&Classifier::load(&no_levels_path).unwrap(), &no_levels.raw, &expected, 3);
    tract_check::tract_onnx_agrees(&path, &c, &x, 3);
    assert!(c.streams());
    c.prepare(&[1, 3], true).unwrap();
    let whole = c.classify_batch(&x, 3).unwrap();
    let mut session = c.session().unwrap();
    // Twice through the same session: the second touch starts from an empty window.
    for (sample, (normalised, expected)) in
        x.chunks(7600).zip(normalised.chunks(7600).zip(&whole)).chain(x.chunks(7600).zip(normalised.chunks(7600).zip(&whole)).take(1))
    {
        for n in 0..400 {
            session.push_frame(&(0..19).map(|e| sample[e * 400 + n]).collect::<Vec<_>>()).unwrap();
            if n % 10 != 9 {
                continue;
            }
            let tokens = (n + 1) / 10;
            let logits = &reference::forward_prefix(&baked, normalised, 1, tokens).unwrap()[0];
            let peek = session.peek().unwrap();
            let worst = peek.prediction.probabilities.iter().zip(softmax(logits)).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-5, "{tokens} tokens: {worst:e}");
        }
        let streamed = session.finish().unwrap();
        let worst = streamed.probabilities.iter().zip(&expected.probabilities).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(worst <= 1e-5 && streamed.class == expected.class, "streamed against whole window: {worst:e}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A camera's model: the layout `pvt3 cv` derives for 30 × 40 RGB frames (patches of 10 × 10
/// pixels, 12 a frame, the GelSight preset's widths, a spectral head over the image's space with
/// its rings and histogram), the histograms of its gradients too (`spectral_gradients`), its
/// frames' log ring powers averaged if `log_frames` (`spectral_log_frames`), with a patch mask,
/// a quarter of its frames and half of its patches pruned and the others scaled, normalised
/// pixel by pixel; with its candle form and the metadata it is exported with.
fn camera_model(log_frames: bool) -> (Pvt3, pvt3_spec::baked::BakedPvt3, Normalization, pvt3_export::Metadata) {
    let layout = Config { classes: 5, ..Config::for_sensor(pvt3_spec::Sensor::Camera, &[30, 40, 3, 25]).unwrap() };
    let pvt3_spec::Network::Pvt3(network) = layout.network else { panic!("a camera's layout is a PVT³") };
    let cfg = Config {
        network: pvt3_models::Pvt3Config { patch_selection: true, spectral_gradients: true, spectral_log_frames: log_frames, ..network }
            .into(),
        ..layout
    };
    assert_eq!((cfg.patch_height, cfg.patch_width, cfg.num_patches(), cfg.dim), (10, 10, 12, 64));
    assert_eq!(
        (cfg.spectral_space(), cfg.spectral_bands(), cfg.spectral_histogram(), cfg.spectral_gradients()),
        (true, 12, 24, true),
        "a camera's layout has a spectral head over the image, with a histogram (and here its gradients')"
    );
    let (model, varmap) = Pvt3::init(&cfg, 7).unwrap();
    let unpruned = bake(&cfg, &varmap_tensors(&varmap).unwrap()).unwrap();
    let scales: Vec<f32> = (0..25).map(|t| if t % 4 == 3 { 0.0 } else { 1.0 - t as f32 / 50.0 }).collect();
    varmap.data().lock().unwrap()["frame_mask"].set(&candle_core::Tensor::new(scales, &candle_core::Device::Cpu).unwrap()).unwrap();
    let patches: Vec<f32> = (0..12).map(|p| if p % 2 == 1 { 0.0 } else { 0.5 + p as f32 / 10.0 }).collect();
    varmap.data().lock().unwrap()["patch_mask"].set(&candle_core::Tensor::new(patches, &candle_core::Device::Cpu).unwrap()).unwrap();
    // A spectral standardisation that magnifies the texture's features, so that the head's term
    // is large (errors of f32 grow with it); the pixels, normalised already, at their own scale,
    // as a fit leaves them (3,600 of them magnified would be a term no fit makes).
    let (features, per, pixels) = (cfg.spectral_features(), cfg.spectral_features_per_channel(), cfg.spectral_pixel_count());
    assert_eq!(pixels, 30 * 40, "a camera's layout reads the pixels");
    let texture = per - pixels;
    let magnified = |i: usize| if i % per < texture { 10.0 + (i / per * texture + i % per) as f32 / 20.0 } else { 1.0 };
    let scale = candle_core::Tensor::new((0..features).map(magnified).collect::<Vec<_>>(), &candle_core::Device::Cpu).unwrap();
    varmap.data().lock().unwrap()["spectral.scale"].set(&scale).unwrap();
    let baked = bake(&cfg, &varmap_tensors(&varmap).unwrap()).unwrap();
    assert_eq!((baked.kept_tokens.len(), baked.kept_patches.len()), (19, 6));
    // Half the patches: about half the spatial transformer's and the embedding's work (the
    // spectral head's transform costs as much, a pruned patch's pixels read as 0).
    let head = cfg.spectral_mult_adds() as f64;
    let frames_only = (unpruned.mult_adds() as f64 - head) * 19.0 / 25.0;
    assert!((baked.mult_adds() as f64 - head) < 0.6 * frames_only, "{} of {frames_only}", baked.mult_adds());
    let (pixels, mut rng) = (30 * 40 * 3, pvt3_models::Rng::new(8));
    let norm = Normalization {
        mean: (0..pixels).map(|_| 100.0 + 30.0 * rng.normal()).collect(),
        std: (0..pixels).map(|_| 20.0 + 10.0 * rng.normal().abs()).collect(),
        frames: 25,
    };
    let meta = pvt3_export::Metadata {
        classes: (0..5).map(|k| format!("c{k}")).collect(),
        provenance: serde_json::json!({"data": "synthetic camera"}),
        stop_rule: None,
        reading: None,
        camera: None,
    };
    (model, baked, norm, meta)
}

/// The camera model of [`camera_model`] in every form, 8-bit pixel values: candle's forward, the
/// runtime on whole windows and frame by frame (its provisional answers too, the head's features
/// computed frame by frame), tract-onnx and onnxruntime all equal the f64 reference within 1e-5,
/// the log of the frames' mean ring power or the mean of their logs.
#[test]
fn a_camera_model_equals_the_reference_in_every_form() {
    for log_frames in [false, true] {
        camera_forms(log_frames);
    }
}

fn camera_forms(log_frames: bool) {
    let (model, baked, norm, meta) = camera_model(log_frames);
    let (pixels, mut rng) = (30 * 40 * 3, pvt3_models::Rng::new(9));
    let raw: Vec<f32> = (0..2 * pixels * 25).map(|_| (128.0 + 60.0 * rng.normal()).clamp(0.0, 255.0).round()).collect();
    let mut normalised = Vec::new();
    raw.chunks(pixels * 25).for_each(|sample| norm.apply_into(sample, &mut normalised));
    let reference = reference::forward(&baked, &normalised, 2).unwrap();
    let headless = reference::forward(&pvt3_spec::baked::BakedPvt3 { spectrum: None, ..baked.clone() }, &normalised, 2).unwrap();
    let term = reference.iter().flatten().zip(headless.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(term > 0.1, "the spectral head adds {term} to a logit");
    let within = |got: &[f32], form: &str| {
        let worst = got.iter().zip(reference.iter().flatten()).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-5, "{form} against the f64 reference: {worst:e}");
    };
    let x = candle_core::Tensor::from_vec(normalised.clone(), (2, 30, 40, 3, 25), &candle_core::Device::Cpu).unwrap();
    within(&model.forward(&x, None).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap(), "candle");
    let dir = scratch("camera");
    let path = dir.join("camera.onnx");
    let file = pvt3_export::export(&baked, &norm, &meta).unwrap();
    // The head's seams, so that a session computes each frame's features as it arrives.
    let seams: Vec<&str> = file.graph.iter().flat_map(|g| &g.node).flat_map(|n| &n.output).map(String::as_str).collect();
    assert!(seams.contains(&pvt3_format::HEAD_FRAMES) && seams.contains(&pvt3_format::HEAD_FEATURES));
    pvt3_export::write(&file, &path).unwrap();
    let c = Classifier::load(&path).unwrap();
    let (logits, _) = c.run(&raw, 2).unwrap();
    within(&logits, "the runtime");
    // No form reads a pruned patch's pixels: other values there change no bit of an answer.
    let kept = pvt3_spec::spectrum::space::kept_pixels(&baked.config, &baked.kept_patches);
    let elsewhere: Vec<f32> = raw.iter().enumerate().map(|(i, v)| if kept[i % (pixels * 25) / 75] { *v } else { 255.0 - *v }).collect();
    assert_ne!(elsewhere, raw);
    assert_eq!(c.run(&elsewhere, 2).unwrap().0, logits, "a pruned patch's pixels changed an answer");
    tract_check::tract_onnx_agrees(&path, &c, &raw, 2);
    let expected: Vec<f32> = reference.iter().flatten().map(|v| *v as f32).collect();
    let msg = onnx_check::assert_onnxruntime_matches(&path, (&[2, 30, 40, 3, 25], &raw), &expected, 1e-5, None);
    assert!(msg.starts_with("ok"), "{msg}");
    let whole = c.classify_batch(&raw, 2).unwrap();
    let mut session = c.session().unwrap();
    for ((sample, normalised), expected) in raw.chunks(pixels * 25).zip(normalised.chunks(pixels * 25)).zip(&whole) {
        for t in 0..25 {
            // The camera's frame: every pixel's colours, row by row.
            session.push_frame(&(0..pixels).map(|i| sample[i * 25 + t]).collect::<Vec<_>>()).unwrap();
            if t % 6 == 5 {
                let logits = &reference::forward_prefix(&baked, normalised, 1, t + 1).unwrap()[0];
                let peek = session.peek().unwrap();
                let worst =
                    peek.prediction.probabilities.iter().zip(softmax(logits)).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
                assert!(worst <= 1e-5, "{} frames: {worst:e}", t + 1);
            }
        }
        let streamed = session.finish().unwrap();
        let worst = streamed.probabilities.iter().zip(&expected.probabilities).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(worst <= 1e-5 && streamed.class == expected.class, "streamed against whole window: {worst:e}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// 8-bit frames as a camera gives them (60 × 80 RGB), to a model whose file says how they were
/// read (shrunk to 30 × 40, less the touch's first frame): a session's answer equals the f64
/// reference on the frames so read.
#[test]
fn a_camera_s_frames_are_read_as_the_import_read_them() {
    let (_, baked, norm, meta) = camera_model(true);
    let camera = pvt3_runtime::Camera { recorded: [60, 80, 3], crop: None, size: Some([30, 40]), grey: false, subtract_first: true };
    let dir = scratch("camera-frames");
    let path = dir.join("camera.onnx");
    pvt3_export::write(&pvt3_export::export(&baked, &norm, &pvt3_export::Metadata { camera: Some(camera), ..meta }).unwrap(), &path)
        .unwrap();
    let c = Classifier::load(&path).unwrap();
    assert_eq!((c.camera(), c.camera_frame_len()), (Some(camera), 60 * 80 * 3));
    let mut rng = pvt3_models::Rng::new(10);
    // The gel before contact, then the touch's 25 frames.
    let touch: Vec<Vec<u8>> =
        (0..26).map(|_| (0..60 * 80 * 3).map(|_| (128.0 + 60.0 * rng.normal()).clamp(0.0, 255.0) as u8).collect()).collect();
    let read = |f: &[u8]| pvt3_runtime::Picture { height: 60, width: 80, channels: 3, data: f.to_vec() }.read_as(&camera).unwrap().data;
    let background = read(&touch[0]);
    let pixels = 30 * 40 * 3;
    let mut sample = vec![0f32; pixels * 25];
    for (t, frame) in touch[1..].iter().enumerate() {
        read(frame).iter().zip(&background).enumerate().for_each(|(i, (v, b))| sample[i * 25 + t] = f32::from(*v) - f32::from(*b));
    }
    let mut normalised = Vec::new();
    norm.apply_into(&sample, &mut normalised);
    let expected = softmax(&reference::forward(&baked, &normalised, 1).unwrap()[0]);
    let mut session = c.session().unwrap();
    for _ in 0..2 {
        touch.iter().for_each(|frame| session.push_camera_frame(frame).unwrap());
        let got = session.finish().unwrap();
        let worst = got.probabilities.iter().zip(&expected).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-5, "camera frames against the reference: {worst:e}");
    }
    // Whole touches as a data set lays them out, frames last (`pvt3-run` given the camera's bytes).
    let laid: Vec<u8> = (0..2).flat_map(|_| (0..60 * 80 * 3).flat_map(|i| touch.iter().map(move |f| f[i]))).collect();
    for got in c.classify_camera_touches(&laid, 2).unwrap() {
        let worst = got.probabilities.iter().zip(&expected).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-5, "whole touches of camera frames against the reference: {worst:e}");
    }
    let err = c.classify_camera_touches(&laid[1..], 2).unwrap_err().to_string();
    assert!(err.contains("are not 2 touches of whole camera frames of 14400 bytes"), "{err}");
    let err = session.push_camera_frame(&touch[0][1..]).unwrap_err();
    assert!(matches!(err, Error::FrameLength { got: 14399, expected: 14400 }), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}
