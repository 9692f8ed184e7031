//! Hostile files: a real exported model whose graph is damaged *inside* the protobuf (an
//! initializer's dimensions, data or type; an index's values; a node's attributes, inputs,
//! outputs or operator; nodes dropped or reordered; the metadata's window and kept frames) and
//! then signed again as the exporter signs, so that the integrity digest passes. Each must be a
//! typed error from `load`, `prepare` or the classification that names the part of the file at
//! fault (an initializer, a node or its tensor, the graph's input or a header entry), or a
//! classification: never a panic, caught or not. Damaged `.npy` inputs likewise.
//!
//! Every kind of file pvt3 writes is damaged ([`subjects`]), and a camera's 8-bit frames of the
//! wrong length. `PVT3_FUZZ_CASES` sets the mutants per file (default: 400 on x86-64, 40 under
//! an emulator); `bench/fuzz.sh` runs the same generator for 100,000 a file and reports what
//! happened.

mod support;

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use prost::Message;
use pvt3_format::onnx::{ModelProto, Op};
use pvt3_runtime::{Classifier, Error};
use support::{golden, root, Draw};

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
    match d.below(15) {
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
        11 if !g.initializer.is_empty() => {
            // Emptied, its other dimensions kept or made wild: it then holds what it says (none).
            let i = d.below(g.initializer.len());
            let t = &mut g.initializer[i];
            t.raw_data.clear();
            t.float_data.clear();
            t.int64_data.clear();
            let k = d.below(t.dims.len() + 1);
            t.dims.insert(k, 0);
            if let Some(k) = (t.dims.len() > 1).then(|| d.below(t.dims.len())).filter(|k| t.dims[*k] != 0) {
                t.dims[k] = d.near(t.dims[k]).max(0);
            }
            "an initializer emptied"
        }
        12 if !g.initializer.is_empty() => {
            // Another shape or element type that its data still fills: read as another tensor.
            let i = d.below(g.initializer.len());
            let t = &mut g.initializer[i];
            let bytes = t.raw_data.len() as i64;
            match d.below(3) {
                0 => t.dims.reverse(),
                1 => t.dims = vec![bytes / if t.data_type == 7 { 8 } else { 4 }],
                _ => {
                    t.data_type = if t.data_type == 7 { 1 } else { 7 };
                    t.dims = vec![bytes / if t.data_type == 7 { 8 } else { 4 }];
                }
            }
            "an initializer's shape or type, its data still filling it"
        }
        13 => {
            // The graph's declared input: an axis, its element type or its name.
            let Some(input) = g.input.first_mut() else { return "nothing (no graph input)" };
            let tensor = input.r#type.get_or_insert_with(Default::default).tensor_type.get_or_insert_with(Default::default);
            let dims = &mut tensor.shape.get_or_insert_with(Default::default).dim;
            match d.below(3) {
                0 if !dims.is_empty() => {
                    let k = d.below(dims.len());
                    let v = match dims[k].value {
                        Some(pvt3_format::onnx::DimensionValue::DimValue(v)) => v,
                        _ => 1,
                    };
                    dims[k].value = Some(pvt3_format::onnx::DimensionValue::DimValue(d.near(v)));
                }
                1 => tensor.elem_type = [0, 7, 10, 99][d.below(4)],
                _ => input.name.push('x'),
            }
            "the graph's input"
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

/// A file to damage and what it is given: a window of its model's frames, cycled to fill any
/// window its damaged header asks for, and for a camera's file one of the camera's frames.
pub struct Subject {
    pub path: std::path::PathBuf,
    pub window: Vec<f32>,
}

/// Every kind of file pvt3 writes, as shipped or as the tests' fixtures keep it: the golden iCub
/// model, the shipped iCub model (pruned, with a stopping rule), BioTac with its spectral head
/// (streaming), the camera (a patch embedding and a head over the image's space, read from the
/// camera's 8-bit frames) and a `--robust auto` file (its head of 16 bands); each with its own
/// touch.
pub fn subjects() -> Vec<Subject> {
    let repo = root().join("..");
    let touch = |path: &str| pvt3_runtime::read_npy(&repo.join(path)).unwrap().1;
    let files = [
        ("tests/golden/icub20/model.onnx", "tests/golden/icub20/input.npy"),
        ("shipped/icub20.onnx", "shipped/icub20-touch.npy"),
        ("shipped/biotac20.onnx", "shipped/biotac20-touch.npy"),
        ("shipped/physiclear.onnx", "shipped/physiclear-touch.npy"),
        ("tests/fixtures/fabricslide-robust-auto.onnx", "tests/fixtures/fabricslide-touch.npy"),
    ];
    files.iter().map(|(model, input)| Subject { path: repo.join(model), window: touch(input) }).collect()
}

/// Loads, prepares and classifies `bytes` (a window, and a streamed touch where the file
/// streams, of the camera's own frames where it has a camera); `Ok(Ok(()))` if it classified,
/// `Ok(Err(refusal))` if refused, `Err` with the message of a panic the runtime caught.
fn try_file(bytes: &[u8], window: &[f32]) -> Result<Result<(), String>, String> {
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
            if c.camera().is_some() {
                camera_frames(&c, &mut s, window)?;
            }
        }
        Ok(())
    };
    match run() {
        Ok(()) => Ok(Ok(())),
        Err(Error::Tract(m)) if m.starts_with("panicked") => Err(m),
        Err(refusal) => Ok(Err(refusal.to_string())),
    }
}

/// The camera's own frames, as a robot pushes them (the recorded size, 8-bit), then frames of
/// the wrong length and touches of the wrong shape, each of which must be refused (a panic,
/// which the fuzz reports, if one is taken).
fn camera_frames(c: &Classifier, s: &mut pvt3_runtime::Session, window: &[f32]) -> pvt3_runtime::Result<()> {
    let len = c.camera_frame_len();
    let frame: Vec<u8> = (0..len).map(|i| (window[i % window.len()] as u8).wrapping_add(i as u8)).collect();
    s.push_camera_frame(&frame)?;
    s.push_camera_frame(&frame)?;
    for wrong in [0, 1, len - 1, len + 1, 2 * len + 1] {
        let bytes = vec![7u8; wrong];
        assert!(matches!(s.push_camera_frame(&bytes), Err(Error::FrameLength { .. })), "a camera frame of {wrong} bytes, not {len}, taken");
        assert!(c.classify_camera_touches(&bytes, 1 + wrong % 3).is_err(), "{wrong} bytes taken as touches of frames of {len}");
    }
    Ok(())
}

/// What a fuzz found: the outcomes by kind of damage, the panics, and the refusals that name no
/// part of the file (each `case N (damages): message`).
pub struct Fuzzed {
    pub outcomes: Outcomes,
    pub panics: Vec<String>,
    pub unnamed: Vec<String>,
}

/// `cases` re-signed mutants of the model in `path`, 1–3 damages each, on two threads.
pub fn fuzz(path: &std::path::Path, cases: usize, seed: u64, window: &[f32]) -> Fuzzed {
    let good = ModelProto::decode(std::fs::read(path).unwrap().as_slice()).unwrap();
    let outcomes = std::sync::Mutex::new(Outcomes::new());
    let panics = std::sync::Mutex::new(Vec::new());
    let unnamed = std::sync::Mutex::new(Vec::new());
    let names = named_parts(&good);
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
                    Ok(Err(_)) => 0,
                    Ok(Ok(())) => 1,
                    Err(_) => 2,
                };
                if let Ok(Err(refusal)) = &outcome {
                    if !names.iter().any(|n| names_word(refusal, n)) {
                        unnamed.lock().unwrap().push(format!("case {case} ({}): {refusal}", kinds.join(", ")));
                    }
                }
                if let Err(message) = outcome {
                    panics.lock().unwrap().push(format!("case {case} ({}): {message}", kinds.join(", ")));
                }
                outcomes.lock().unwrap().entry(kinds[0]).or_default()[slot] += 1;
            });
        }
    });
    Fuzzed { outcomes: outcomes.into_inner().unwrap(), panics: panics.into_inner().unwrap(), unnamed: unnamed.into_inner().unwrap() }
}

/// What a refusal may name: the file's initializers, nodes, tensors, graph input and header entries.
fn named_parts(m: &ModelProto) -> Vec<String> {
    let g = m.graph.as_ref().expect("a graph");
    let tensors = g.node.iter().flat_map(|n| n.output.iter().chain([&n.name]));
    let inputs = g.input.iter().map(|i| &i.name);
    let names = g.initializer.iter().map(|t| &t.name).chain(tensors).chain(inputs).chain(m.metadata_props.iter().map(|e| &e.key));
    names.filter(|n| !n.is_empty()).cloned().collect()
}

/// Whether `text` holds `name` as a whole word (so `Add_1` is not found in `Add_12`).
fn names_word(text: &str, name: &str) -> bool {
    let word = |c: char| c.is_alphanumeric() || c == '_' || c == '.';
    text.match_indices(name).any(|(at, _)| !text[..at].ends_with(word) && !text[at + name.len()..].starts_with(word))
}

fn cases() -> usize {
    let default = if cfg!(target_arch = "x86_64") { 400 } else { 40 };
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
fn re_signed_damaged_models_are_refused_by_name_or_run_and_never_panic() {
    count_panics();
    let mut report = String::new();
    // PVT3_FUZZ_FILE=NAME damages only the files whose path holds NAME.
    let only = std::env::var("PVT3_FUZZ_FILE").unwrap_or_default();
    for (k, subject) in subjects().iter().enumerate().filter(|(_, s)| s.path.to_string_lossy().contains(&only)) {
        let path = &subject.path;
        let started = std::time::Instant::now();
        let Fuzzed { outcomes, panics: panicked, unnamed } = fuzz(path, cases(), 0x5eed + k as u64, &subject.window);
        let from = report.len();
        let total: [usize; 3] = outcomes.values().fold([0; 3], |a, o| [a[0] + o[0], a[1] + o[1], a[2] + o[2]]);
        report += &format!("{}: {} refused, {} ran, {} panicked\n", path.display(), total[0], total[1], total[2]);
        for (kind, [refused, ran, panics]) in &outcomes {
            report += &format!("  {kind}: {refused} refused, {ran} ran, {panics} panicked\n");
        }
        report += &format!("  refusals naming no part of the file: {}\n", unnamed.len());
        assert!(panicked.is_empty(), "{report}{}", panicked.join("\n"));
        assert!(unnamed.is_empty(), "refusals that name no part of {}:\n{report}{}", path.display(), unnamed.join("\n"));
        // Both outcomes: every build runs every intact file (the small one, tested on aarch64,
        // the spectral heads with its own FFT).
        assert_eq!(try_file(&std::fs::read(path).unwrap(), &subject.window), Ok(Ok(())), "{} runs intact", path.display());
        assert!(total[0] > cases() / 2 && total[1] > 0, "the damage reaches both outcomes: {report}");
        // Each file's outcome as soon as it is known: a long run stopped early keeps what it found.
        println!("{}  ({:.0} s)", report[from..].trim_end(), started.elapsed().as_secs_f64());
    }
    assert_eq!(PANICS.load(Ordering::SeqCst), 0, "no panic, not even a caught one\n{report}");
}

/// The damage that panicked in tract before sizes were checked (an initializer emptied, its
/// other axis wild) is refused at load, naming the initializer; so are its sizes made to
/// disagree with its data, and its data type changed.
#[test]
fn a_camera_file_with_an_initializer_s_sizes_damaged_is_refused_by_name() {
    let (bytes, name) = support::damaged_camera_file();
    let err = Classifier::from_bytes(&bytes, "camera.onnx").err().expect("refused");
    let message = err.to_string();
    assert!(matches!(err, Error::NotOnnx { .. }), "{message}");
    assert!(message.contains(&format!("initializer `{name}` is of shape [1125899906842624, 0]: more than")), "{message}");
    let good = ModelProto::decode(std::fs::read(root().join("../shipped/physiclear.onnx")).unwrap().as_slice()).unwrap();
    type Damage = fn(&mut pvt3_format::onnx::TensorProto);
    let damages: [(Damage, &str); 3] = [
        (|t| t.dims[0] *= 2, "values of 4 bytes) but"),
        (|t| t.dims[0] = -t.dims[0], "has a negative dimension"),
        (|t| t.data_type = 11, "has element type 11"),
    ];
    for (damage, why) in damages {
        let mut m = good.clone();
        let t = m.graph.as_mut().unwrap().initializer.iter_mut().find(|t| t.data_type == 1 && t.dims.len() == 2).unwrap();
        damage(t);
        let name = t.name.clone();
        m.sign();
        let message = Classifier::from_bytes(&m.encode_to_vec(), "camera.onnx").err().expect("refused").to_string();
        assert!(message.contains(&format!("initializer `{name}`")) && message.contains(why), "{message}");
    }
}

#[test]
fn damaged_npy_inputs_are_refused_and_never_panic() {
    // The golden iCub windows (float32) and the camera's touch (8-bit).
    for (k, file) in [golden("input.npy"), root().join("../shipped/physiclear-touch.npy")].iter().enumerate() {
        damaged_npy(file, 0x1234_5678 + k as u64);
    }
}

fn damaged_npy(file: &std::path::Path, seed: u64) {
    let good = std::fs::read(file).unwrap();
    let dir = support::scratch("npy");
    let mut d = Draw(seed);
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
