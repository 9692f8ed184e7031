//! Classify touches with the pvt3 runtime from Rust: the guide's snippet (docs/guide/robot.md) as a whole program,
//! which `cargo test` builds and runs (`runtime/tests/rust_example.rs`).
//!
//!     cargo run --release -p pvt3-runtime --example classify -- WINDOWS.npy
//!
//! Loads `model.onnx` from the current folder, classifies the first window of WINDOWS.npy whole
//! and frame by frame, streams it again until the file's stopping rule says the material is clear,
//! and slides over all the windows as one stream. Prints one line per answer: how, the class name
//! and its probability.

use pvt3_runtime::{Classifier, Prediction, Result};

// The guide's snippet (docs/guide/robot.md), from here to the end of `slide`.
/// A window classified whole, and the same touch streamed frame by frame as the sensor delivers it.
fn classify(classifier: &Classifier, window: &[f32], frames: &[Vec<f32>]) -> Result<(Prediction, Prediction)> {
    classifier.prepare(&[1], true)?; // at start-up: build the plans, so the first touch costs no more
    let whole = classifier.classify(window)?; // raw values, [height, width, (channels,) frames] row-major
    let mut touch = classifier.session()?;
    for frame in frames {
        touch.push_frame(frame)?;
    }
    Ok((whole, touch.finish()?)) // the same answer, each kept frame encoded as it arrived
}

/// A touch ended as soon as the file's stopping rule (calibrated at training) says it is clear.
fn until_clear(classifier: &Classifier, frames: &[Vec<f32>]) -> Result<Prediction> {
    let mut touch = classifier.session()?;
    for frame in frames {
        touch.push_frame(frame)?;
        if let Ok(peek) = touch.peek() {
            if peek.stop {
                touch.reset(); // the next touch starts afresh in the same session
                return Ok(peek.prediction);
            }
        }
    }
    touch.finish()
}

/// A robot that keeps sliding: no end to the stream, an answer after every token once a window
/// is in (the latest window's, what `classify` gives it).
fn slide(classifier: &Classifier, sensor: impl IntoIterator<Item = Vec<f32>>) -> Result<Vec<Prediction>> {
    let mut stream = classifier.continuous(1)?;
    let mut answers = Vec::new();
    for frame in sensor {
        answers.extend(stream.push_frame(&frame)?);
    }
    Ok(answers)
}
// The end of the guide's snippet.

/// Frame `t` of each window of `values` (`[windows, …, frames]`, row-major): the frames a sensor
/// would deliver, window after window.
fn frames_of(values: &[f32], window_len: usize, frames: usize) -> Vec<Vec<f32>> {
    values.chunks(window_len).flat_map(|w| (0..frames).map(move |t| w.iter().skip(t).step_by(frames).copied().collect())).collect()
}

fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let input = std::env::args().nth(1).ok_or("usage: classify WINDOWS.npy (with model.onnx in this folder)")?;
    let classifier = Classifier::load("model.onnx")?; // refused if damaged since export
    let (_, values) = pvt3_runtime::read_npy(std::path::Path::new(&input))?;
    let window_len: usize = classifier.sample_shape().iter().product();
    let frames_per_window = *classifier.sample_shape().last().ok_or("a window has frames")?;
    let all = frames_of(&values, window_len, frames_per_window);
    let first = &all[..frames_per_window];
    let (whole, streamed) = classify(&classifier, &values[..window_len], first)?;
    let clear = until_clear(&classifier, first)?;
    let say = |how: &str, p: &Prediction| println!("{how}\t{}\t{:.6}", p.label, p.probabilities[p.class]);
    say("whole", &whole);
    say("streamed", &streamed);
    say("until clear", &clear);
    for p in slide(&classifier, all)? {
        say("slide", &p);
    }
    Ok(())
}
