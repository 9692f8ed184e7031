//! `pvt3-run --bench MODEL.onnx`: latency on this machine, measured the way a robot runs the
//! model. Whole windows at batch 1 (median and p99) and batch 32 (windows per second), and a
//! streamed touch: each kept frame's spatial encoding, each pruned frame's drop, and the
//! end-of-touch temporal stage; and a continuous stream answering after every token (the cost
//! of one answer, and per token). Inputs are synthetic (latency does not depend on the values).
//! Also the load (read, digest check, parse), the digest check alone, `Classifier::prepare` for
//! batch 1 and streaming, and the first call after it.
//! The classifier chooses its kernels by the default fixed rule; batch 1 is also measured with
//! tract's own choice ("untuned") and with kernels timed at load ("measured"), and the first call,
//! which builds the plan, is timed with the fixed rule and with timing.

use std::time::{Duration, Instant};

use pvt3_runtime::{Classifier, Kernels, Result};
use serde_json::json;

/// Deterministic values of about unit scale.
fn synthetic(n: usize) -> Vec<f32> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        })
        .collect()
}

/// Runs `f` until `budget` is spent (at least `min` times) after three untimed calls.
fn sample(budget: Duration, min: usize, mut f: impl FnMut() -> Result<()>) -> Result<Vec<f64>> {
    for _ in 0..3 {
        f()?;
    }
    let (start, mut times) = (Instant::now(), Vec::new());
    while times.len() < min || start.elapsed() < budget {
        let t = Instant::now();
        f()?;
        times.push(t.elapsed().as_secs_f64());
    }
    Ok(times)
}

/// (median, p99) in microseconds (zeros for no samples).
fn quantiles(mut times: Vec<f64>) -> (f64, f64) {
    if times.is_empty() {
        return (0.0, 0.0);
    }
    times.sort_by(f64::total_cmp);
    let at = |q: f64| times[((times.len() - 1) as f64 * q).round() as usize] * 1e6;
    (at(0.5), at(0.99))
}

pub fn bench(path: &str, threads: usize, seconds: f64) -> Result<serde_json::Value> {
    let started = Instant::now();
    let c = Classifier::load(path)?.with_threads(threads);
    let load_ms = started.elapsed().as_secs_f64() * 1e3;
    let bytes = std::fs::read(path).map_err(|source| pvt3_runtime::Error::Io { path: path.into(), source })?;
    let started = Instant::now();
    pvt3_format::verify(&bytes).map_err(|reason| pvt3_runtime::Error::Corrupted { path: path.into(), reason })?;
    let digest_ms = started.elapsed().as_secs_f64() * 1e3;
    let budget = Duration::from_secs_f64(seconds);
    let len: usize = c.sample_shape().iter().product();
    let windows = synthetic(32 * len);
    let one = &windows[..len];
    let started = Instant::now();
    c.classify(one)?;
    let plan_ms = started.elapsed().as_secs_f64() * 1e3;
    let (b1_median, b1_p99) = quantiles(sample(budget, 20, || c.classify(one).map(drop))?);
    let other = |kernels: Kernels| -> Result<(f64, f64)> {
        let c = Classifier::load(path)?.with_threads(threads).with_kernels(kernels);
        let started = Instant::now();
        c.classify(one)?;
        let first_ms = started.elapsed().as_secs_f64() * 1e3;
        Ok((quantiles(sample(budget, 20, || c.classify(one).map(drop))?).0, first_ms))
    };
    let prepared = Classifier::load(path)?.with_threads(threads);
    let started = Instant::now();
    prepared.prepare(&[1], c.streams())?;
    let prepare_ms = started.elapsed().as_secs_f64() * 1e3;
    let started = Instant::now();
    prepared.classify(one)?;
    let prepared_first_ms = started.elapsed().as_secs_f64() * 1e3;
    let (untuned_median, _) = other(Kernels::Tract)?;
    let (measured_median, measured_first_ms) = other(Kernels::Measured)?;
    let b32 = sample(budget, 5, || c.classify_batch(&windows, 32).map(drop))?;
    let b32_windows_per_second = 32.0 * b32.len() as f64 / b32.iter().sum::<f64>();

    let frames = *c.sample_shape().last().expect("a frame axis");
    let frame_len = len / frames;
    let touch: Vec<Vec<f32>> = (0..frames).map(|t| (0..frame_len).map(|j| one[j * frames + t]).collect()).collect();
    let (continuous_answer_median, continuous_per_token_us) = continuous_costs(&c, &touch, budget)?;
    let whole = json!({
        "model": path,
        "threads": threads,
        "frames": frames,
        "kept_frames": c.kept_frames().len(),
        "load_ms": load_ms,
        "digest_check_ms": digest_ms,
        "batch1_median_us": b1_median,
        "batch1_p99_us": b1_p99,
        "batch1_untuned_median_us": untuned_median,
        "batch1_measured_median_us": measured_median,
        "batch1_first_call_ms": plan_ms,
        "batch1_measured_first_call_ms": measured_first_ms,
        "prepare_ms": prepare_ms,
        "batch1_first_call_after_prepare_ms": prepared_first_ms,
        "batch32_windows_per_second": b32_windows_per_second,
        "windows_per_run": c.windows_per_run()?,
        "continuous_answer_median_us": continuous_answer_median,
        "continuous_per_token_us": continuous_per_token_us,
    });
    if !c.streams() {
        // A spectral head exported before it streamed reads the whole window: not streamed.
        return Ok(whole);
    }
    let stream = stream_costs(&c, &touch, budget)?;
    let mut all = whole;
    all.as_object_mut().expect("an object").extend(stream.as_object().expect("an object").clone());
    Ok(all)
}

/// A continuous stream answering after every token (`Classifier::continuous`): the frames of
/// `touch` over and over, timed once a whole window is in. The median cost of an answer and the
/// cost per token, in microseconds.
fn continuous_costs(c: &Classifier, touch: &[Vec<f32>], budget: Duration) -> Result<(f64, f64)> {
    let mut continuous = c.continuous(1)?;
    for frame in touch {
        continuous.push_frame(frame)?;
    }
    let (mut answers, mut spent) = (Vec::new(), 0.0);
    let start = Instant::now();
    for frame in touch.iter().cycle() {
        if answers.len() >= 20 && start.elapsed() >= budget {
            break;
        }
        let s = Instant::now();
        let answered = continuous.push_frame(frame)?.is_some();
        let e = s.elapsed().as_secs_f64();
        spent += e;
        if answered {
            answers.push(e);
        }
    }
    let continuous_per_token_us = spent / answers.len() as f64 * 1e6;
    let (continuous_answer_median, _) = quantiles(answers);
    Ok((continuous_answer_median, continuous_per_token_us))
}

/// A streamed touch (`Classifier::session`): each kept frame's spatial encoding, each pruned
/// frame's drop, the end of the touch, and provisional answers at 10 %, 50 % and 100 % of it.
fn stream_costs(c: &Classifier, touch: &[Vec<f32>], budget: Duration) -> Result<serde_json::Value> {
    let mut session = c.session()?;
    let (mut kept, mut dropped, mut finish) = (Vec::new(), Vec::new(), Vec::new());
    let kept_frames = c.kept_frames().to_vec();
    let start = Instant::now();
    while finish.len() < 20 || start.elapsed() < budget {
        for (t, frame) in touch.iter().enumerate() {
            let s = Instant::now();
            session.push_frame(frame)?;
            let e = s.elapsed().as_secs_f64();
            // With tubelets, a kept token's last frame runs its spatial encoding; the others wait.
            if kept_frames.binary_search(&t).is_err() {
                dropped.push(e);
            } else if (t + 1) % c.tubelet() == 0 {
                kept.push(e);
            }
        }
        let s = Instant::now();
        session.finish()?;
        finish.push(s.elapsed().as_secs_f64());
    }
    // Provisional answers at 10 %, 50 % and 100 % of a touch's temporal tokens (`Session::peek`).
    let tokens = touch.len() / c.tubelet();
    let mut peek_us = serde_json::Map::new();
    for percent in [10, 50, 100] {
        let k = (percent * tokens).div_ceil(100).max(1);
        for frame in &touch[..k * c.tubelet()] {
            session.push_frame(frame)?;
        }
        if let Err(pvt3_runtime::Error::NoPrefixes) = session.peek() {
            break; // a file exported before provisional answers existed
        }
        let (median, _) = quantiles(sample(budget, 20, || session.peek().map(drop))?);
        peek_us.insert(format!("stream_peek_{percent}pct_median_us"), json!(median));
        session.reset();
    }
    let touches = finish.len() as f64;
    let per_touch = (kept.iter().sum::<f64>() + dropped.iter().sum::<f64>() + finish.iter().sum::<f64>()) / touches * 1e6;
    let (kept_median, kept_p99) = quantiles(kept);
    let (dropped_median, _) = quantiles(dropped);
    let (finish_median, finish_p99) = quantiles(finish);
    let stream = json!({
        "stream_kept_frame_median_us": kept_median,
        "stream_kept_frame_p99_us": kept_p99,
        "stream_pruned_frame_median_us": dropped_median,
        "stream_end_of_touch_median_us": finish_median,
        "stream_end_of_touch_p99_us": finish_p99,
        "stream_compute_per_touch_us": per_touch,
        "stream_peek_us": peek_us,
    });
    Ok(stream)
}
