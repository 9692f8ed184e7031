//! The runtime alone (no exporter, no candle: these run on the robot's architecture too) on the
//! committed golden model: its logits equal the independent implementation's to 1e-5 with every
//! kernel choice, the default choice gives bit-identical outputs at every load and run, and a
//! classifier shared by several threads answers each as it answers one.

mod support;

use pvt3_runtime::{Classifier, Kernels};
use support::{emulated, golden, golden_vectors};

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn golden_logits_match_with_every_kernel_choice_at_batch_1_and_8() {
    let (x, expected) = golden_vectors();
    for kernels in [Kernels::Fixed, Kernels::Tract, Kernels::Measured] {
        let c = Classifier::load(golden("model.onnx")).unwrap().with_kernels(kernels);
        for batch in [8, 1] {
            let (logits, probabilities) = c.run(&x[..batch * 4500], batch).unwrap();
            assert_eq!(logits.len(), batch * 20);
            let err = logits.iter().zip(&expected).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
            assert!(err <= 1e-5, "{kernels:?}, batch {batch}: {err:e}");
            for p in probabilities.chunks(20) {
                assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            }
        }
    }
}

/// Window `w` of the golden input, frame by frame.
fn frames(x: &[f32], w: usize) -> Vec<Vec<f32>> {
    (0..75).map(|t| (0..60).map(|i| x[w * 4500 + i * 75 + t]).collect()).collect()
}

/// Everything one load answers for the golden input: batch 8, batch 1 per window, and two
/// windows streamed (one session reused; a streamed frame costs most under an emulator, and
/// `stream`'s tests hold every window's stream to its batch answer).
fn answers(c: &Classifier, x: &[f32]) -> Vec<Vec<u32>> {
    let mut out = vec![bits(&c.run(x, 8).unwrap().0)];
    let mut session = c.session().unwrap();
    for w in 0..8 {
        out.push(bits(&c.run(&x[w * 4500..(w + 1) * 4500], 1).unwrap().0));
    }
    for w in [0, 7] {
        for f in frames(x, w) {
            session.push_frame(&f).unwrap();
        }
        out.push(bits(&session.finish().unwrap().probabilities));
    }
    out
}

#[test]
fn the_default_kernels_give_bit_identical_outputs_across_loads_and_runs() {
    let (x, _) = golden_vectors();
    let first = Classifier::load(golden("model.onnx")).unwrap();
    let expected = answers(&first, &x);
    assert_eq!(answers(&first, &x), expected, "a second run of one load");
    // Two more loads, one prepared ahead; under an emulator the prepared one alone.
    for load in 0..if emulated() { 1 } else { 2 } {
        let again = Classifier::load(golden("model.onnx")).unwrap();
        if load == 0 {
            again.prepare(&[8, 1], true).unwrap();
        }
        assert_eq!(answers(&again, &x), expected, "load {load}");
    }
    assert!(matches!(first.prepare(&[0], false), Err(pvt3_runtime::Error::EmptyBatch)));
    assert!(matches!(first.run(&x, usize::MAX / 1000), Err(pvt3_runtime::Error::BatchTooLarge { .. })), "batch × sample length overflows");
}

#[test]
fn a_classifier_shared_by_threads_answers_each_as_it_answers_one() {
    let (x, _) = golden_vectors();
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let expected = answers(&c, &x);
    let shared = Classifier::load(golden("model.onnx")).unwrap();
    std::thread::scope(|s| {
        let threads: Vec<_> = (0..4).map(|_| s.spawn(|| (0..3).map(|_| answers(&shared, &x)).collect::<Vec<_>>())).collect();
        for t in threads {
            for got in t.join().unwrap() {
                assert_eq!(got, expected);
            }
        }
    });
}

/// Plans on two threads give the golden logits in a build with the `threads` feature (the
/// default), and a clear error in one without it (`--no-default-features`, the small build).
#[test]
fn two_threads_per_plan_need_the_threads_feature() {
    let (x, expected) = golden_vectors();
    let c = Classifier::load(golden("model.onnx")).unwrap().with_threads(2);
    let result = c.run(&x[..8 * 4500], 8);
    if cfg!(feature = "threads") {
        let (logits, _) = result.unwrap();
        let err = logits.iter().zip(&expected).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(err <= 1e-5, "{err:e}");
    } else {
        let err = result.unwrap_err();
        assert!(matches!(err, pvt3_runtime::Error::NoThreads { asked: 2 }), "{err}");
    }
}

/// `text` replaced by `with` (of the same length) in `bytes`, once.
fn replaced(bytes: &[u8], text: &str, with: &str) -> Vec<u8> {
    assert_eq!(text.len(), with.len());
    let at = bytes.windows(text.len()).position(|w| w == text.as_bytes()).unwrap_or_else(|| panic!("`{text}` not in the file"));
    let mut out = bytes.to_vec();
    out[at..at + text.len()].copy_from_slice(with.as_bytes());
    out
}

/// A well-signed file of another major format version is refused with a message that says so; a
/// newer minor version is read.
#[test]
fn a_file_of_another_major_format_version_is_refused() {
    let bytes = std::fs::read(golden("model.onnx")).unwrap();
    let claimed = bytes.windows(7).position(|w| w == b"sha256:").map(|at| String::from_utf8(bytes[at..at + 71].to_vec()).unwrap()).unwrap();
    let (major, minor) = pvt3_format::FORMAT_VERSION;
    let resigned = |version: &str| {
        // The metadata entry: key, then the value's tag (field 2, length-delimited) and length.
        let changed = replaced(&bytes, &format!("pvt3.format\u{12}\u{3}{major}.{minor}"), &format!("pvt3.format\u{12}\u{3}{version}"));
        let digest = pvt3_format::digest(&changed).unwrap();
        replaced(&changed, &claimed, &digest)
    };
    let err = Classifier::from_bytes(&resigned("2.0"), "v2.onnx").err().expect("format 2.0 refused");
    assert!(err.to_string().contains(&format!("format 2.0, which this runtime (format {major}.{minor}) does not read")), "{err}");
    assert!(Classifier::from_bytes(&resigned("1.9"), "v1.9.onnx").is_ok());
}
