//! A soak test of the runtime: one classifier shared by several threads for minutes, each
//! thread classifying windows in batches, streaming touches through sessions with provisional
//! answers after every token, and sliding a continuous stream; every answer is checked against
//! the one a single thread got before the threads started (bit for bit), and the process's
//! resident memory is sampled as it runs. Prints one JSON object.
//!
//!   soak MODEL.onnx INPUT.npy THREADS SECONDS

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use pvt3_runtime::{read_npy, Classifier, Prediction};

/// Resident memory of this process, in KiB (Linux: /proc/self/statm, in pages).
fn resident_kib() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: u64 = statm.split_whitespace().nth(1).and_then(|v| v.parse().ok()).unwrap_or(0);
    pages * 4
}

/// Frame `t` of window `w` of windows laid out `[height, width, (channels,) frames]`.
fn frame(x: &[f32], sample: usize, frames: usize, w: usize, t: usize) -> Vec<f32> {
    (0..sample / frames).map(|j| x[w * sample + j * frames + t]).collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, model, input, threads, seconds] = &args[..] else {
        eprintln!("usage: soak MODEL.onnx INPUT.npy THREADS SECONDS");
        std::process::exit(2);
    };
    let (threads, seconds): (usize, f64) = (threads.parse().expect("THREADS"), seconds.parse().expect("SECONDS"));
    // SAFETY: the first thing main does, before any other thread exists.
    unsafe { pvt3_runtime::keep_freed_memory() };
    let c = Classifier::load(model).expect("the model loads");
    let (_, x) = read_npy(std::path::Path::new(input)).expect("the input reads");
    let sample: usize = c.sample_shape().iter().product();
    let frames = *c.sample_shape().last().unwrap();
    let windows = x.len() / sample;
    c.prepare(&[1, windows], c.streams()).expect("plans build");
    // The answers of one thread, before any other runs: what every later answer must equal.
    let batch = c.classify_batch(&x[..windows * sample], windows).unwrap();
    let single: Vec<Prediction> = (0..windows).map(|w| c.classify(&x[w * sample..(w + 1) * sample]).unwrap()).collect();
    let streamed: Vec<(Vec<Prediction>, Prediction)> = if c.streams() {
        let mut s = c.session().unwrap();
        (0..windows)
            .map(|w| {
                let mut peeks = Vec::new();
                for t in 0..frames {
                    s.push_frame(&frame(&x, sample, frames, w, t)).unwrap();
                    if (t + 1) % c.tubelet() == 0 {
                        peeks.push(s.peek().unwrap().prediction);
                    }
                }
                (peeks, s.finish().unwrap())
            })
            .collect()
    } else {
        Vec::new()
    };
    let stop = AtomicBool::new(false);
    let (classified, mismatches) = (AtomicU64::new(0), AtomicU64::new(0));
    let mut samples = vec![(0.0, resident_kib())];
    let started = Instant::now();
    std::thread::scope(|scope| {
        for k in 0..threads {
            let (c, x, batch, single, streamed, stop, classified, mismatches) =
                (&c, &x, &batch, &single, &streamed, &stop, &classified, &mismatches);
            scope.spawn(move || {
                let check = |ok: bool| {
                    if !ok {
                        mismatches.fetch_add(1, Ordering::Relaxed);
                    }
                };
                let mut round = k;
                while !stop.load(Ordering::Relaxed) {
                    let w = round % windows;
                    match round % 4 {
                        0 => {
                            check(c.classify_batch(&x[..windows * sample], windows).unwrap() == *batch);
                            classified.fetch_add(windows as u64, Ordering::Relaxed);
                        }
                        1 | 2 => {
                            check(c.classify(&x[w * sample..(w + 1) * sample]).unwrap() == single[w]);
                            classified.fetch_add(1, Ordering::Relaxed);
                        }
                        _ if c.streams() => {
                            // A session of its own per touch, dropped after it: sessions must not leak.
                            let mut s = c.session().unwrap();
                            let mut peeks = Vec::new();
                            for t in 0..frames {
                                s.push_frame(&frame(x, sample, frames, w, t)).unwrap();
                                if (t + 1) % c.tubelet() == 0 {
                                    peeks.push(s.peek().unwrap().prediction);
                                }
                            }
                            check(peeks == streamed[w].0 && s.finish().unwrap() == streamed[w].1);
                            // And a continuous stream over two windows back to back.
                            let mut slide = c.continuous(frames / c.tubelet()).unwrap();
                            for (v, t) in [w, (w + 1) % windows].into_iter().flat_map(|v| (0..frames).map(move |t| (v, t))) {
                                if let Some(p) = slide.push_frame(&frame(x, sample, frames, v, t)).unwrap() {
                                    check(p == single[v]);
                                }
                            }
                            classified.fetch_add(1 + 2 + peeks.len() as u64, Ordering::Relaxed);
                        }
                        _ => {}
                    }
                    round += threads;
                }
            });
        }
        let deadline = Duration::from_secs_f64(seconds);
        while started.elapsed() < deadline {
            std::thread::sleep(Duration::from_secs_f64((seconds / 60.0).clamp(0.5, 10.0)));
            samples.push((started.elapsed().as_secs_f64(), resident_kib()));
        }
        stop.store(true, Ordering::Relaxed);
    });
    // Growth: the last tenth of the samples against the samples of the first tenth after the
    // warm-up (plans built, allocator pools filled).
    let tenth = (samples.len() / 10).max(1);
    let mean = |s: &[(f64, u64)]| s.iter().map(|v| v.1 as f64).sum::<f64>() / s.len() as f64;
    let (early, late) = (mean(&samples[1..=tenth.min(samples.len() - 1)]), mean(&samples[samples.len() - tenth..]));
    let out = serde_json::json!({
        "model": model, "threads": threads, "seconds": started.elapsed().as_secs_f64(),
        "classifications": classified.load(Ordering::Relaxed), "mismatches": mismatches.load(Ordering::Relaxed),
        "resident_kib_start": samples[0].1, "resident_kib_early": early, "resident_kib_late": late,
        "resident_growth": late / early - 1.0, "samples": samples.len(),
    });
    println!("{out}");
    if mismatches.load(Ordering::Relaxed) > 0 {
        std::process::exit(1);
    }
}
