//! `pvt3-run MODEL.onnx INPUT.npy`: classify tactile windows on the robot with the pvt3 runtime.
//! INPUT holds one window `[height, width, (channels,) frames]` or a batch of them, raw sensor
//! values as recorded (axes of length 1 may be left out); for a model of a camera's frames that
//! records how `pvt3 import` read them (`pvt3.camera`), INPUT may instead hold touches of the
//! camera's 8-bit frames as it gives them, read as the import read them. Prints one line per
//! window: index, class, label, probability; with `--json`, one JSON object per window with
//! every probability.
//! `--help` and `--version` answer on standard output. Exit status: 0 answered, 1 refused (the
//! reason on standard error), 2 a command line it cannot read.
//!
//! `pvt3-run --bench MODEL.onnx [THREADS [SECONDS]]` measures latency on this machine instead
//! (one JSON line; see `bench.rs`).

#![deny(clippy::undocumented_unsafe_blocks)]

use std::process::ExitCode;

use pvt3_runtime::{read_npy, Classifier};

mod bench;

const USAGE: &str = "usage: pvt3-run [--json] MODEL.onnx INPUT.npy
       pvt3-run --bench MODEL.onnx [THREADS [SECONDS]]
       pvt3-run --help | --version

Classifies the window(s) in INPUT (raw sensor values, [batch,] height, width, [channels,] frames;
axes of length 1 may be left out; float32, float64, int16 or uint8) with the exported model, one
line per window: index, class, label, probability; --json prints one JSON object per window
instead, with every probability. For a model of a camera's frames that records how pvt3 import
read them, INPUT may hold the camera's 8-bit frames as it gives them ([batch,] its height, width,
channels, frames: one more, first, for a model read less the touch's first), each read as the
import read them.
--bench measures latency instead, on THREADS threads (default 1) for about SECONDS (default 2)
per measurement: batch 1 and 32, batch 1 with tract's own kernels and with kernels timed at load,
the first call, and a streamed touch (per kept frame, per pruned frame, end of touch; not for a
file whose spectral head reads the whole window, exported before the head streamed). Prints one JSON line.
Options may come in any position.

Exit status: 0 when every window is answered (or the benchmark ran); 1 when the file or the input
is refused, the reason on standard error; 2 for a command line it cannot read.";

fn main() -> ExitCode {
    // SAFETY: first thing in main, before any other thread exists.
    unsafe { pvt3_runtime::keep_freed_memory() };
    let args: Vec<String> = std::env::args().skip(1).collect();
    // Flags in any position; the rest are the positional words, in order.
    let (flags, words): (Vec<&str>, Vec<&str>) = args.iter().map(String::as_str).partition(|a| a.starts_with('-') && a.len() > 1);
    let number = |word: Option<&&str>, default: f64| word.map_or(Some(default), |v| v.parse::<f64>().ok().filter(|v| *v > 0.0));
    let outcome = match (flags.as_slice(), words.as_slice()) {
        (flags, _) if flags.iter().any(|f| ["--help", "-h"].contains(f)) => {
            say(USAGE);
            return ExitCode::SUCCESS;
        }
        (flags, _) if flags.iter().any(|f| ["--version", "-V"].contains(f)) => {
            say(&format!("pvt3-run {}", pvt3_runtime::version()));
            return ExitCode::SUCCESS;
        }
        (["--bench"], [model, rest @ ..]) if rest.len() <= 2 => match (number(rest.first(), 1.0), number(rest.get(1), 2.0)) {
            (Some(threads), Some(seconds)) => bench::bench(model, threads as usize, seconds).map(|report| say(&report.to_string())),
            _ => return usage("THREADS and SECONDS are positive numbers"),
        },
        ([], [model, input]) => run(model, input, false),
        (["--json"], [model, input]) => run(model, input, true),
        (flags, _) => match flags.iter().find(|f| !["--json", "--bench"].contains(f)) {
            Some(unknown) => return usage(&format!("no option `{unknown}`")),
            None => return usage("expected MODEL.onnx INPUT.npy, or --bench MODEL.onnx"),
        },
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pvt3-run: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Prints a line on standard output; a reader that has closed it (`pvt3-run … | head`) ends the
/// program quietly, as Unix tools end.
fn say(line: &str) {
    use std::io::Write;
    if let Err(e) = writeln!(std::io::stdout(), "{line}") {
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!("pvt3-run: standard output: {e}");
            std::process::exit(1);
        }
        std::process::exit(0);
    }
}

/// A command line it cannot read: what is wrong, then the usage; exit status 2.
fn usage(why: &str) -> ExitCode {
    eprintln!("pvt3-run: {why}\n\n{USAGE}");
    ExitCode::from(2)
}

fn run(model: &str, input: &str, json: bool) -> pvt3_runtime::Result<()> {
    let classifier = Classifier::load(model)?;
    let (shape, values) = read_npy(std::path::Path::new(input))?;
    let npy = |reason| pvt3_runtime::Error::Npy { path: input.to_string(), reason };
    // The model's own windows, else touches of the camera's frames as it gives them.
    let camera = classifier.camera().and_then(|c| batch_of(&shape[..shape.len().saturating_sub(1)], &c.recorded));
    let predictions = match (windows(&shape, classifier.sample_shape()), camera) {
        (Ok(batch), _) => classifier.classify_batch(&values, batch)?,
        (Err(_), Some(touches)) => classifier.classify_camera_touches(&bytes(&values).map_err(npy)?, touches)?,
        (Err(why), None) => return Err(npy(why)),
    };
    for (i, p) in predictions.iter().enumerate() {
        match json {
            true => {
                let line = serde_json::json!({"window": i, "class": p.class, "label": p.label, "probabilities": p.probabilities});
                say(&line.to_string());
            }
            false => say(&format!("{i}\t{}\t{}\t{:.4}", p.class, p.label, p.probabilities[p.class])),
        }
    }
    Ok(())
}

/// How many of the model's windows an array of `shape` holds: one window of `sample` (`[height,
/// width, (channels,) frames]`) or a batch of them, axes of length 1 left in or out. Otherwise
/// what is wrong, in the user's terms.
fn windows(shape: &[usize], sample: &[usize]) -> Result<usize, String> {
    let numbers = |s: &[usize], by: &str| s.iter().map(usize::to_string).collect::<Vec<_>>().join(by);
    if shape.contains(&0) {
        return Err(format!("an empty array, of shape [{}]", numbers(shape, ", ")));
    }
    if let Some(batch) = batch_of(shape, sample) {
        return Ok(batch);
    }
    let long = |s: &[usize]| s.iter().copied().filter(|&n| n != 1).collect::<Vec<_>>();
    let (frames, space) = sample.split_last().expect("a frame axis");
    let hint = match shape.split_last() {
        Some((n, rest)) if n != frames && long(rest).ends_with(&long(space)) => {
            format!("; its windows have {n} frames where the model reads {frames}: cut each touch into windows of {frames} frames")
        }
        _ => String::new(),
    };
    Err(format!(
        "an array of shape [{}]; the model reads one window of {} (height × width × [channels ×] frames) or a batch of them{hint}",
        numbers(shape, ", "),
        numbers(sample, " × ")
    ))
}

/// How many arrays of `one` an array of `shape` holds, one or a batch of them, axes of length 1
/// left in or out; `None` where it holds neither.
fn batch_of(shape: &[usize], one: &[usize]) -> Option<usize> {
    let long = |s: &[usize]| s.iter().copied().filter(|&n| n != 1).collect::<Vec<_>>();
    let (got, want) = (long(shape), long(one));
    match got.len() == want.len() + 1 && got[1..] == want[..] {
        true => Some(got[0]),
        false => (got == want).then_some(1),
    }
}

/// The array's values as a camera's bytes, or which is not one.
fn bytes(values: &[f32]) -> Result<Vec<u8>, String> {
    let byte = |(i, v): (usize, &f32)| match v.fract() == 0.0 && (0.0..=255.0).contains(v) {
        true => Ok(*v as u8),
        false => Err(format!("value {i} is {v}: a camera's frames are 8-bit, 0 to 255")),
    };
    values.iter().enumerate().map(byte).collect()
}

#[cfg(test)]
mod tests {
    use super::{batch_of, bytes, windows};

    #[test]
    fn a_camera_s_touches_are_told_from_the_model_s_windows_by_their_frames_size() {
        let recorded = [240, 320, 3];
        assert_eq!(batch_of(&[240, 320, 3], &recorded), Some(1));
        assert_eq!(batch_of(&[5, 240, 320, 3], &recorded), Some(5));
        assert_eq!(batch_of(&[30, 40, 3], &recorded), None);
        assert_eq!(batch_of(&[240, 320], &[240, 320, 1]), Some(1), "grey");
        assert_eq!(bytes(&[0.0, 255.0, 7.0]), Ok(vec![0, 255, 7]));
        assert!(bytes(&[0.0, 0.5]).unwrap_err().starts_with("value 1 is 0.5"));
        assert!(bytes(&[256.0]).is_err() && bytes(&[-1.0]).is_err());
    }

    #[test]
    fn one_window_or_a_batch_with_or_without_axes_of_length_one() {
        let sample = [24, 1, 270];
        assert_eq!(windows(&[24, 1, 270], &sample), Ok(1));
        assert_eq!(windows(&[24, 270], &sample), Ok(1));
        assert_eq!(windows(&[1, 24, 1, 270], &sample), Ok(1));
        assert_eq!(windows(&[3, 24, 1, 270], &sample), Ok(3));
        assert_eq!(windows(&[3, 24, 270], &sample), Ok(3));
        assert_eq!(windows(&[6, 10, 3, 75], &[6, 10, 3, 75]), Ok(1));
        assert_eq!(windows(&[8, 6, 10, 3, 75], &[6, 10, 3, 75]), Ok(8));
    }

    #[test]
    fn a_wrong_shape_is_named_with_what_the_model_reads() {
        let e = windows(&[3, 24, 281], &[24, 1, 270]).unwrap_err();
        assert!(e.starts_with("an array of shape [3, 24, 281]; the model reads one window of 24 × 1 × 270"), "{e}");
        assert!(e.ends_with("its windows have 281 frames where the model reads 270: cut each touch into windows of 270 frames"), "{e}");
        let e = windows(&[3, 19, 270], &[24, 1, 270]).unwrap_err();
        assert!(e.contains("[3, 19, 270]") && !e.contains("cut each touch"), "{e}");
        assert!(windows(&[0, 24, 270], &[24, 1, 270]).unwrap_err().starts_with("an empty array"));
        assert!(windows(&[10, 6, 3, 75], &[6, 10, 3, 75]).is_err(), "height and width swapped");
    }
}
