//! The Rust example (`runtime/examples/classify.rs`): the README's snippet is the example's code
//! to the letter, so that what the README shows compiles; run on the golden windows, its answers
//! are the runtime's.

mod support;

use pvt3_runtime::{read_npy, Classifier};
use support::{golden, root, scratch, target_command};

const BEGIN: &str = "// The README's snippet, from here to the end of `slide`.\n";
const END: &str = "// The end of the README's snippet.\n";

#[test]
fn the_readme_shows_the_example_s_code() {
    let example = std::fs::read_to_string(root().join("examples/classify.rs")).unwrap();
    let snippet = example.split(BEGIN).nth(1).and_then(|rest| rest.split(END).next()).expect("the snippet's markers");
    let readme = std::fs::read_to_string(root().join("../README.md")).unwrap();
    assert!(
        readme.contains(&format!("```rust\n{snippet}```\n")),
        "README.md's Rust block is not examples/classify.rs's snippet:\n{snippet}"
    );
}

#[test]
fn the_example_answers_as_the_runtime_does() {
    let dir = scratch("rust-example");
    std::fs::copy(golden("model.onnx"), dir.join("model.onnx")).unwrap();
    // The test binary lives in target/<profile>/deps; the examples in target/<profile>/examples.
    let examples = std::env::current_exe().unwrap().parent().unwrap().parent().unwrap().join("examples");
    let out = target_command(examples.join("classify")).arg(golden("input.npy")).current_dir(&dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let (_, x) = read_npy(&golden("input.npy")).unwrap();
    let first = c.classify(&x[..4500]).unwrap();
    let line = |how: &str| stdout.lines().find(|l| l.starts_with(&format!("{how}\t"))).unwrap_or_else(|| panic!("{how}: {stdout}"));
    for how in ["whole", "streamed", "until clear"] {
        let fields: Vec<&str> = line(how).split('\t').collect();
        assert_eq!(fields[1], first.label, "{how}: the golden file has no stopping rule, so every way reads the whole window");
        assert!((fields[2].parse::<f32>().unwrap() - first.probabilities[first.class]).abs() < 1e-5, "{how}");
    }
    // Eight windows of 75 frames, one token a frame: an answer at every frame from the 75th.
    assert_eq!(stdout.lines().filter(|l| l.starts_with("slide\t")).count(), 8 * 75 - 74);
    std::fs::remove_dir_all(dir).unwrap();
}
