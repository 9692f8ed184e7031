//! The exported golden model in onnxruntime, batch 1 and 8; the pruned-frame graph; errors.

use std::path::PathBuf;

use ndarray::{Array2, Array4};
use ndarray_npy::read_npy;
use pvt3_models::Config;
use pvt3_spec::bake::bake;
use pvt3_spec::reference;
use pvt3_spec::weights::read_tensors;

use super::*;

#[path = "../../../tests/support/onnx_check.rs"]
mod onnx_check;
#[path = "../../../tests/support/spectral_case.rs"]
mod spectral_case;
#[path = "../../../tests/support/workspace.rs"]
mod workspace;

fn golden(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/icub20").join(file)
}

fn identity_normalization(cfg: &Config) -> Normalization {
    let channels = cfg.sensor_channels();
    Normalization { mean: vec![0.0; channels], std: vec![1.0; channels], frames: cfg.frames }
}

fn meta(classes: usize) -> Metadata {
    Metadata {
        classes: (0..classes).map(|k| format!("class_{k}")).collect(),
        provenance: serde_json::json!({"data": "golden"}),
        stop_rule: None,
        reading: None,
        camera: None,
    }
}

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-export-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn golden_model_in_onnxruntime_matches_the_golden_logits_at_batch_1_and_8() {
    let cfg = Config::icub20();
    let baked = bake(&cfg, &read_tensors(&golden("weights.safetensors")).unwrap()).unwrap();
    let model = export(&baked, &identity_normalization(&cfg), &meta(20)).unwrap();
    let dir = scratch("golden");
    let path = dir.join("golden.onnx");
    write(&model, &path).unwrap();
    let input: Array4<f32> = read_npy(golden("input.npy")).unwrap();
    let logits: Array2<f64> = read_npy(golden("logits.npy")).unwrap();
    let x: Vec<f32> = input.iter().copied().collect();
    let y: Vec<f32> = logits.iter().map(|v| *v as f32).collect();
    let msg = onnx_check::assert_onnxruntime_matches(&path, (&[8, 6, 10, 75], &x), &y, 1e-5, None);
    assert!(msg.starts_with("ok"), "{msg}");
    let one = dir.join("golden1.onnx");
    write(&model, &one).unwrap();
    onnx_check::assert_onnxruntime_matches(&one, (&[1, 6, 10, 75], &x[..4500]), &y[..20], 1e-5, None);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Folded attention (several heads; layer norms with non-trivial scale and bias absorbed; the
/// softmax with and without its maximum subtracted) equals the f64 reference of the baked model.
#[test]
fn folded_attention_matches_the_reference_with_heads_norms_and_large_scores() {
    let cfg = Config { heads: 2, dim_head: 32, frames: 12, ..Config::icub20() };
    let (_, varmap) = pvt3_models::Pvt3::init(&cfg, 5).unwrap();
    let mut tensors = pvt3_models::weights::varmap_tensors(&varmap).unwrap();
    let mut rng = pvt3_models::Rng::new(9);
    // In name order, so that the draws, and the model, are the same in every run (a map's own
    // order is not).
    let mut names: Vec<String> = tensors.keys().filter(|n| n.contains("norm.")).cloned().collect();
    names.sort();
    for name in names {
        let values = &mut tensors.get_mut(&name).expect("a name of the map").1;
        values.iter_mut().for_each(|v| *v = if name.ends_with("weight") { 1.0 + 0.5 * rng.normal() } else { 0.5 * rng.normal() });
    }
    let x: Vec<f32> = (0..2 * 6 * 10 * 12).map(|_| rng.normal()).collect();
    let dir = scratch("folded");
    for (tag, q_scale) in [("bounded", 1.0), ("large", 40.0)] {
        let mut t = tensors.clone();
        for (name, (_, values)) in t.iter_mut() {
            if name.ends_with("attn.qkv.weight") {
                let third = values.len() / 3;
                values[..third].iter_mut().for_each(|v| *v *= q_scale);
            }
        }
        let baked = bake(&cfg, &t).unwrap();
        let model = export(&baked, &identity_normalization(&cfg), &meta(20)).unwrap();
        let graph = model.graph.as_ref().unwrap();
        let named = |part: &str| graph.initializer.iter().filter(|t| t.name.contains(part)).count();
        assert_eq!(named("attn_queries"), 2 * 8, "{tag}: 8 attentions, query weights and bias each");
        assert_eq!(named("attn_keys"), 0, "{tag}: all 8 attentions fold, so the keys are the norm itself");
        let maxes = graph.node.iter().filter(|n| n.op_type == "Max").count();
        assert_eq!(maxes > 0, tag == "large", "{tag}: the row maximum is subtracted only where scores can be large");
        let expected: Vec<f32> = reference::forward(&baked, &x, 2).unwrap().into_iter().flatten().map(|v| v as f32).collect();
        let path = dir.join(format!("{tag}.onnx"));
        write(&model, &path).unwrap();
        let msg = onnx_check::assert_onnxruntime_matches(&path, (&[2, 6, 10, 12], &x), &expected, 1e-4, None);
        assert!(msg.starts_with("ok"), "{tag}: {msg}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn pruned_frames_are_gathered_away_before_the_spatial_transformer() {
    let cfg = Config::icub20();
    let mut tensors = read_tensors(&golden("weights.safetensors")).unwrap();
    let pruned = export(&bake(&cfg, &tensors).unwrap(), &identity_normalization(&cfg), &meta(20)).unwrap();
    tensors.get_mut("frame_mask").unwrap().1.iter_mut().for_each(|v| *v = 1.0);
    let full = export(&bake(&cfg, &tensors).unwrap(), &identity_normalization(&cfg), &meta(20)).unwrap();
    let graph = |m: &ModelProto| m.graph.clone().unwrap();
    let spatial_batch = |m: &ModelProto| {
        let g = graph(m);
        g.initializer.iter().find(|t| t.name.starts_with("kept_row_")).unwrap().dims[1]
    };
    assert_eq!(spatial_batch(&pruned), 55, "the golden frame mask prunes 20 of 75 frames");
    assert_eq!(spatial_batch(&full), 75);
    let gathers = |m: &ModelProto| graph(m).node.iter().filter(|n| n.op_type == "Gather").count();
    assert_eq!(gathers(&pruned), gathers(&full) + 2, "a Gather of the kept frames at the input, one that orders the time tokens");
    assert_eq!(graph(&pruned).node.len(), graph(&full).node.len() + 2, "the two gathers");
    let kept = pruned.metadata_props.iter().find(|p| p.key == pvt3_format::keys::KEPT_FRAMES).unwrap();
    assert_eq!(serde_json::from_str::<Vec<usize>>(&kept.value).unwrap().len(), 55);
}

#[test]
fn what_cannot_be_exported_is_named() {
    let cfg = Config::icub20();
    let mut tensors = read_tensors(&golden("weights.safetensors")).unwrap();
    let baked = bake(&cfg, &tensors).unwrap();
    let msg = export(&baked, &identity_normalization(&Config { height: 3, ..cfg.clone() }), &meta(20)).unwrap_err().to_string();
    assert!(msg.contains("normalisation does not fit 60 channels"), "{msg}");
    let msg = export(&baked, &identity_normalization(&cfg), &meta(3)).unwrap_err().to_string();
    assert!(msg.contains("3 class names for 20 classes"), "{msg}");
    tensors.get_mut("frame_mask").unwrap().1.iter_mut().for_each(|v| *v = 0.0);
    let msg = export(&bake(&cfg, &tensors).unwrap(), &identity_normalization(&cfg), &meta(20)).unwrap_err().to_string();
    assert!(msg.contains("every frame or every patch is pruned"), "{msg}");
}

/// `tests/golden/icub20/model.onnx`, the golden weights exported (identity normalisation, classes
/// material_1 …), is test data for the runtime, which must not depend on the exporter. This keeps
/// it current: run with PVT3_BLESS=1 to rewrite it after a deliberate change of the exporter.
#[test]
fn committed_golden_onnx_is_what_the_exporter_writes() {
    let cfg = Config::icub20();
    let baked = bake(&cfg, &read_tensors(&golden("weights.safetensors")).unwrap()).unwrap();
    let classes = (0..20).map(|k| format!("material_{}", k + 1)).collect();
    let meta = Metadata {
        classes,
        provenance: serde_json::json!({"data": "tests/golden/icub20 (independent implementation)"}),
        stop_rule: None,
        reading: None,
        camera: None,
    };
    let model = export(&baked, &identity_normalization(&cfg), &meta).unwrap();
    let graph = model.graph.as_ref().unwrap();
    let small: Vec<_> =
        graph.initializer.iter().filter(|t| t.raw_data.len() <= 1024).map(|t| (&t.dims, t.data_type, &t.raw_data)).collect();
    let distinct: std::collections::HashSet<_> = small.iter().collect();
    assert!(small.len() > 50 && distinct.len() == small.len(), "{} small constants, {} distinct", small.len(), distinct.len());
    let bytes = model.encode_to_vec();
    let path = golden("model.onnx");
    if std::env::var_os("PVT3_BLESS").is_some() {
        std::fs::write(&path, &bytes).unwrap();
    }
    assert!(std::fs::read(&path).ok() == Some(bytes), "{} is stale: rerun this test with PVT3_BLESS=1", path.display());
}

/// Frames too large for one block-diagonal embedding are cut into patches (and their rows,
/// padded for the normalisation, sliced back first): the graph still equals the f64 reference,
/// with a normalisation that is not the identity.
#[test]
fn large_frames_are_cut_into_patches_and_normalised() {
    let cfg = Config { height: 32, width: 32, channels: 2, frames: 4, patch_height: 4, patch_width: 4, ..Config::icub20() };
    let (_, varmap) = pvt3_models::Pvt3::init(&cfg, 3).unwrap();
    let baked = bake(&cfg, &pvt3_models::weights::varmap_tensors(&varmap).unwrap()).unwrap();
    let mut rng = pvt3_models::Rng::new(4);
    let channels = 32 * 32 * 2;
    let norm = Normalization {
        mean: (0..channels).map(|_| 5.0 * rng.normal()).collect(),
        std: (0..channels).map(|_| 0.5 + rng.normal().abs()).collect(),
        frames: 4,
    };
    let raw: Vec<f32> = (0..2 * channels * 4).map(|i| norm.mean[(i / 4) % channels] + 3.0 * rng.normal()).collect();
    let model = export(&baked, &norm, &meta(20)).unwrap();
    let graph = model.graph.as_ref().unwrap();
    assert!(graph.node.iter().any(|n| n.op_type == "Slice"), "the padded rows are sliced back before the patches");
    let mut normalised = Vec::new();
    raw.chunks(channels * 4).for_each(|sample| norm.apply_into(sample, &mut normalised));
    let expected: Vec<f32> = reference::forward(&baked, &normalised, 2).unwrap().into_iter().flatten().map(|v| v as f32).collect();
    let dir = scratch("large");
    let path = dir.join("large.onnx");
    write(&model, &path).unwrap();
    let msg = onnx_check::assert_onnxruntime_matches(&path, (&[2, 32, 32, 2, 4], &raw), &expected, 1e-4, None);
    assert!(msg.starts_with("ok"), "{msg}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A model with a spectral head (BioTac's layout, a normalisation that is not the identity, a
/// standardisation that is not either, a third of its tokens pruned) equals the f64 reference in
/// onnxruntime, for the whole window and for the touch so far (its key bias hiding the tokens not
/// yet received), and takes a stopping rule. The tolerance is onnxruntime's: its DFT op over 400
/// frames is 7e-4 off in these logits (measured, 1.32.0), where tract's FFT is within 1e-5
/// (tests/runtime.rs). A head that reads no levels, likewise on a prefix and the whole window.
#[test]
fn a_spectral_head_matches_the_reference_on_every_prefix() {
    let t = pvt3_models::Config::biotac20().time_tokens();
    spectral_head_matches_the_reference(true, &[1, 2, 3, 17, t]);
    spectral_head_matches_the_reference(false, &[17, t]);
}

fn spectral_head_matches_the_reference(levels: bool, prefixes: &[usize]) {
    let spectral_case::SpectralCase { baked, norm, raw, normalised } = spectral_case::spectral_case(2, levels);
    let rule = pvt3_format::StopRule { top_probability: 0.9, agreeing: 2 };
    let model = export(&baked, &norm, &Metadata { stop_rule: Some(rule), ..meta(20) }).unwrap();
    let graph = model.graph.as_ref().unwrap();
    assert!(graph.node.iter().any(|n| n.op_type == "DFT"));
    for seam in [pvt3_format::SPECTRAL_LOGITS, pvt3_format::FRAME_WEIGHTS] {
        assert!(graph.node.iter().any(|n| n.output.iter().any(|o| o == seam)), "{seam}");
    }
    let dir = scratch(&format!("spectral-{levels}"));
    let path = dir.join("spectral.onnx");
    write(&model, &path).unwrap();
    for &tokens in prefixes {
        let expected: Vec<f32> =
            reference::forward_prefix(&baked, &normalised, 2, tokens).unwrap().into_iter().flatten().map(|v| v as f32).collect();
        let msg = onnx_check::assert_onnxruntime_matches(&path, (&[2, 19, 1, 400], &raw), &expected, 2e-3, Some(tokens));
        assert!(msg.starts_with("ok"), "levels {levels}, {tokens} tokens: {msg}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}
