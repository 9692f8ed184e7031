//! Streaming on the committed golden model (20 of its 75 frames pruned): frame by frame equals
//! the whole window; pruned frames are never read; misuse is a typed error.

use std::path::PathBuf;

use super::*;
use crate::read_npy;
use pvt3_format::TOKEN_BIAS;

fn golden(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/icub20").join(file)
}

/// Frame `t` of window `w` of a `[batch, 6, 10, 75]` array.
fn frame(x: &[f32], w: usize, t: usize) -> Vec<f32> {
    (0..60).map(|i| x[w * 4500 + i * 75 + t]).collect()
}

#[test]
fn streaming_frame_by_frame_equals_the_whole_window() {
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let (_, x) = read_npy(&golden("input.npy")).unwrap();
    let whole = c.classify_batch(&x, 8).unwrap();
    let mut session = c.session().unwrap();
    for (w, expected) in whole.iter().enumerate() {
        for t in 0..75 {
            session.push_frame(&frame(&x, w, t)).unwrap();
        }
        assert_eq!(session.received(), 75);
        let got = session.finish().unwrap();
        assert_eq!(session.received(), 0, "finishing starts the next touch");
        let worst = got.probabilities.iter().zip(&expected.probabilities).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(worst <= 1e-5, "window {w}: {worst:e}");
        assert_eq!((got.class, &got.label), (expected.class, &expected.label));
    }
}

#[test]
fn pruned_frames_are_dropped_unread_and_misuse_is_an_error() {
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let (_, x) = read_npy(&golden("input.npy")).unwrap();
    let kept = c.kept_frames().to_vec();
    let pruned = (0..75).find(|t| !kept.contains(t)).unwrap();
    let expected = c.classify(&x[..4500]).unwrap();
    let mut s = c.session().unwrap();
    assert!(matches!(s.finish(), Err(Error::Incomplete { got: 0, frames: 75 })));
    assert!(matches!(s.push_frame(&[0.0; 59]), Err(Error::FrameLength { got: 59, expected: 60 })));
    for t in 0..75 {
        let mut f = frame(&x, 0, t);
        if t == pruned {
            f[3] = f32::NAN; // never read: the model pruned this frame
        } else if t == kept[0] {
            let mut bad = f.clone();
            bad[5] = f32::INFINITY;
            assert!(matches!(s.push_frame(&bad), Err(Error::NonFinite { index: 5, .. })));
        }
        s.push_frame(&f).unwrap();
    }
    assert!(matches!(s.push_frame(&frame(&x, 0, 0)), Err(Error::TooManyFrames { frames: 75 })));
    assert_eq!(s.finish().unwrap().class, expected.class);
    s.push_frame(&frame(&x, 1, 0)).unwrap();
    s.reset();
    assert_eq!(s.received(), 0);
}

/// A provisional answer leaves the touch going; with every frame in it is the touch's answer;
/// before the first whole token it is a typed error.
#[test]
fn a_peek_reads_the_touch_so_far_and_leaves_it_going() {
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let (_, x) = read_npy(&golden("input.npy")).unwrap();
    let mut s = c.session().unwrap();
    assert!(matches!(s.peek(), Err(Error::NoTokenYet { tubelet: 1 })));
    let mut changed = false;
    let mut last: Option<Prediction> = None;
    for t in 0..75 {
        s.push_frame(&frame(&x, 2, t)).unwrap();
        let peek = s.peek().unwrap();
        assert_eq!((peek.frames, s.received(), peek.stop), (t + 1, t + 1, false), "the golden file has no stopping rule");
        assert_eq!(s.peek().unwrap().prediction.probabilities, peek.prediction.probabilities, "peeking changes nothing");
        changed |= last.is_some_and(|l| l.probabilities != peek.prediction.probabilities);
        last = Some(peek.prediction);
    }
    assert!(changed, "each token moves the provisional answer");
    let finished = s.finish().unwrap();
    assert_eq!(last.unwrap().probabilities, finished.probabilities, "with every frame in, a peek is the answer");
}

/// A file exported before format 1.1 has no key bias: it classifies and streams as before, and
/// a peek says why it cannot answer.
#[test]
fn a_file_without_the_key_bias_gives_no_provisional_answer() {
    use prost::Message;
    let bytes = std::fs::read(golden("model.onnx")).unwrap();
    let mut model = pvt3_format::onnx::ModelProto::decode(&bytes[..]).unwrap();
    for node in &mut model.graph.as_mut().unwrap().node {
        for name in node.input.iter_mut().chain(node.output.iter_mut()) {
            if name == TOKEN_BIAS {
                *name = "no_seam".into();
            }
        }
    }
    model.sign();
    let old = Classifier::from_bytes(&model.encode_to_vec(), "old.onnx").unwrap();
    let (_, x) = read_npy(&golden("input.npy")).unwrap();
    let mut s = old.session().unwrap();
    for t in 0..75 {
        s.push_frame(&frame(&x, 0, t)).unwrap();
    }
    assert!(matches!(s.peek(), Err(Error::NoPrefixes)));
    let expected = Classifier::load(golden("model.onnx")).unwrap().classify(&x[..4500]).unwrap();
    assert_eq!(s.finish().unwrap().probabilities, expected.probabilities);
}

/// A file with a spectral head that reads the whole window (here the golden graph with a node
/// writing `spectral_logits` and none writing `frame_weights`, as files exported before the head
/// streamed, signed again) loads where the runtime has the `spectral` feature, and is not
/// streamed; the small robot build, without it, refuses it at load, by name.
#[test]
fn a_spectral_file_needs_the_spectral_feature() {
    use prost::Message;
    use pvt3_format::onnx::{ModelProto, NodeProto, Op};
    let bytes = std::fs::read(golden("model.onnx")).unwrap();
    let mut model = ModelProto::decode(&bytes[..]).unwrap();
    model.graph.as_mut().unwrap().node.push(NodeProto {
        input: vec![pvt3_format::LOGITS.into()],
        output: vec![pvt3_format::SPECTRAL_LOGITS.into()],
        name: "spectral".into(),
        op_type: Op::Identity.name().into(),
        ..Default::default()
    });
    model.sign();
    let c = Classifier::from_bytes(&model.encode_to_vec(), "spectral.onnx").unwrap();
    assert!(!c.streams() && matches!(c.session(), Err(Error::WholeWindowOnly)));
}
