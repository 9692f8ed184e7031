//! A soak test of the runtime: one classifier shared by several threads for minutes, each
//! thread classifying windows in batches, streaming touches through sessions with provisional
//! answers after every token, and sliding a continuous stream; every answer is checked against
//! the one a single thread got before the threads started (bit for bit), and the process's
//! resident memory is sampled as it runs. Prints one JSON object.
//!
//!   soak MODEL.onnx INPUT.npy THREADS SECONDS

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use pvt3_runtime::{read_npy, Classifier, Prediction, Session};

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

/// The windows of the input, as the model reads them.
struct Windows {
    x: Vec<f32>,
    /// Values a window, frames a window, windows.
    sample: usize,
    frames: usize,
    count: usize,
}

impl Windows {
    fn window(&self, w: usize) -> &[f32] {
        &self.x[w * self.sample..(w + 1) * self.sample]
    }

    fn all(&self) -> &[f32] {
        &self.x[..self.count * self.sample]
    }

    /// Window `w` streamed through `s`: the provisional answer after every token, and the last.
    fn stream(&self, c: &Classifier, s: &mut Session, w: usize) -> (Vec<Prediction>, Prediction) {
        let mut peeks = Vec::new();
        for t in 0..self.frames {
            s.push_frame(&frame(&self.x, self.sample, self.frames, w, t)).unwrap();
            if (t + 1) % c.tubelet() == 0 {
                peeks.push(s.peek().unwrap().prediction);
            }
        }
        (peeks, s.finish().unwrap())
    }
}

/// The answers of one thread, before any other runs: what every later answer must equal.
struct Expected {
    batch: Vec<Prediction>,
    single: Vec<Prediction>,
    /// Each window streamed (where the model streams).
    streamed: Vec<(Vec<Prediction>, Prediction)>,
}

impl Expected {
    fn of(c: &Classifier, win: &Windows) -> Self {
        let batch = c.classify_batch(win.all(), win.count).unwrap();
        let single = (0..win.count).map(|w| c.classify(win.window(w)).unwrap()).collect();
        let streamed = match c.streams() {
            true => {
                let mut s = c.session().unwrap();
                (0..win.count).map(|w| win.stream(c, &mut s, w)).collect()
            }
            false => Vec::new(),
        };
        Self { batch, single, streamed }
    }
}

/// Round `round` of a thread's work: the whole batch, one window, or (where the model streams)
/// a touch through a session of its own, dropped after it (sessions must not leak), and a
/// continuous stream over two windows back to back. Returns how many of its checks found an
/// answer other than the expected one, and how many answers it took.
fn one_round(c: &Classifier, win: &Windows, expected: &Expected, round: usize) -> (u64, u64) {
    let differs = |same: bool| u64::from(!same);
    let w = round % win.count;
    match round % 4 {
        0 => (differs(c.classify_batch(win.all(), win.count).unwrap() == expected.batch), win.count as u64),
        1 | 2 => (differs(c.classify(win.window(w)).unwrap() == expected.single[w]), 1),
        _ if c.streams() => {
            let touch = win.stream(c, &mut c.session().unwrap(), w);
            let mut mismatches = differs(touch == expected.streamed[w]);
            let mut slide = c.continuous(win.frames / c.tubelet()).unwrap();
            for v in [w, (w + 1) % win.count] {
                for t in 0..win.frames {
                    if let Some(p) = slide.push_frame(&frame(&win.x, win.sample, win.frames, v, t)).unwrap() {
                        mismatches += differs(p == expected.single[v]);
                    }
                }
            }
            (mismatches, 1 + 2 + touch.0.len() as u64)
        }
        _ => (0, 0),
    }
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
    let win = Windows { count: x.len() / sample, frames: *c.sample_shape().last().unwrap(), sample, x };
    c.prepare(&[1, win.count], c.streams()).expect("plans build");
    let expected = Expected::of(&c, &win);
    let stop = AtomicBool::new(false);
    let (classified, mismatches) = (AtomicU64::new(0), AtomicU64::new(0));
    let mut samples = vec![(0.0, resident_kib())];
    let started = Instant::now();
    std::thread::scope(|scope| {
        for k in 0..threads {
            let (c, win, expected, stop, classified, mismatches) = (&c, &win, &expected, &stop, &classified, &mismatches);
            scope.spawn(move || {
                let mut round = k;
                while !stop.load(Ordering::Relaxed) {
                    let (differed, answers) = one_round(c, win, expected, round);
                    mismatches.fetch_add(differed, Ordering::Relaxed);
                    classified.fetch_add(answers, Ordering::Relaxed);
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
