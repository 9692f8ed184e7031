//! A stream of three golden windows back to back (225 frames), classified continuously: every
//! answer is the batch classification of the window ending at its frame.

use std::path::PathBuf;

use crate::{read_npy, Classifier, Error};

fn golden(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/icub20").join(file)
}

/// The golden input's first `windows` windows, `[6 × 10, 75]` each, as one stream of frames.
fn stream(windows: usize) -> Vec<Vec<f32>> {
    let (_, x) = read_npy(&golden("input.npy")).unwrap();
    (0..windows).flat_map(|w| (0..75).map(move |t| (w, t))).map(|(w, t)| (0..60).map(|i| x[w * 4500 + i * 75 + t]).collect()).collect()
}

/// The window of the stream's frames `end - 75..end`, in the model's layout.
fn window(stream: &[Vec<f32>], end: usize) -> Vec<f32> {
    (0..60).flat_map(|i| (end - 75..end).map(move |t| stream[t][i])).collect()
}

#[test]
fn every_answer_is_the_batch_classification_of_the_latest_window() {
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let frames = stream(3);
    for every in [1, 7] {
        let mut continuous = c.continuous(every).unwrap();
        let mut answered = Vec::new();
        for (f, frame) in frames.iter().enumerate() {
            if let Some(p) = continuous.push_frame(frame).unwrap() {
                let expected = c.classify(&window(&frames, f + 1)).unwrap();
                assert_eq!(p, expected, "every {every}, window ending at frame {}", f + 1);
                answered.push(f + 1);
            }
        }
        // After the first whole window, then every `every` frames (tubelet 1).
        let due: Vec<usize> = (75..=225).step_by(every).collect();
        assert_eq!(answered, due, "every {every}");
        assert_eq!(continuous.received(), 225);
    }
}

#[test]
fn a_reset_stream_waits_for_a_whole_window_and_misuse_is_an_error() {
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let frames = stream(2);
    let mut continuous = c.continuous(1).unwrap();
    for frame in &frames[..100] {
        continuous.push_frame(frame).unwrap();
    }
    continuous.reset();
    let first = frames[75..150].iter().position(|f| continuous.push_frame(f).unwrap().is_some());
    assert_eq!(first, Some(74), "the 75th frame after the reset answers");
    assert!(matches!(c.continuous(0), Err(Error::NoStride)));
    assert!(matches!(continuous.push_frame(&[0.0; 59]), Err(Error::FrameLength { got: 59, expected: 60 })));
    let mut nan = frames[0].clone();
    nan[3] = f32::NAN;
    assert!(matches!(continuous.push_frame(&nan), Err(Error::NonFinite { index: 3, .. })));
    assert_eq!(continuous.received(), 75, "a refused frame is not taken");
}
