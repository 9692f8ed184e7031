//! The robot runtime (tract) on exported files: the golden model against the golden logits and
//! the baked f64 reference, batch 1 and 8, and the typed errors bad input and bad files get.

use std::path::{Path, PathBuf};

use ndarray::{Array2, Array4};
use ndarray_npy::read_npy;
use pvt3_models::bake::bake;
use pvt3_models::weights::read_tensors;
use pvt3_models::{reference, Config};
use pvt3_runtime::{Classifier, Error};

fn golden(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/icub20").join(file)
}

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-runtime-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The committed golden model (kept current by an export test), its input, and its baked form.
fn golden_onnx() -> (PathBuf, Vec<f32>, pvt3_models::bake::BakedPvt3) {
    let baked = bake(&Config::icub20(), &read_tensors(&golden("weights.safetensors")).unwrap()).unwrap();
    let input: Array4<f32> = read_npy(golden("input.npy")).unwrap();
    (golden("model.onnx"), input.iter().copied().collect(), baked)
}

#[test]
fn golden_logits_from_tract_match_the_golden_and_the_f64_reference() {
    let (path, x, baked) = golden_onnx();
    let expected: Array2<f64> = read_npy(golden("logits.npy")).unwrap();
    let reference = reference::forward(&baked, &x, 8).unwrap();
    let c = Classifier::load(&path).unwrap();
    assert_eq!(c.sample_shape(), &[6, 10, 75]);
    assert_eq!(c.kept_frames().len(), 55);
    for batch in [8, 1] {
        let (logits, probabilities) = c.run(&x[..batch * 4500], batch).unwrap();
        let golden_err = logits.iter().zip(expected.iter()).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
        let reference_err =
            logits.iter().zip(reference.iter().flatten()).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
        assert!(golden_err <= 1e-5 && reference_err <= 1e-5, "batch {batch}: {golden_err:e}, {reference_err:e}");
        for p in probabilities.chunks(20) {
            assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        }
    }
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
    assert!(matches!(err, Error::NotOnnx { .. }), "{err}");
    let text = dir.join("text.onnx");
    std::fs::write(&text, "not a model").unwrap();
    assert!(matches!(Classifier::load(&text), Err(Error::NotOnnx { .. } | Error::NotPvt3 { .. })));
    assert!(matches!(Classifier::load(dir.join("absent.onnx")), Err(Error::Io { .. })));
    std::fs::remove_dir_all(dir).unwrap();
}
