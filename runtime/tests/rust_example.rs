//! The Rust example (`runtime/examples/classify.rs`): the guide's snippet (docs/guide/robot.md)
//! is the example's code to the letter, so that what the guide shows compiles; run on the golden
//! windows, its answers are the runtime's.

mod support;

use pvt3_runtime::{read_npy, Classifier};
use support::{golden, root, scratch, target_command};

const BEGIN: &str = "// The guide's snippet (docs/guide/robot.md), from here to the end of `slide`.\n";
const END: &str = "// The end of the guide's snippet.\n";

#[test]
fn the_guide_shows_the_example_s_code() {
    let example = std::fs::read_to_string(root().join("examples/classify.rs")).unwrap();
    let snippet = example.split(BEGIN).nth(1).and_then(|rest| rest.split(END).next()).expect("the snippet's markers");
    let guide = std::fs::read_to_string(root().join("../docs/guide/robot.md")).unwrap();
    assert!(
        guide.contains(&format!("```rust\n{snippet}```\n")),
        "docs/guide/robot.md's Rust block is not examples/classify.rs's snippet:\n{snippet}"
    );
}

#[test]
fn the_example_answers_as_the_runtime_does() {
    let dir = scratch("rust-example");
    std::fs::copy(golden("model.onnx"), dir.join("model.onnx")).unwrap();
    // The test binary lives in target/<profile>/deps; the examples in target/<profile>/examples.
    let examples = std::env::current_exe().unwrap().parent().unwrap().parent().unwrap().join("examples");
    // Two of the golden windows: the stream answers every frame once a window is in, and each
    // answer classifies a whole window, which costs under an emulator.
    // The .npy of eight is its header, shape (8, 6, 10, 75), and the values: the same header
    // with (2, …, of the same length, and the first two windows' values.
    let eight = std::fs::read(golden("input.npy")).unwrap();
    let values = 10 + u16::from_le_bytes([eight[8], eight[9]]) as usize;
    let header = String::from_utf8(eight[10..values].to_vec()).unwrap().replacen("(8,", "(2,", 1);
    let two = dir.join("two.npy");
    std::fs::write(&two, [&eight[..10], header.as_bytes(), &eight[values..values + 2 * 4500 * 4]].concat()).unwrap();
    let (_, x) = read_npy(&two).unwrap();
    assert_eq!(x.len(), 2 * 4500);
    let out = target_command(examples.join("classify")).arg(&two).current_dir(&dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let first = c.classify(&x[..4500]).unwrap();
    let line = |how: &str| stdout.lines().find(|l| l.starts_with(&format!("{how}\t"))).unwrap_or_else(|| panic!("{how}: {stdout}"));
    for how in ["whole", "streamed", "until clear"] {
        let fields: Vec<&str> = line(how).split('\t').collect();
        assert_eq!(fields[1], first.label, "{how}: the golden file has no stopping rule, so every way reads the whole window");
        assert!((fields[2].parse::<f32>().unwrap() - first.probabilities[first.class]).abs() < 1e-5, "{how}");
    }
    // Two windows of 75 frames, one token a frame: an answer at every frame from the 75th.
    assert_eq!(stdout.lines().filter(|l| l.starts_with("slide\t")).count(), 2 * 75 - 74);
    std::fs::remove_dir_all(dir).unwrap();
}
