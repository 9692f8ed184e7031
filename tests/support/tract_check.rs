//! tract's own ONNX loader as the oracle of the runtime's reader: the same file, the same logits.

use std::path::Path;

use pvt3_runtime::Classifier;

/// The runtime's own reader (`runtime/src/wire.rs`, tract-core operators wired from the nodes)
/// held to tract-onnx's ONNX loader on the same file: the same logits at batch `batch`.
pub fn tract_onnx_agrees(path: &Path, c: &Classifier, x: &[f32], batch: usize) {
    use tract_onnx::prelude::*;
    let shape: Vec<usize> = std::iter::once(batch).chain(c.sample_shape().iter().copied()).collect();
    let plan = tract_onnx::onnx()
        .model_for_path(path)
        .and_then(|m| m.with_input_fact(0, f32::fact(&shape).into()))
        .and_then(|m| m.into_optimized())
        .and_then(|m| m.into_runnable())
        .unwrap_or_else(|e| panic!("tract-onnx cannot load {}: {e:#}", path.display()));
    let out = plan.run(tvec!(Tensor::from_shape(&shape, x).unwrap().into())).unwrap();
    let theirs: Vec<f32> = out[0].to_plain_array_view::<f32>().unwrap().iter().copied().collect();
    let (ours, _) = c.run(x, batch).unwrap();
    assert_eq!(theirs.len(), ours.len(), "{}: logits", path.display());
    let worst = ours.iter().zip(&theirs).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    assert!(worst <= 1e-5, "{}: the runtime's reader against tract-onnx's: {worst:e}", path.display());
}
