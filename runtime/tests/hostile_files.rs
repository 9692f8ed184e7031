//! Hostile files: a real exported model whose graph is damaged *inside* the protobuf (an
//! initializer's dimensions, data or type; an index's values; a node's attributes, inputs,
//! outputs or operator; nodes dropped or reordered; the metadata's window and kept frames) and
//! then signed again as the exporter signs, so that the integrity digest passes. Each must be a
//! typed error from `load`, `prepare` or the classification, or a classification: never a panic,
//! caught or not. Damaged `.npy` inputs likewise.
//!
//! `PVT3_FUZZ_CASES` sets the mutants per file (default: 1000 on x86-64, 40 under an emulator);
//! `bench/fuzz.sh` runs the same generator for 100,000 and reports what happened.

mod support;

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use prost::Message;
use pvt3_format::onnx::{ModelProto, Op};
use pvt3_runtime::{Classifier, Error};
use support::{golden, golden_vectors, root, Draw};

/// What a damaged count or index looks like.
trait Near {
    fn near(&mut self, v: i64) -> i64;
}

impl Near for Draw {
    /// A value near `v`, or a wild one.
    fn near(&mut self, v: i64) -> i64 {
        match self.below(8) {
            0 => 0,
            1 => -1,
            2 => v + 1,
            3 => v - 1,
            4 => v * 2,
            5 => -v - 1,
            6 => i64::MAX - self.below(3) as i64,
            _ => self.below(1 << 20) as i64 - (1 << 19),
        }
    }
}

/// One damage inside the model, named for the report.
fn damage(m: &mut ModelProto, d: &mut Draw) -> &'static str {
    let g = m.graph.as_mut().expect("a graph");
    match d.below(12) {
        0 if !g.initializer.is_empty() => {
            let i = d.below(g.initializer.len());
            let t = &mut g.initializer[i];
            if t.dims.is_empty() {
                t.dims.push(d.near(1));
            } else {
                let k = d.below(t.dims.len());
                t.dims[k] = d.near(t.dims[k]);
            }
            "an initializer's dimension"
        }
        1 if !g.initializer.is_empty() => {
            // The values of an integer initializer: indices, shapes, axes.
            let ints: Vec<usize> = (0..g.initializer.len()).filter(|&i| g.initializer[i].data_type == 7).collect();
            let Some(&i) = ints.get(d.below(ints.len())) else { return "nothing (no int64 initializer)" };
            let t = &mut g.initializer[i];
            let n = t.raw_data.len() / 8;
            if n > 0 {
                let k = d.below(n);
                let v = i64::from_le_bytes(t.raw_data[k * 8..k * 8 + 8].try_into().unwrap());
                t.raw_data[k * 8..k * 8 + 8].copy_from_slice(&d.near(v).to_le_bytes());
            }
            "an int64 initializer's value"
        }
        2 if !g.initializer.is_empty() => {
            let i = d.below(g.initializer.len());
            let t = &mut g.initializer[i];
            let keep = d.below(t.raw_data.len() + 1);
            t.raw_data.truncate(keep);
            "an initializer's data cut short"
        }
        3 if !g.initializer.is_empty() => {
            let i = d.below(g.initializer.len());
            let t = &mut g.initializer[i];
            t.data_type = [1, 7, 6, 11, 0, 99][d.below(6)];
            "an initializer's element type"
        }
        4 => {
            let i = d.below(g.node.len());
            let n = &mut g.node[i];
            if n.attribute.is_empty() {
                return "nothing (a node without attributes)";
            }
            let k = d.below(n.attribute.len());
            let a = &mut n.attribute[k];
            if !a.ints.is_empty() {
                let k = d.below(a.ints.len());
                a.ints[k] = d.near(a.ints[k]);
            } else {
                a.i = d.near(a.i);
                a.f = [0.0, -1.0, f32::NAN, f32::INFINITY, 1e30][d.below(5)];
            }
            "a node's attribute"
        }
        5 => {
            let i = d.below(g.node.len());
            let n = &mut g.node[i];
            if n.input.len() > 1 {
                let (i, j) = (d.below(n.input.len()), d.below(n.input.len()));
                n.input.swap(i, j);
            }
            "a node's inputs swapped"
        }
        6 => {
            // An input renamed to another tensor of the graph (an output or an initializer).
            let names: Vec<String> =
                g.node.iter().flat_map(|n| n.output.clone()).chain(g.initializer.iter().map(|t| t.name.clone())).collect();
            let name = names[d.below(names.len())].clone();
            let i = d.below(g.node.len());
            let n = &mut g.node[i];
            if !n.input.is_empty() {
                let k = d.below(n.input.len());
                n.input[k] = name;
            }
            "a node reading another tensor"
        }
        7 => {
            let i = d.below(g.node.len());
            let n = &mut g.node[i];
            if !n.input.is_empty() {
                n.input.remove(d.below(n.input.len()));
            }
            "a node's input dropped"
        }
        8 => {
            let i = d.below(g.node.len());
            let n = &mut g.node[i];
            n.op_type = Op::ALL[d.below(Op::ALL.len())].name().to_string();
            "a node's operator"
        }
        9 => {
            let i = d.below(g.node.len());
            if d.below(2) == 0 {
                g.node.remove(i);
            } else {
                let j = d.below(g.node.len());
                g.node.swap(i, j);
            }
            "a node dropped or moved"
        }
        10 => {
            let i = d.below(g.node.len());
            let n = &mut g.node[i];
            if let Some(o) = n.output.first_mut() {
                o.push('x');
            }
            "a node's output renamed"
        }
        _ => {
            // The header: the window's dimensions or the kept frames.
            let keys = [pvt3_format::keys::CONFIG, pvt3_format::keys::KEPT_FRAMES];
            let key = keys[d.below(keys.len())];
            let Some(e) = m.metadata_props.iter_mut().find(|e| e.key == key) else { return "nothing (no such entry)" };
            let mut value: serde_json::Value = serde_json::from_str(&e.value).unwrap();
            match &mut value {
                serde_json::Value::Array(a) if !a.is_empty() => {
                    let k = d.below(a.len());
                    a[k] = d.near(a[k].as_i64().unwrap_or(0)).into();
                }
                serde_json::Value::Object(o) => {
                    let fields = ["height", "width", "channels", "frames", "tubelet", "dim"];
                    let f = fields[d.below(fields.len())];
                    let v = o.get(f).and_then(|v| v.as_i64()).unwrap_or(1);
                    o.insert(f.into(), d.near(v).into());
                }
                _ => {}
            }
            e.value = value.to_string();
            "the header's window or kept frames"
        }
    }
}

/// What happened to the mutants, by kind of damage: (refused, ran, panicked).
type Outcomes = BTreeMap<&'static str, [usize; 3]>;

/// Loads, prepares and classifies `bytes` (a window, and a streamed touch where the file
/// streams); `Ok(true)` if it classified, `Ok(false)` if refused, `Err` with the message of a
/// panic the runtime caught.
fn try_file(bytes: &[u8], window: &[f32]) -> Result<bool, String> {
    let run = || -> pvt3_runtime::Result<()> {
        let c = Classifier::from_bytes(bytes, "hostile.onnx")?;
        c.prepare(&[1], c.streams())?;
        let sample: usize = c.sample_shape().iter().product();
        let input: Vec<f32> = (0..sample).map(|i| window[i % window.len()]).collect();
        c.classify(&input)?;
        if c.streams() {
            let frames = *c.sample_shape().last().unwrap();
            let mut s = c.session()?;
            for t in 0..frames {
                s.push_frame(&(0..sample / frames).map(|j| input[j * frames + t]).collect::<Vec<_>>())?;
                // A provisional answer after each token: refused or given, as long as nothing panics.
                if (t + 1) % c.tubelet() == 0 {
                    if let Err(Error::Tract(m)) = s.peek() {
                        return Err(Error::Tract(m));
                    }
                }
            }
            s.finish()?;
        }
        Ok(())
    };
    match run() {
        Ok(()) => Ok(true),
        Err(Error::Tract(m)) if m.starts_with("panicked") => Err(m),
        Err(_) => Ok(false),
    }
}

/// `cases` re-signed mutants of the model in `path`, 1–3 damages each, on two threads.
pub fn fuzz(path: &std::path::Path, cases: usize, seed: u64, window: &[f32]) -> (Outcomes, Vec<String>) {
    let good = ModelProto::decode(std::fs::read(path).unwrap().as_slice()).unwrap();
    let outcomes = std::sync::Mutex::new(Outcomes::new());
    let panics = std::sync::Mutex::new(Vec::new());
    let next = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let case = next.fetch_add(1, Ordering::SeqCst);
                if case >= cases {
                    break;
                }
                // PVT3_FUZZ_ONLY=N replays case N alone (its damage is drawn from the case number).
                if std::env::var("PVT3_FUZZ_ONLY").is_ok_and(|only| only != case.to_string()) {
                    continue;
                }
                let mut d = Draw(seed ^ (case as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
                let mut m = good.clone();
                let kinds: Vec<&str> = (0..1 + d.below(3)).map(|_| damage(&mut m, &mut d)).collect();
                m.sign();
                let bytes = m.encode_to_vec();
                let outcome = std::panic::catch_unwind(|| try_file(&bytes, window)).unwrap_or_else(|p| {
                    Err(p.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| p.downcast_ref::<String>().cloned()).unwrap_or_default())
                });
                let slot = match &outcome {
                    Ok(false) => 0,
                    Ok(true) => 1,
                    Err(_) => 2,
                };
                if let Err(message) = outcome {
                    panics.lock().unwrap().push(format!("case {case} ({}): {message}", kinds.join(", ")));
                }
                outcomes.lock().unwrap().entry(kinds[0]).or_default()[slot] += 1;
            });
        }
    });
    (outcomes.into_inner().unwrap(), panics.into_inner().unwrap())
}

fn cases() -> usize {
    let default = if cfg!(target_arch = "x86_64") { 1000 } else { 40 };
    std::env::var("PVT3_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// Every panic anywhere in the process, caught or not, counted.
static PANICS: AtomicUsize = AtomicUsize::new(0);

fn count_panics() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        PANICS.fetch_add(1, Ordering::SeqCst);
        previous(info);
    }));
}

#[test]
fn re_signed_damaged_models_are_refused_or_run_and_never_panic() {
    count_panics();
    let (x, _) = golden_vectors();
    let files = [golden("model.onnx"), root().join("../tests/fixtures/biotac20-spectral.onnx")];
    let mut report = String::new();
    for (k, path) in files.iter().enumerate() {
        let (outcomes, panicked) = fuzz(path, cases(), 0x5eed + k as u64, &x[..4500]);
        let total: [usize; 3] = outcomes.values().fold([0; 3], |a, o| [a[0] + o[0], a[1] + o[1], a[2] + o[2]]);
        report += &format!("{}: {} refused, {} ran, {} panicked\n", path.display(), total[0], total[1], total[2]);
        for (kind, [refused, ran, panics]) in &outcomes {
            report += &format!("  {kind}: {refused} refused, {ran} ran, {panics} panicked\n");
        }
        assert!(panicked.is_empty(), "{report}{}", panicked.join("\n"));
        // Both outcomes: every build runs both intact files (the small one, tested on aarch64,
        // the spectral head with its own FFT).
        assert_eq!(try_file(&std::fs::read(path).unwrap(), &x[..4500]), Ok(true), "{} runs intact", path.display());
        assert!(total[0] > cases() / 2 && total[1] > 0, "the damage reaches both outcomes: {report}");
    }
    println!("{report}");
    assert_eq!(PANICS.load(Ordering::SeqCst), 0, "no panic, not even a caught one\n{report}");
}

#[test]
fn damaged_npy_inputs_are_refused_and_never_panic() {
    let good = std::fs::read(golden("input.npy")).unwrap();
    let dir = support::scratch("npy");
    let mut d = Draw(0x1234_5678);
    let mut outcomes = [0usize; 2];
    for case in 0..cases() {
        let mut m = good.clone();
        match case % 3 {
            0 => m.truncate(d.below(good.len())),
            1 => (0..1 + d.below(8)).for_each(|_| {
                let at = d.below(256.min(m.len()));
                m[at] = d.below(256) as u8;
            }),
            _ => (0..1 + d.below(4)).for_each(|_| {
                let at = d.below(m.len());
                m[at] ^= 1 << d.below(8);
            }),
        }
        let path = dir.join(format!("{case}.npy"));
        std::fs::write(&path, &m).unwrap();
        let outcome = std::panic::catch_unwind(|| pvt3_runtime::read_npy(&path));
        std::fs::remove_file(&path).unwrap();
        match outcome {
            Ok(r) => outcomes[usize::from(r.is_ok())] += 1,
            Err(_) => panic!("case {case}: read_npy panicked"),
        }
    }
    assert!(outcomes[0] > 0 && outcomes[1] > 0, "{outcomes:?}");
    std::fs::remove_dir_all(dir).unwrap();
}
