//! `pvt3 import` of ROS 2 bags written by libraries no one here wrote (tests/bag_writer.py:
//! rosbags' rosbag2 writer, MCAP and SQLite; mcap-ros2-support's, zstd and lz4 chunks), for every
//! message pvt3 reads: each camera set imports equal, byte for byte, to the same frames written
//! as image files and imported, and each taxel array's to the same values written as CSV files.
//! And what a user who names no topic, or the wrong one, is told.

#[path = "support/onnx_check.rs"]
#[allow(dead_code)] // the other end-to-end tests use the rest of it
mod onnx_check;
#[path = "support/pvt3_command.rs"]
#[allow(dead_code)] // the other end-to-end tests use the rest of it
mod pvt3_command;
#[path = "support/workspace.rs"]
mod workspace;

use std::path::Path;

use ndarray::ArrayD;
use onnx_check::run_script;
use pvt3_command::{fails, ok, scratch};

const WRITERS: [&str; 4] = ["rosbags-mcap", "rosbags-sqlite3", "mcap-ros2-zstd", "mcap-ros2-lz4"];
const ARRAYS: [&str; 6] = ["float32", "float64", "int16", "int32", "uint16", "uint8"];
const CASES: [&str; 9] =
    ["rgb8", "bgr8-padded", "rgba8", "bgra8", "mono8", "mono16-little", "mono16-big", "compressed-png", "compressed-jpeg"];

/// The entries of a set that hold what it read (its sources' names differ: `.mcap` or not).
fn read(set: &Path) -> Vec<(String, ArrayD<u8>)> {
    let mut npz = ndarray_npy::NpzReader::new(std::fs::File::open(set).unwrap()).unwrap();
    let mut entries: Vec<(String, ArrayD<u8>)> =
        ["x", "camera", "class_names"].iter().map(|k| (k.to_string(), npz.by_name(k).unwrap())).collect();
    let y: ArrayD<i64> = npz.by_name("y").unwrap();
    entries.push(("y".into(), y.mapv(|v| v as u8)));
    entries
}

fn import(dir: &Path, out: &Path, topic: bool) -> String {
    let (dir, out) = (dir.to_str().unwrap(), out.to_str().unwrap());
    let mut args = vec!["import", dir, "--frames", "6", "--frames-from", "whole", "--out", out];
    if topic {
        args.extend(["--topic", "/camera"]);
    }
    ok(&args)
}

/// The entries of a taxel array's set that hold what it read, as their bytes.
fn read_values(set: &Path) -> Vec<(String, Vec<u8>)> {
    let mut npz = ndarray_npy::NpzReader::new(std::fs::File::open(set).unwrap()).unwrap();
    let x: ArrayD<f32> = npz.by_name("x").unwrap();
    let mut entries = vec![("x".to_string(), x.iter().flat_map(|v| v.to_le_bytes()).collect())];
    entries.push(("x.shape".into(), x.shape().iter().flat_map(|d| d.to_le_bytes()).collect()));
    for k in ["y", "lengths"] {
        let v: ArrayD<i64> = npz.by_name(k).unwrap();
        entries.push((k.into(), v.iter().flat_map(|v| v.to_le_bytes()).collect()));
    }
    for k in ["class_names", "channels"] {
        let v: ArrayD<u8> = npz.by_name(k).unwrap();
        entries.push((k.into(), v.iter().copied().collect()));
    }
    entries
}

/// The writer runs once (it takes seconds): each check reads what it wrote, the last damaging it.
#[test]
fn bags_written_by_other_libraries_import_as_their_files_do() {
    let dir = scratch("bags");
    run_script("tests/bag_writer.py", &[&dir]);
    bags_of_every_writer_and_message_import_equal_to_their_frames(&dir);
    a_long_bag_is_cut_into_touches_by_a_labels_file(&dir);
    a_bag_without_its_topic_lists_the_topics_it_has(&dir);
    std::fs::remove_dir_all(dir).unwrap();
}

fn bags_of_every_writer_and_message_import_equal_to_their_frames(dir: &Path) {
    for case in ARRAYS {
        // The CSV files' columns as a 3 × 4 grid; the bags' layout gives it, but float64's (none).
        let reference = dir.join(format!("{case}.npz"));
        let (csv, out) = (dir.join("csv").join(case), reference.to_str().unwrap());
        ok(&["import", csv.to_str().unwrap(), "--columns", "data*", "--grid", "3x4", "--out", out]);
        let expected = read_values(&reference);
        for writer in WRITERS {
            let (bag, out) = (dir.join("bags").join(writer).join(case), dir.join(format!("{case}-{writer}.npz")));
            let mut args = vec!["import", bag.to_str().unwrap(), "--topic", "/taxels", "--out", out.to_str().unwrap()];
            if case == "float64" {
                args.extend(["--grid", "3x4"]);
            }
            let said = ok(&args);
            assert!(
                said.contains("10 touches of 2 classes") && said.contains("12 channels as a 3 × 4 grid") && !said.contains("times:"),
                "{case}, {writer}:\n{said}"
            );
            assert!(read_values(&out) == expected, "{case}, {writer}: the bag's set differs from its CSV files'");
        }
    }
    for case in CASES {
        let reference = dir.join(format!("{case}.npz"));
        import(&dir.join("frames").join(case), &reference, false);
        let expected = read(&reference);
        for writer in WRITERS {
            let out = dir.join(format!("{case}-{writer}.npz"));
            let said = import(&dir.join("bags").join(writer).join(case), &out, true);
            assert!(said.contains("10 touches of 2 classes") && !said.contains("times:"), "{case}, {writer}:\n{said}");
            assert!(read(&out) == expected, "{case}, {writer}: the bag's set differs from its frames'");
        }
    }
}

/// One long bag, cut into its touches by a labels file (`path,class,start,end`), imports as the
/// touches' own frames do.
fn a_long_bag_is_cut_into_touches_by_a_labels_file(dir: &Path) {
    let reference = dir.join("reference.npz");
    import(&dir.join("frames/rgb8"), &reference, false);
    let out = dir.join("cut.npz");
    let (long, labels, o) = (dir.join("long"), dir.join("long/labels.csv"), out.to_str().unwrap());
    let args = ["--labels", labels.to_str().unwrap(), "--topic", "/camera", "--frames", "6", "--frames-from", "whole", "--out", o];
    let said = ok(&[&["import", long.to_str().unwrap()], &args[..]].concat());
    assert!(said.contains("10 touches of 2 classes"), "{said}");
    assert!(read(&out) == read(&reference), "the cut touches differ from their own frames");
    // A row whose seconds hold no message of the bag.
    let text = std::fs::read_to_string(&labels).unwrap();
    let bad = long.join("bad.csv");
    std::fs::write(&bad, text.replacen(",0,0.5\n", ",100,100.5\n", 1)).unwrap();
    let args = ["--labels", bad.to_str().unwrap(), "--topic", "/camera", "--frames", "6", "--frames-from", "whole", "--out", o];
    let said = fails(&[&["import", long.to_str().unwrap()], &args[..]].concat());
    assert!(said.contains("run: topic `/camera` has no message from 100 s to 100.5 s of the bag"), "{said}");
}

/// Damages the bags it reads: the last check.
fn a_bag_without_its_topic_lists_the_topics_it_has(dir: &Path) {
    let bags = dir.join("bags/rosbags-sqlite3/rgb8");
    let out = dir.join("x.npz");
    let said = fails(&["import", bags.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(said.contains("a bag needs --topic") && said.contains("/camera (sensor_msgs/msg/Image, 6 messages)"), "{said}");
    let said = fails(&["import", bags.to_str().unwrap(), "--topic", "/tactile", "--out", out.to_str().unwrap()]);
    assert!(said.contains("no message on topic `/tactile`; its topics:\n  /camera (sensor_msgs/msg/Image, 6 messages)"), "{said}");
    // A taxel array's bags: a grid that disagrees with their layout, a camera's option.
    let taxels = dir.join("bags/mcap-ros2-zstd/int16");
    let said = fails(&["import", taxels.to_str().unwrap(), "--topic", "/taxels", "--grid", "2x6", "--out", out.to_str().unwrap()]);
    assert!(said.contains("--grid 2x6 disagrees with the bag's messages, laid out 3 × 4 (layout.dim)"), "{said}");
    let said = fails(&["import", taxels.to_str().unwrap(), "--topic", "/taxels", "--frames", "6", "--out", out.to_str().unwrap()]);
    assert!(said.contains("--frames is for a camera's touches"), "{said}");
    // A metadata.yaml naming a file that is not there.
    let bag = bags.join("felt/touch0");
    let file = std::fs::read_dir(&bag).unwrap().map(|e| e.unwrap().path()).find(|p| p.extension().is_some_and(|e| e == "db3")).unwrap();
    std::fs::remove_file(&file).unwrap();
    let said = fails(&["import", bags.to_str().unwrap(), "--topic", "/camera", "--out", out.to_str().unwrap()]);
    assert!(said.contains("touch0") && said.contains("metadata.yaml names touch0.db3, which is not there"), "{said}");
}
