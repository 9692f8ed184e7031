//! Every shell block of the README and the guide (docs/guide/) runs as a user types it, so that a
//! changed flag or path fails here. Each page's blocks run in a folder of its own, beside what
//! the pages assume:
//! the checkout's `shipped/` and `data/` and its crates, a folder of CSV touches (`csvs/`), bags
//! written by tests/bag_writer.py (`bags/`, `skin-bags/`), `model.onnx` and `windows.npy`; the
//! tests' builds of pvt3, pvt3-run and pvt3-ros come first on PATH, and `cargo` stands for those
//! builds (tests/guide_cargo.py). A `console` block's output is checked as the page shows it
//! (snapbox: `...` for lines, `[..]` within one).
//!
//! A block that cannot run here says why on the line above it, visible in the page's source:
//! - `<!-- commands: parse only, REASON -->`: each command of pvt3's programs has its options
//!   and values read (`--help` added, which reads the whole line first) but does no work; other
//!   commands are not run;
//! - `<!-- commands: not run, REASON -->`.

#[path = "support/csv_tree.rs"]
#[allow(dead_code)] // the CLI tests use the rest of it
mod csv_tree;
#[path = "support/onnx_check.rs"]
#[allow(dead_code)] // the other end-to-end tests use the rest of it
mod onnx_check;
#[path = "support/pages.rs"]
mod pages;
#[path = "support/workspace.rs"]
mod workspace;

use std::path::{Path, PathBuf};
use std::process::Command;

use pages::user_pages;
use workspace::workspace;

/// The programs whose commands a page's blocks give, as the tests built them.
const PROGRAMS: [&str; 3] = ["pvt3", "pvt3-run", "pvt3-ros"];

/// How a block is checked.
#[derive(Debug, PartialEq)]
enum How {
    Run,
    ParseOnly(String),
    NotRun(String),
}

/// A fenced shell block of a page: `sh`, `bash`, `shell`, `console`, or a `text` block of
/// `$ ` commands.
#[derive(Debug)]
struct Block {
    at: String,
    console: bool,
    text: String,
    how: How,
}

/// The marker on the line before a block, if any.
fn how(marker: &str) -> Result<How, String> {
    let Some(rest) = marker.trim().strip_prefix("<!-- commands:").and_then(|r| r.strip_suffix("-->")) else {
        return Ok(How::Run);
    };
    let rest = rest.trim();
    match (rest.strip_prefix("parse only,"), rest.strip_prefix("not run,")) {
        (Some(why), _) if !why.trim().is_empty() => Ok(How::ParseOnly(why.trim().into())),
        (_, Some(why)) if !why.trim().is_empty() => Ok(How::NotRun(why.trim().into())),
        _ => Err(format!("`{marker}`: expected `<!-- commands: parse only, REASON -->` or `<!-- commands: not run, REASON -->`")),
    }
}

/// The shell blocks of `page`.
fn blocks(page: &Path) -> Vec<Block> {
    let text = std::fs::read_to_string(page).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let name = page.strip_prefix(workspace()).unwrap_or(page).display().to_string();
    let mut found = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let Some(info) = lines[i].strip_prefix("```").filter(|info| !info.is_empty()) else {
            i += 1;
            continue;
        };
        let end = i
            + 1
            + lines[i + 1..].iter().position(|l| l.starts_with("```")).unwrap_or_else(|| panic!("{name}:{}: an unclosed block", i + 1));
        let body = lines[i + 1..end].join("\n");
        let console = info == "console" || (info == "text" && body.starts_with("$ "));
        if console || ["sh", "bash", "shell"].contains(&info) {
            let marker = if i > 0 { lines[i - 1] } else { "" };
            let how = how(marker).unwrap_or_else(|e| panic!("{name}:{i}: {e}"));
            found.push(Block { at: format!("{name}:{}", i + 1), console, text: body, how });
        }
        i = end + 1;
    }
    found
}

/// What the pages assume, made once in `assumed/` (the bags' writer's output beside it in
/// `made/`): the checkout's folders, the programs, a CSV folder, bags, a model and its windows.
fn fixtures() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-guide-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (assumed, made) = (dir.join("assumed"), dir.join("made"));
    let bin = assumed.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let root = workspace().canonicalize().unwrap();
    for shared in ["shipped", "data", "trainer", "runtime", "ros"] {
        std::os::unix::fs::symlink(root.join(shared), assumed.join(shared)).unwrap();
    }
    let built = Path::new(env!("CARGO_BIN_EXE_pvt3")).parent().unwrap();
    for program in PROGRAMS {
        let path = built.join(program);
        assert!(path.exists(), "{}: build every program first (cargo test --workspace does)", path.display());
        std::os::unix::fs::symlink(path, bin.join(program)).unwrap();
    }
    let cargo = format!("#!/bin/sh\nexec python3 {} \"$@\"\n", root.join("tests/guide_cargo.py").display());
    std::fs::write(bin.join("cargo"), cargo).unwrap();
    std::fs::set_permissions(bin.join("cargo"), std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    csv_tree::write(&assumed.join("csvs"), 2, 8, 40, 64);
    onnx_check::run_script("tests/bag_writer.py", &[&made]);
    std::os::unix::fs::symlink(made.join("bags/rosbags-mcap/rgb8"), assumed.join("bags")).unwrap();
    std::os::unix::fs::symlink(made.join("bags/rosbags-mcap/int16"), assumed.join("skin-bags")).unwrap();
    std::fs::copy(root.join("shipped/icub20.onnx"), assumed.join("model.onnx")).unwrap();
    std::fs::copy(root.join("shipped/icub20-touch.npy"), assumed.join("windows.npy")).unwrap();
    dir
}

/// The folder of one page's blocks, which build on each other, made on its first block: every
/// fixture beside it, and a home of its own.
fn page_folder(fixtures: &Path, page: usize) -> PathBuf {
    let dir = fixtures.join(format!("page{page}"));
    if !dir.exists() {
        std::fs::create_dir_all(dir.join("home")).unwrap();
        for entry in std::fs::read_dir(fixtures.join("assumed")).unwrap().map(|e| e.unwrap()) {
            std::os::unix::fs::symlink(entry.path(), dir.join(entry.file_name())).unwrap();
        }
    }
    dir
}

/// A bash running in `dir` as the user's shell would, the tests' programs first on PATH.
fn shell(dir: &Path, script: &str) -> Command {
    let path = format!("{}:{}", dir.join("bin").display(), std::env::var("PATH").unwrap_or_default());
    let mut c = Command::new("bash");
    c.args(["-c", script]).current_dir(dir).env("PATH", path).env("HOME", dir.join("home"));
    // A user's shell asks for no backtraces, which an error would otherwise print after itself.
    c.env_remove("RUST_BACKTRACE").env_remove("RUST_LIB_BACKTRACE");
    c.env("PVT3_REAL_CARGO", env!("CARGO")).env("PVT3_WORKSPACE", workspace().canonicalize().unwrap());
    c.env("PVT3_BUILT", Path::new(env!("CARGO_BIN_EXE_pvt3")).parent().unwrap());
    c
}

/// Runs a block's commands as a script that stops at the first failure: what went wrong, if
/// anything.
fn run_script(dir: &Path, script: &str) -> Result<(), String> {
    let out = shell(dir, &format!("set -euo pipefail\n{script}")).output().unwrap();
    match out.status.success() {
        true => Ok(()),
        false => Err(format!("{}\n{}{}", out.status, String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))),
    }
}

/// A parse-only block: its commands of pvt3's programs, each with `--help` added.
fn parse_only(text: &str) -> String {
    let mut script = String::new();
    for program in PROGRAMS {
        script += &format!("{program}() {{ command {program} \"$@\" --help > /dev/null; }}\n");
    }
    for line in text.lines() {
        let first = line.split_whitespace().next().unwrap_or_default();
        if PROGRAMS.contains(&first) || line.starts_with("cargo run") {
            script += &(line.replace("cargo run", "PVT3_GUIDE_HELP=1 cargo run") + "\n");
        }
    }
    script
}

/// A console block: each `$ ` command run, its standard output and error together matched
/// against what the page shows after it.
fn console(dir: &Path, text: &str) -> Result<(), String> {
    for part in text.split("\n$ ").map(|p| p.trim_start_matches("$ ")) {
        let (command, shown) = part.split_once('\n').unwrap_or((part, ""));
        let out = shell(dir, &format!("{command} 2>&1")).output().unwrap();
        let said = String::from_utf8_lossy(&out.stdout).to_string();
        snapbox::Assert::new()
            .try_eq(Some(&command), said.into(), if shown.is_empty() { String::new() } else { format!("{shown}\n") }.into())
            .map_err(|e| format!("$ {command}\n{e}"))?;
    }
    Ok(())
}

/// Every block runs, is read, or says why not; none fails.
#[test]
fn every_shell_block_of_the_readme_and_the_guide_runs_as_written() {
    let fixtures = fixtures();
    let mut failed = Vec::new();
    let mut counts = [0; 3];
    for (n, block) in user_pages().iter().enumerate().flat_map(|(n, p)| blocks(p).into_iter().map(move |b| (n, b))) {
        let dir = page_folder(&fixtures, n);
        let result = match &block.how {
            How::Run if block.console => console(&dir, &block.text),
            How::Run => run_script(&dir, &block.text),
            How::ParseOnly(_) => run_script(&dir, &parse_only(&block.text)),
            How::NotRun(_) => Ok(()),
        };
        counts[match block.how {
            How::Run => 0,
            How::ParseOnly(_) => 1,
            How::NotRun(_) => 2,
        }] += 1;
        if let Err(e) = result {
            failed.push(format!("{}: {e}", block.at));
        }
    }
    eprintln!("shell blocks: {} run, {} read (parse only), {} not run, each with its reason", counts[0], counts[1], counts[2]);
    assert!(failed.is_empty(), "{}", failed.join("\n\n"));
    assert!(counts[0] >= 8, "the blocks that run are the guide's substance: {counts:?}");
    std::fs::remove_dir_all(&fixtures).unwrap();
}

/// The block reader finds blocks and their markers, and refuses a marker without a reason.
#[test]
fn blocks_and_their_markers_are_read() {
    assert_eq!(how("<!-- commands: not run, needs the FabricSlide set -->"), Ok(How::NotRun("needs the FabricSlide set".into())));
    assert_eq!(how("<!-- commands: parse only, trains for hours -->"), Ok(How::ParseOnly("trains for hours".into())));
    assert_eq!(how("Some prose."), Ok(How::Run));
    assert!(how("<!-- commands: not run -->").is_err());
    let script = parse_only("ros2 bag record -o x /t\npvt3 cv --data x.npz   # a comment\ncargo run --release -- train");
    assert!(
        !script.contains("ros2") && script.contains("pvt3 cv --data x.npz") && script.contains("PVT3_GUIDE_HELP=1 cargo run"),
        "{script}"
    );
}
