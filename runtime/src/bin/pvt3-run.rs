//! `pvt3-run MODEL.onnx INPUT.npy`: classify tactile windows on the robot with the pvt3 runtime.
//! INPUT holds one window `[height, width, (channels,) frames]` or a batch of them, raw sensor
//! values as recorded. Prints one line per window: index, class, label, probability.

use std::process::ExitCode;

use pvt3_runtime::{read_npy, Classifier};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 2 || args[0].starts_with('-') {
        eprintln!("usage: pvt3-run MODEL.onnx INPUT.npy\n\nClassifies the window(s) in INPUT (raw sensor values, [batch,] height, width, [channels,] frames) with the exported model.");
        return ExitCode::from(2);
    }
    match run(&args[0], &args[1]) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pvt3-run: {e}");
            ExitCode::FAILURE
        }
    }
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
