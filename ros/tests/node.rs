//! pvt3-ros on a real zenoh transport, on loopback only: a router, a sensor driver and a listener
//! that no one here wrote (tests/ros_peer.py: eclipse-zenoh, messages by rosbags) around the
//! node's binary. Its answers equal the runtime's for the same frames (what `pvt3-run` computes,
//! its own calls: `classify_camera_touches`, `classify_batch`), for a camera's file and a taxel
//! array's; the listener finds the node by rmw_zenoh's tokens and reads its answers on the keys
//! it computes itself; hostile traffic (frames of the wrong size or encoding, cut CDR, a foreign
//! type, a publisher that leaves mid-touch, a second publisher, a frame out of order) is refused
//! on `/rosout` while the node serves on. A camera's recording cut as `touch:=moving` is answered
//! over the frames `pvt3 import` takes of it (`FrameSpan::Moving`). Built for aarch64, the node
//! runs under the emulator `PVT3_TARGET_RUNNER` names (tests/run.sh), the peer on the host.

#[path = "../../tests/support/onnx_check.rs"]
#[allow(dead_code)] // the other end-to-end tests use the rest of it
mod onnx_check;
#[path = "../../tests/support/target.rs"]
#[allow(dead_code)] // `emulated` is the runtime's tests'
mod target;
#[path = "../../tests/support/workspace.rs"]
mod workspace;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

use pvt3_format::span::FrameSpan;
use pvt3_runtime::{Classifier, Picture};
use workspace::workspace;

/// What the listener heard: the answers' probabilities, the statuses and the `/rosout` lines.
struct Heard {
    answers: Vec<Vec<f32>>,
    statuses: Vec<serde_json::Value>,
    logs: Vec<String>,
    node_said: String,
}

/// Runs the peer on `touches` (`kind`: image or array) and the node on `model` with `params`.
fn converse(model: &Path, touches: &Path, kind: &str, hostile: bool, params: &[&str]) -> Heard {
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port().to_string();
    let python = onnx_check::python();
    let mut peer = Command::new(python);
    peer.arg(workspace().join("tests/ros_peer.py")).args([port.as_str(), touches.to_str().unwrap(), kind]);
    if hostile {
        peer.arg("hostile");
    }
    let mut peer = peer.stdout(Stdio::piped()).spawn().expect("the peer runs");
    let mut lines = BufReader::new(peer.stdout.take().unwrap()).lines();
    assert_eq!(lines.next().unwrap().unwrap(), "ready");
    let router = format!("router:=tcp/127.0.0.1:{port}");
    let mut args = vec!["--ros-args", "-p", &router];
    let model = format!("model:={}", model.display());
    args.extend(["-p", &model]);
    params.iter().for_each(|p| args.extend(["-p", p]));
    let mut node =
        target::target_command(env!("CARGO_BIN_EXE_pvt3-ros")).args(&args).stderr(Stdio::piped()).spawn().expect("the node runs");
    let heard: Vec<serde_json::Value> = lines.map(|l| serde_json::from_str(&l.unwrap()).unwrap()).collect();
    assert!(peer.wait().unwrap().success(), "the peer failed");
    node.kill().unwrap();
    let output = node.wait_with_output().unwrap();
    let node_said = String::from_utf8_lossy(&output.stderr).to_string();
    let floats = |v: &serde_json::Value| v.as_array().unwrap().iter().map(|p| p.as_f64().unwrap() as f32).collect();
    Heard {
        answers: heard.iter().filter_map(|h| h.get("probabilities").map(floats)).collect(),
        statuses: heard.iter().filter_map(|h| h.get("status").cloned()).collect(),
        logs: heard.iter().filter_map(|h| h.get("log").and_then(|l| l.as_str()).map(String::from)).collect(),
        node_said,
    }
}

fn assert_close(heard: &[Vec<f32>], expected: &[Vec<f32>], what: &str) {
    assert_eq!(heard.len(), expected.len(), "{what}: answers");
    for (k, (h, e)) in heard.iter().zip(expected).enumerate() {
        let worst = h.iter().zip(e).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
        assert!(h.len() == e.len() && worst <= 1e-5, "{what}, touch {k}: off by {worst}");
    }
}

#[test]
fn a_camera_s_touches_are_answered_as_the_runtime_answers_them_through_hostile_traffic() {
    let model = workspace().join("shipped/physiclear.onnx");
    let classifier = Classifier::load(&model).unwrap();
    let [h, w, c] = classifier.camera().unwrap().recorded;
    let frames = *classifier.sample_shape().last().unwrap();
    // Two touches of the camera's frames as it gives them: [touches, height, width, channels, frames].
    let values: Vec<u8> = (0..2 * h * w * c * frames).map(|i| ((i * 7 + i / 997) % 251) as u8).collect();
    let dir = std::env::temp_dir().join(format!("pvt3-ros-camera-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let touches = dir.join("touches.npy");
    let array = ndarray::ArrayD::from_shape_vec(ndarray::IxDyn(&[2, h, w, c, frames]), values.clone()).unwrap();
    ndarray_npy::write_npy(&touches, &array).unwrap();
    let expected: Vec<Vec<f32>> = classifier.classify_camera_touches(&values, 2).unwrap().into_iter().map(|p| p.probabilities).collect();
    let heard = converse(&model, &touches, "image", true, &["early_stop:=false"]);
    assert_close(&heard.answers, &expected, "camera");
    let left = format!("the publisher of the touch's frames left after {} frames: the touch is dropped", frames / 2);
    let refusals = [
        "a frame of 120 × 320 RGB; the file reads the camera's 240 × 320 × 3",
        "encoding `yuv422`",
        "truncated",
        "too short for a CDR message",
        "String_, which pvt3 does not read",
        &left,
        "a second publisher's frame, dropped: the touch is the first's (4 frames in)",
        "before the one before it",
    ];
    for why in refusals {
        assert!(heard.logs.iter().any(|l| l.contains(why)), "/rosout lacks `{why}`: {:?}", heard.logs);
    }
    assert!(!heard.node_said.contains("panicked"), "{}", heard.node_said);
    let status = &heard.statuses[0];
    assert_eq!((status["frames"].as_str(), status["ended_by"].as_str()), (Some(frames.to_string().as_str()), Some("window")), "{status}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_taxel_array_s_touches_are_answered_as_the_runtime_answers_them() {
    let model = workspace().join("tests/golden/icub20/model.onnx");
    let touches = workspace().join("tests/golden/icub20/input.npy");
    let (shape, values) = pvt3_runtime::read_npy(&touches).unwrap();
    let classifier = Classifier::load(&model).unwrap();
    let expected: Vec<Vec<f32>> = classifier.classify_batch(&values, shape[0]).unwrap().into_iter().map(|p| p.probabilities).collect();
    let heard = converse(&model, &touches, "array", false, &[]);
    assert_close(&heard.answers, &expected, "iCub");
}

#[test]
fn a_camera_s_recording_is_answered_over_its_moving_span_as_the_import_takes_it() {
    let model = workspace().join("shipped/physiclear.onnx");
    let classifier = Classifier::load(&model).unwrap();
    let camera = classifier.camera().unwrap();
    let [h, w, c] = camera.recorded;
    let window = classifier.session().unwrap().frames();
    // A recording of 4 windows' frames: the bare gel, then a texture sliding across it for two
    // windows, then the bare gel again.
    let recorded = 4 * window;
    let sliding = window..3 * window;
    let pictures: Vec<Picture> = (0..recorded)
        .map(|t| {
            let (row, column) = (|i: usize| i / (w * c), |i: usize| (i / c) % w);
            let data =
                (0..h * w * c)
                    .map(|i| {
                        if sliding.contains(&t) {
                            ((column(i) + 3 * t) * 37 % 251 + row(i) * 5 % 50) as u8
                        } else {
                            (100 + row(i) / 8) as u8
                        }
                    })
                    .collect();
            Picture { height: h, width: w, channels: c, data }
        })
        .collect();
    let taken = FrameSpan::Moving.take(&pictures, window);
    assert!(taken.first >= window - 1 && taken.last <= 3 * window + 1, "the span {}..={} is not the sliding's", taken.first, taken.last);
    let chosen: Vec<usize> = camera.subtract_first.then_some(0).into_iter().chain(taken.frames.iter().copied()).collect();
    let layout = |frames: &[usize]| -> Vec<u8> {
        (0..h * w * c).flat_map(|i| frames.iter().map(move |&t| (t, i))).map(|(t, i)| pictures[t].data[i]).collect()
    };
    let answer = |frames: &[usize]| classifier.classify_camera_touches(&layout(frames), 1).unwrap()[0].probabilities.clone();
    let expected = vec![answer(&chosen)];
    // The test tells the spans apart: the whole recording's frames answer otherwise, by more
    // than ten times the tolerance.
    let whole = FrameSpan::Whole.take(&pictures, window).frames;
    let whole: Vec<usize> = camera.subtract_first.then_some(0).into_iter().chain(whole).collect();
    let apart = answer(&whole).iter().zip(&expected[0]).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
    assert!(apart > 1e-4, "the whole recording answers as its moving span does (off by {apart})");
    let dir = std::env::temp_dir().join(format!("pvt3-ros-moving-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let touches = dir.join("recording.npy");
    let all: Vec<usize> = (0..recorded).collect();
    let array = ndarray::ArrayD::from_shape_vec(ndarray::IxDyn(&[1, h, w, c, recorded]), layout(&all)).unwrap();
    ndarray_npy::write_npy(&touches, &array).unwrap();
    let heard = converse(&model, &touches, "image", false, &["touch:=moving", &format!("recording:={recorded}")]);
    assert_close(&heard.answers, &expected, "moving span");
    let status = &heard.statuses[0];
    assert_eq!(
        (status["frames"].as_str(), status["ended_by"].as_str()),
        (Some(recorded.to_string().as_str()), Some("recording")),
        "{status}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
