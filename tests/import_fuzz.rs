//! `pvt3 import` against hostile recordings: small trees of a user's touches (CSV class folders, a
//! flat CSV folder named by pattern, PNG frame folders, PNG and JPEG still images, videos, ROS 2
//! bags in MCAP and SQLite of a camera's images and in MCAP of a taxel array's values, written here with the crates that read them: tests/bags.rs holds the
//! reading to bags written by libraries no one here wrote), each
//! mutant damaged one way (a file truncated, its bytes flipped or replaced, a cell out of range or
//! not a number, a ragged row, a name with a line break or bytes that are not UTF-8, classes left
//! too small, stray files) or given hostile options, and the release command run on it with a
//! time limit. Every outcome is counted: imported and sane (the set reloads, its values finite,
//! its labels, names and sources agreeing in count), refused naming a file or an option, refused
//! without naming either, panic, signal, timeout, garbage. The test fails on any of the last
//! five. CI runs `PVT3_IMPORT_FUZZ` mutants (300 by default); `bench/import_fuzz.sh` runs many
//! more and docs/benchmarks.md gives its figures. `PVT3_IMPORT_FUZZ_BIN` runs them against
//! another build of `pvt3` (an earlier one, to see what it let through).

use std::collections::BTreeMap;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use pvt3_spec::Rng;
use pvt3_trainer::data::Dataset;

#[path = "support/csv_tree.rs"]
mod csv_tree;

/// The time one import may take: the trees are a few kilobytes, and a healthy import of them takes
/// well under a second.
const LIMIT: Duration = Duration::from_secs(30);

/// The kinds of tree a user brings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Tree {
    Csv,
    CsvFlat,
    Frames,
    Stills,
    Jpeg,
    BagMcap,
    BagSqlite,
    BagArray,
    Video,
}

const TREES: [Tree; 9] =
    [Tree::Csv, Tree::CsvFlat, Tree::Frames, Tree::Stills, Tree::Jpeg, Tree::BagMcap, Tree::BagSqlite, Tree::BagArray, Tree::Video];

/// How a mutant was damaged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Damage {
    None,
    Truncated,
    Flipped,
    Replaced,
    Emptied,
    OddCell,
    RaggedRow,
    HeaderOnly,
    LineBreakName,
    NotUtf8Name,
    NotUtf8Twin,
    OddName,
    TooFewTouches,
    StrayFiles,
    OtherSize,
    /// Every CSV header's first channel named with thousands of characters, chosen by a pattern
    /// that makes backtracking try every split.
    LongColumn,
    Options,
}

const DAMAGES: [Damage; 17] = [
    Damage::None,
    Damage::Truncated,
    Damage::Flipped,
    Damage::Replaced,
    Damage::Emptied,
    Damage::OddCell,
    Damage::RaggedRow,
    Damage::HeaderOnly,
    Damage::LineBreakName,
    Damage::NotUtf8Name,
    Damage::NotUtf8Twin,
    Damage::OddName,
    Damage::TooFewTouches,
    Damage::StrayFiles,
    Damage::OtherSize,
    Damage::LongColumn,
    Damage::Options,
];

/// What became of a mutant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    Imported,
    Refused,
    RefusedUnnamed,
    Panic,
    Signal,
    Timeout,
    Garbage,
}

const CELLS: [&str; 16] = [
    "1e39",
    "-1e39",
    "1e308",
    "inf",
    "-inf",
    "nan",
    "NaN",
    "",
    "abc",
    "0x10",
    "1,5",
    "\"",
    "1e-400",
    "99999999999999999999999",
    " 7 ",
    "１２",
];

const OPTIONS: [&[&str]; 24] = [
    &["--columns", "*a*a*a*a*a*a*b"],
    &["--columns", ""],
    &["--columns", "???"],
    &["--columns", "e1,e1,nothing"],
    &["--grid", "0x0"],
    &["--grid", "1x99"],
    &["--grid", "2x2"],
    &["--per-distance", "speed=1e300"],
    &["--per-distance", "speed=1e-300"],
    &["--per-distance", "speed=nan"],
    &["--per-force", "force=1e-300"],
    &["--name", "{a}{b}"],
    &["--name", "{class}_*"],
    &["--name", "*_{class}_*_{x}_*"],
    &["--frames", "0"],
    &["--frames", "1000000000"],
    &["--frames", "3", "--allow-short"],
    &["--size", "0x0"],
    &["--size", "99999x1"],
    &["--size", "3x3", "--grey"],
    &["--crop", "9999x1+0+0"],
    &["--crop", "2x2+99999+0"],
    &["--labels", "missing.csv"],
    &["--frames-from", "whole", "--subtract-first"],
];

#[test]
fn hostile_recordings_are_imported_sanely_or_refused_by_name() {
    let mutants: usize = std::env::var("PVT3_IMPORT_FUZZ").ok().and_then(|v| v.parse().ok()).unwrap_or(300);
    let root = std::env::temp_dir().join(format!("pvt3-import-fuzz-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let bases: BTreeMap<Tree, PathBuf> = TREES.iter().map(|t| (*t, base(&root, *t))).collect();
    let mut rng = Rng::new(2026);
    let mut counts: BTreeMap<(Tree, Damage, Outcome), usize> = BTreeMap::new();
    let mut failures = Vec::new();
    let started = Instant::now();
    for m in 0..mutants {
        // Videos are slow to decode: one mutant in twelve.
        let tree = if rng.below(12) == 0 { Tree::Video } else { TREES[rng.below(TREES.len() - 1)] };
        let damage = DAMAGES[rng.below(DAMAGES.len())];
        let dir = root.join(format!("m{m}"));
        copy(&bases[&tree], &dir);
        let mut args: Vec<String> = Vec::new();
        match tree {
            Tree::CsvFlat => args.extend(["--name".into(), "{class}_F{force}_V{speed}mmps_*".into()]),
            // Their touches hold 4 frames: undamaged, they import.
            Tree::Frames | Tree::Video => args.extend(["--frames".into(), "4".into()]),
            Tree::BagMcap | Tree::BagSqlite => args.extend(["--frames", "4", "--topic", "/camera"].map(String::from)),
            Tree::BagArray => args.extend(["--topic", "/taxels"].map(String::from)),
            _ => {}
        }
        damage_tree(&dir, tree, damage, &mut rng, &mut args);
        let (outcome, said) = run(&dir, &args);
        *counts.entry((tree, damage, outcome)).or_default() += 1;
        if outcome >= Outcome::RefusedUnnamed {
            failures.push(format!("mutant {m} ({tree:?}, {damage:?}, {args:?}): {outcome:?}\n{said}"));
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    let _ = std::fs::remove_dir_all(&root);
    report(&counts, mutants, started.elapsed());
    assert!(failures.is_empty(), "{} of {mutants} mutants failed:\n{}", failures.len(), failures.join("\n\n"));
}

/// A tree of `kind` under `root`: two or three classes of five touches.
fn base(root: &Path, kind: Tree) -> PathBuf {
    let dir = root.join(format!("{kind:?}"));
    match kind {
        Tree::Csv => csv_tree::write(&dir, 2, 5, 8, 12),
        Tree::CsvFlat => {
            let nested = root.join("csv-for-flat");
            csv_tree::write(&nested, 3, 6, 8, 12);
            csv_tree::flatten(&nested, &dir, 3, 6);
        }
        Tree::BagArray => {
            for class in 0..2 {
                let class_dir = dir.join(format!("class_{class}"));
                std::fs::create_dir_all(&class_dir).unwrap();
                for touch in 0..5 {
                    bag::write_taxels(&class_dir.join(format!("touch_{touch}.mcap")), class, touch);
                }
            }
        }
        Tree::Frames | Tree::Stills | Tree::Jpeg | Tree::BagMcap | Tree::BagSqlite | Tree::Video => {
            for class in 0..2 {
                let class_dir = dir.join(format!("class_{class}"));
                std::fs::create_dir_all(&class_dir).unwrap();
                for touch in 0..5 {
                    let frames: Vec<Vec<u8>> = (0..4).map(|f| picture(class, touch, f)).collect();
                    match kind {
                        Tree::Frames => {
                            let folder = class_dir.join(format!("touch_{touch}"));
                            std::fs::create_dir_all(&folder).unwrap();
                            frames.iter().enumerate().for_each(|(f, p)| write_png(&folder.join(format!("{f}.png")), p, W, H));
                        }
                        Tree::Stills => write_png(&class_dir.join(format!("touch_{touch}.png")), &frames[0], W, H),
                        Tree::Jpeg => write_jpeg(&class_dir.join(format!("touch_{touch}.jpg")), &frames[0]),
                        Tree::BagMcap => bag::write_mcap(&class_dir.join(format!("touch_{touch}.mcap")), &frames),
                        Tree::BagSqlite => bag::write_sqlite(&class_dir.join(format!("touch_{touch}")), &frames),
                        _ => write_video(&class_dir.join(format!("touch_{touch}.mkv")), &frames),
                    }
                }
            }
        }
    }
    dir
}

const H: usize = 8;
const W: usize = 10;

/// An RGB frame, H × W: its class's level and a square that moves with the frame.
fn picture(class: usize, touch: usize, f: usize) -> Vec<u8> {
    (0..H * W * 3).map(|i| ((i / 3 % W == f + touch) as usize * 150 + 40 * class + i % 3 * 7) as u8).collect()
}

/// Bags of `sensor_msgs/msg/Image` (rgb8) on `/camera`, one message a frame, stamped 40 ms apart;
/// and of a 2 × 3 taxel array's `std_msgs/msg/Int16MultiArray` on `/taxels`, 6 to 9 frames.
mod bag {
    use std::path::Path;

    use super::{H, W};

    /// The CDR of frame `f`, `data` its RGB bytes.
    fn image(f: usize, data: &[u8]) -> Vec<u8> {
        let mut m = vec![0, 1, 0, 0];
        let mut u32 = |m: &mut Vec<u8>, v: u32| {
            m.resize(4 + (m.len() - 4).next_multiple_of(4), 0);
            m.extend_from_slice(&v.to_le_bytes());
        };
        let text = |m: &mut Vec<u8>, u32: &mut dyn FnMut(&mut Vec<u8>, u32), s: &str| {
            u32(m, s.len() as u32 + 1);
            m.extend_from_slice(s.as_bytes());
            m.push(0);
        };
        u32(&mut m, 1);
        u32(&mut m, (f * 40_000_000) as u32);
        text(&mut m, &mut u32, "camera");
        u32(&mut m, H as u32);
        u32(&mut m, W as u32);
        text(&mut m, &mut u32, "rgb8");
        m.push(0);
        u32(&mut m, (W * 3) as u32);
        u32(&mut m, data.len() as u32);
        m.extend_from_slice(data);
        m
    }

    const TYPE: &str = "sensor_msgs/msg/Image";

    pub fn write_mcap(path: &Path, frames: &[Vec<u8>]) {
        let messages: Vec<Vec<u8>> = frames.iter().enumerate().map(|(f, frame)| image(f, frame)).collect();
        write_messages(path, TYPE, "/camera", &messages);
    }

    /// The CDR of a 2 × 3 Int16MultiArray holding `values`.
    fn taxel_frame(values: &[i16]) -> Vec<u8> {
        let mut m = vec![0, 1, 0, 0, 2, 0, 0, 0];
        for (label, size, stride) in [("rows", 2u32, 6u32), ("cols", 3, 3)] {
            m.extend_from_slice(&(label.len() as u32 + 1).to_le_bytes());
            m.extend_from_slice(label.as_bytes());
            m.push(0);
            m.resize(4 + (m.len() - 4).next_multiple_of(4), 0);
            m.extend_from_slice(&size.to_le_bytes());
            m.extend_from_slice(&stride.to_le_bytes());
        }
        m.extend_from_slice(&0u32.to_le_bytes());
        m.extend_from_slice(&(values.len() as u32).to_le_bytes());
        values.iter().for_each(|v| m.extend_from_slice(&v.to_le_bytes()));
        m
    }

    pub fn write_taxels(path: &Path, class: usize, touch: usize) {
        let frames =
            (0..6 + touch % 4).map(|f| taxel_frame(&(0..6).map(|k| (k * 7 + f * 3 + class * 40 + touch) as i16 - 20).collect::<Vec<_>>()));
        write_messages(path, "std_msgs/msg/Int16MultiArray", "/taxels", &frames.collect::<Vec<_>>());
    }

    /// An MCAP file of `messages` of type `type_name` on `topic`, received 40 ms apart.
    fn write_messages(path: &Path, type_name: &str, topic: &str, messages: &[Vec<u8>]) {
        let mut writer = mcap::Writer::new(std::io::BufWriter::new(std::fs::File::create(path).unwrap())).unwrap();
        let schema = writer.add_schema(type_name, "ros2msg", b"").unwrap();
        let channel = writer.add_channel(schema, topic, "cdr", &Default::default()).unwrap();
        for (f, message) in messages.iter().enumerate() {
            let time = 1_000_000_000 + f as u64 * 40_000_000;
            let header = mcap::records::MessageHeader { channel_id: channel, sequence: f as u32, log_time: time, publish_time: time };
            writer.write_to_known_channel(&header, message).unwrap();
        }
        writer.finish().unwrap();
    }

    /// A bag directory as rosbag2 writes it before Jazzy: metadata.yaml beside its `.db3`.
    pub fn write_sqlite(dir: &Path, frames: &[Vec<u8>]) {
        std::fs::create_dir_all(dir).unwrap();
        let metadata = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  relative_file_paths:\n    - bag_0.db3\n  compression_format: ''\n  compression_mode: ''\n";
        std::fs::write(dir.join("metadata.yaml"), metadata).unwrap();
        let db = rusqlite::Connection::open(dir.join("bag_0.db3")).unwrap();
        db.execute_batch(
            "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
             CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);",
        )
        .unwrap();
        db.execute("INSERT INTO topics VALUES (1, '/camera', ?1, 'cdr', '')", [TYPE]).unwrap();
        for (f, frame) in frames.iter().enumerate() {
            let time = 1_000_000_000 + f as i64 * 40_000_000;
            db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (1, ?1, ?2)", rusqlite::params![time, image(f, frame)])
                .unwrap();
        }
    }
}

fn write_png(path: &Path, data: &[u8], width: usize, height: usize) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut png = png::Encoder::new(file, width as u32, height as u32);
    png.set_color(png::ColorType::Rgb);
    png.write_header().unwrap().write_image_data(data).unwrap();
}

/// A JPEG through FFmpeg (the project reads JPEG, and writes none).
fn write_jpeg(path: &Path, data: &[u8]) {
    ffmpeg(&[data.to_vec()], &["-frames:v", "1", "-q:v", "3"], path);
}

fn write_video(path: &Path, frames: &[Vec<u8>]) {
    ffmpeg(frames, &["-c:v", "ffv1", "-pix_fmt", "bgr0"], path);
}

fn ffmpeg(frames: &[Vec<u8>], codec: &[&str], path: &Path) {
    use std::io::Write;
    let size = format!("{W}x{H}");
    let mut child = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", &size, "-r", "25", "-i", "pipe:0"])
        .args(codec)
        .arg(path)
        .stdin(Stdio::piped())
        .spawn()
        .expect("ffmpeg runs (apt-get install ffmpeg)");
    let mut stdin = child.stdin.take().unwrap();
    frames.iter().for_each(|f| stdin.write_all(f).unwrap());
    drop(stdin);
    assert!(child.wait().unwrap().success(), "ffmpeg wrote {}", path.display());
}

fn copy(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy(&path, &target);
        } else {
            std::fs::copy(&path, &target).unwrap();
        }
    }
}

/// Every file under `dir`, sorted.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            found.extend(files(&path));
        } else {
            found.push(path);
        }
    }
    found.sort();
    found
}

/// Every folder under `dir` (not `dir`), sorted.
fn folders(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            found.push(path.clone());
            found.extend(folders(&path));
        }
    }
    found.sort();
    found
}

/// `dir` (a copy of a base tree of `tree`) damaged as `damage` says; options go into `args`.
fn damage_tree(dir: &Path, tree: Tree, damage: Damage, rng: &mut Rng, args: &mut Vec<String>) {
    let all = files(dir);
    let file = all[rng.below(all.len())].clone();
    let bytes = std::fs::read(&file).unwrap();
    let csv = matches!(tree, Tree::Csv | Tree::CsvFlat);
    match damage {
        Damage::None => {}
        Damage::Truncated => std::fs::write(&file, &bytes[..rng.below(bytes.len().max(1))]).unwrap(),
        Damage::Flipped => {
            let mut bytes = bytes;
            for _ in 0..1 + rng.below(8) {
                let at = rng.below(bytes.len().max(1)).min(bytes.len().saturating_sub(1));
                if let Some(b) = bytes.get_mut(at) {
                    *b ^= 1 << rng.below(8);
                }
            }
            std::fs::write(&file, bytes).unwrap();
        }
        Damage::Replaced => std::fs::write(&file, (0..rng.below(4096)).map(|_| rng.below(256) as u8).collect::<Vec<_>>()).unwrap(),
        Damage::Emptied => std::fs::write(&file, b"").unwrap(),
        Damage::OddCell | Damage::RaggedRow | Damage::HeaderOnly if csv => {
            let text = String::from_utf8(bytes).unwrap();
            let mut lines: Vec<String> = text.lines().map(String::from).collect();
            let row = 1 + rng.below(lines.len() - 1);
            match damage {
                Damage::OddCell => {
                    let mut cells: Vec<String> = lines[row].split(',').map(String::from).collect();
                    let at = rng.below(cells.len());
                    cells[at] = CELLS[rng.below(CELLS.len())].into();
                    lines[row] = cells.join(",");
                }
                Damage::RaggedRow => lines[row].push_str(",1"),
                _ => lines.truncate(1),
            }
            std::fs::write(&file, lines.join("\n") + "\n").unwrap();
        }
        Damage::OddCell | Damage::RaggedRow | Damage::HeaderOnly => std::fs::write(&file, &bytes[..bytes.len() / 2]).unwrap(),
        Damage::LineBreakName | Damage::NotUtf8Name | Damage::OddName => {
            let victims: Vec<PathBuf> = folders(dir).into_iter().chain(all).collect();
            let victim = &victims[rng.below(victims.len())];
            let mut name = victim.file_name().unwrap().as_bytes().to_vec();
            let inserted: Vec<u8> = match damage {
                Damage::LineBreakName => b"\nX".to_vec(),
                Damage::NotUtf8Name => vec![0xff, 0xfe],
                _ => ["  é ".to_string(), "..".into(), "#".into(), "x".repeat(200)][rng.below(4)].clone().into_bytes(),
            };
            name.splice(1..1, inserted);
            std::fs::rename(victim, victim.with_file_name(std::ffi::OsStr::from_bytes(&name))).unwrap();
        }
        Damage::NotUtf8Twin => {
            // A second class folder whose name differs from another's only in bytes that are not
            // UTF-8: a lossy reading would merge the two.
            // In a flat folder, a touch file's twin.
            let first = folders(dir).into_iter().next().unwrap_or(file);
            let mut twin = first.file_name().unwrap().as_bytes().to_vec();
            twin.insert(1, 0xff);
            let twin = first.with_file_name(std::ffi::OsStr::from_bytes(&twin));
            if first.is_dir() {
                copy(&first, &twin);
            } else {
                std::fs::copy(&first, &twin).unwrap();
            }
        }
        Damage::TooFewTouches => {
            let victims: Vec<PathBuf> = std::fs::read_dir(file.parent().unwrap()).unwrap().map(|e| e.unwrap().path()).collect();
            for victim in victims.iter().take(1 + rng.below(victims.len())) {
                let _ = std::fs::remove_file(victim).or_else(|_| std::fs::remove_dir_all(victim));
            }
        }
        Damage::StrayFiles => {
            std::fs::write(dir.join("README.txt"), "notes").unwrap();
            std::fs::create_dir_all(dir.join("empty_class")).unwrap();
            std::fs::write(file.with_file_name("notes.md"), "x").unwrap();
        }
        Damage::OtherSize if !csv => write_png(&file.with_extension("png"), &[9; 3 * 5 * 7], 7, 5),
        Damage::OtherSize => std::fs::write(&file, "time,e1\n1,2\n2,3\n").unwrap(),
        Damage::LongColumn if csv => {
            let long = "a".repeat(4_000) + "e1";
            for f in files(dir) {
                let text = std::fs::read_to_string(&f).unwrap();
                std::fs::write(&f, text.replacen("e1", &long, 1)).unwrap();
            }
            args.extend(["--columns".into(), "*a*a*a*a*a*a*a*b,e2".into()]);
        }
        Damage::LongColumn => args.extend(["--columns".into(), "*a*a*a*a*a*a*a*b".into()]),
        Damage::Options => {
            let chosen = OPTIONS[rng.below(OPTIONS.len())];
            args.extend(chosen.iter().map(|a| a.to_string()));
        }
    }
}

/// Runs `pvt3 import dir args` (its output beside `dir`) with the time limit: what became of it,
/// and what it said.
fn run(dir: &Path, args: &[String]) -> (Outcome, String) {
    let out = dir.with_extension("npz");
    let pvt3 = std::env::var_os("PVT3_IMPORT_FUZZ_BIN").map_or_else(|| env!("CARGO_BIN_EXE_pvt3").into(), PathBuf::from);
    let mut child = Command::new(pvt3)
        .arg("import")
        .arg(dir)
        .args(args)
        .arg("--out")
        .arg(&out)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("pvt3 runs");
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            return (Outcome::Timeout, format!("still running after {LIMIT:?}"));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let output = child.wait_with_output().unwrap();
    let said = String::from_utf8_lossy(&output.stderr).to_string() + &String::from_utf8_lossy(&output.stdout);
    let outcome = if let Some(signal) = status.signal() {
        return (Outcome::Signal, format!("signal {signal}\n{said}"));
    } else if said.contains("panicked") {
        Outcome::Panic
    } else if status.success() {
        match sane(&out, dir) {
            Ok(()) => Outcome::Imported,
            Err(why) => return (Outcome::Garbage, format!("{why}\n{said}")),
        }
    } else if said.contains(&*dir.to_string_lossy()) || said.contains("--") || said.contains(".csv") {
        Outcome::Refused
    } else {
        Outcome::RefusedUnnamed
    };
    let _ = std::fs::remove_file(out);
    (outcome, said)
}

/// Whether the set written to `out` reloads with finite values, its labels, class names, sources
/// and conditions agreeing in count, and every source a file of `dir` (a name read lossily is
/// no file's).
fn sane(out: &Path, dir: &Path) -> Result<(), String> {
    let data = Dataset::load(out, 0).map_err(|e| format!("the set does not reload: {e}"))?;
    let n = data.len();
    let classes = data.labels.iter().max().map_or(0, |m| *m as usize + 1);
    let names = data.class_names.as_ref().map_or(0, Vec::len);
    let sources = data.sources.as_ref().map_or(0, Vec::len);
    if names != classes || sources != n || data.labels.len() != n || data.conditions.iter().any(|c| c.levels.len() != n) {
        return Err(format!("counts disagree: {n} touches, {classes} classes, {names} class names, {sources} sources"));
    }
    if let Some(lost) = data.sources.iter().flatten().find(|s| !dir.join(s).exists()) {
        return Err(format!("the source {lost:?} is no file of the tree"));
    }
    if (0..n).any(|i| data.sample(i).iter().any(|v| !v.is_finite())) {
        return Err("a value is not finite".into());
    }
    Ok(())
}

/// The outcomes by tree and damage, and in all.
fn report(counts: &BTreeMap<(Tree, Damage, Outcome), usize>, mutants: usize, took: Duration) {
    let mut total: BTreeMap<Outcome, usize> = BTreeMap::new();
    for ((_, _, outcome), n) in counts {
        *total.entry(*outcome).or_default() += n;
    }
    println!("{mutants} mutants in {:.0} s: {total:?}", took.as_secs_f64());
    for ((tree, damage, outcome), n) in counts {
        println!("  {tree:?} {damage:?} {outcome:?}: {n}");
    }
}
