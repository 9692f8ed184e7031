//! `pvt3-run MODEL.onnx INPUT.npy`: classify tactile windows on the robot with the pvt3 runtime.
//! INPUT holds one window `[height, width, (channels,) frames]` or a batch of them, raw sensor
//! values as recorded. Prints one line per window: index, class, label, probability.
//!
//! `pvt3-run --bench MODEL.onnx [THREADS [SECONDS]]` measures latency on this machine instead
//! (one JSON line; see `bench.rs`).

#![deny(clippy::undocumented_unsafe_blocks)]

use std::process::ExitCode;

use pvt3_runtime::{read_npy, Classifier};

mod bench;

const USAGE: &str = "usage: pvt3-run MODEL.onnx INPUT.npy
       pvt3-run --bench MODEL.onnx [THREADS [SECONDS]]

Classifies the window(s) in INPUT (raw sensor values, [batch,] height, width, [channels,] frames)
with the exported model, one line per window: index, class, label, probability.
--bench measures latency instead, on THREADS threads (default 1) for about SECONDS (default 2)
per measurement: batch 1 and 32, batch 1 with tract's own kernels and with kernels timed at load,
the first call, and a streamed touch (per kept frame, per pruned frame, end of touch; not for a
file whose spectral head reads the whole window, exported before the head streamed). Prints one JSON line.";

fn main() -> ExitCode {
    // SAFETY: first thing in main, before any other thread exists.
    unsafe { pvt3_runtime::keep_freed_memory() };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |i: usize, default: f64| args.get(i).map_or(Some(default), |v| v.parse::<f64>().ok().filter(|v| *v > 0.0));
    let outcome = match args.iter().map(String::as_str).collect::<Vec<_>>().as_slice() {
        ["--bench", model, ..] if args.len() <= 4 => match (number(2, 1.0), number(3, 2.0)) {
            (Some(threads), Some(seconds)) => bench::bench(model, threads as usize, seconds).map(|report| println!("{report}")),
            _ => return usage(),
        },
        [model, input] if !model.starts_with('-') => run(model, input),
        _ => return usage(),
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pvt3-run: {e}");
            ExitCode::FAILURE
        }
    }
}

fn usage() -> ExitCode {
    eprintln!("{USAGE}");
    ExitCode::from(2)
}

fn run(model: &str, input: &str) -> pvt3_runtime::Result<()> {
    let classifier = Classifier::load(model)?;
    let (shape, values) = read_npy(std::path::Path::new(input))?;
    let batch = if shape.len() == classifier.sample_shape().len() { 1 } else { shape.first().copied().unwrap_or(0) };
    for (i, p) in classifier.classify_batch(&values, batch)?.iter().enumerate() {
        println!("{i}\t{}\t{}\t{:.4}", p.class, p.label, p.probabilities[p.class]);
    }
    Ok(())
}
