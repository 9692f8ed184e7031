//! Importing a generated CSV tree, and the errors a user's own files can provoke.

use std::path::PathBuf;

use super::*;
use crate::data::Dataset;

#[path = "../../../tests/support/csv_tree.rs"]
mod csv_tree;

fn tree(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-import-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    csv_tree::write(&dir, 3, 6, 40, 64);
    dir
}

#[test]
fn a_csv_tree_imports_with_its_lengths_names_and_channels() {
    let dir = tree("ok");
    let set = read_folder(&dir, &ImportOptions::default()).unwrap();
    assert_eq!(set.channels, ["e1", "e2", "e3", "e4"]);
    let left: Vec<_> = set.left_out.iter().map(|(n, why)| (n.as_str(), *why)).collect();
    assert_eq!(left, [("time", "a time stamp by its name"), ("pressure_set", "constant")]);
    assert_eq!((set.classes.len(), set.per_class()), (3, vec![6, 6, 6]));
    let (shortest, longest) = set.length_range();
    assert!(shortest >= 40 && longest <= 64 && shortest < longest, "{shortest}..{longest}");
    let out = dir.join("set.npz");
    set.write_npz(&out).unwrap();
    let data = Dataset::load(&out, 0).unwrap();
    assert_eq!(data.sample_shape, vec![4, 1, longest]);
    assert_eq!(data.class_names.as_deref().unwrap(), ["material_0", "material_1", "material_2"]);
    assert_eq!(data.sources.as_ref().unwrap()[0], "material_0/touch_00.csv");
    assert_eq!(*data.lengths.iter().min().unwrap(), shortest);
    assert!(!data.equal_lengths());
    // Touch 0's first frame, channel e2, as the file has it.
    let text = std::fs::read_to_string(dir.join("material_0/touch_00.csv")).unwrap();
    let e2: f32 = text.lines().nth(1).unwrap().split(',').nth(2).unwrap().parse().unwrap();
    assert_eq!(data.sample(0)[longest], e2);
    // Chosen by pattern, laid out on a grid.
    let opts = ImportOptions { columns: vec!["e?".into()], grid: Some((2, 2)) };
    let set = read_folder(&dir, &opts).unwrap();
    set.write_npz(&out).unwrap();
    assert_eq!(Dataset::load(&out, 0).unwrap().sample_shape, vec![2, 2, longest]);
    let err = read_folder(&dir, &ImportOptions { columns: vec!["e?".into()], grid: Some((3, 2)) }).unwrap_err().to_string();
    assert!(err.contains("--grid 3x2 holds 6 channels, and 4 columns were chosen"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_files_are_named_with_their_line() {
    let dir = tree("bad");
    let touch = dir.join("material_1/touch_03.csv");
    let good = std::fs::read_to_string(&touch).unwrap();
    let mut lines: Vec<String> = good.lines().map(String::from).collect();
    let err = |dir: &Path, opts: &ImportOptions| read_folder(dir, opts).unwrap_err().to_string();

    lines[5].push_str(",9.9");
    std::fs::write(&touch, lines.join("\n")).unwrap();
    let msg = err(&dir, &ImportOptions::default());
    assert!(msg.contains("touch_03.csv:6: a ragged row: 7 fields, the header has 6"), "{msg}");

    lines[5] = good.lines().nth(5).unwrap().replacen(",1", ",oops", 1);
    std::fs::write(&touch, lines.join("\n")).unwrap();
    let msg = err(&dir, &ImportOptions { columns: vec!["e*".into()], grid: None });
    assert!(msg.contains("touch_03.csv:6: column `e1` holds text, not a number"), "{msg}");
    // By default a column with text is left out, said so.
    let set = read_folder(&dir, &ImportOptions::default()).unwrap();
    assert!(set.left_out.contains(&("e1".into(), "not numeric")), "{:?}", set.left_out);
    std::fs::write(&touch, &good).unwrap();

    let msg = err(&dir, &ImportOptions { columns: vec!["force".into()], grid: None });
    assert!(msg.contains("--columns force: no column of the header matches"), "{msg}");

    std::fs::create_dir_all(dir.join("material_9")).unwrap();
    let msg = err(&dir, &ImportOptions::default());
    assert!(msg.contains("material_9: an empty class"), "{msg}");
    for n in 0..3 {
        std::fs::write(dir.join(format!("material_9/t{n}.csv")), &good).unwrap();
    }
    let msg = err(&dir, &ImportOptions::default());
    assert!(msg.contains("material_9: 3 touches, too few to split"), "{msg}");
    std::fs::remove_dir_all(dir.join("material_9")).unwrap();

    std::fs::write(&touch, good.replacen("e4", "e5", 1)).unwrap();
    let msg = err(&dir, &ImportOptions::default());
    assert!(msg.contains("touch_03.csv:1: its header differs from"), "{msg}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn patterns_match_whole_names() {
    assert!(matches("ff_e*", "ff_e12") && matches("e?", "e1") && matches("*", ""));
    assert!(!matches("e?", "e12") && !matches("ff_e*", "ff_pdc") && !matches("e1", "e12"));
}
