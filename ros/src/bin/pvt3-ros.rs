//! `pvt3-ros`: the node, started as ROS users start one (`--ros-args -r … -p …`).

#![deny(clippy::undocumented_unsafe_blocks)]

use pvt3_ros::args::{Args, PARAMETERS, TOPICS};
use pvt3_ros::node::Node;

fn help() -> String {
    let mut text = String::from(
        "usage: pvt3-ros --ros-args -p model:=FILE.onnx [-p NAME:=VALUE]... [-r FROM:=TO]...\n\n\
         A ROS 2 node over rmw_zenoh (a zenoh router on the robot): it classifies each touch of a tactile\n\
         sensor's topic with a pvt3 file, decoding every message as `pvt3 import` decodes a bag and reading\n\
         its frames as the file records (a camera's crop, size, grey and first frame; a taxel array's grid).\n\
         The node is `pvt3` in `/` unless -r __node:=NAME or -r __ns:=/NS say otherwise; ROS_DOMAIN_ID picks\n\
         the domain.\n\nParameters (-p NAME:=VALUE):\n",
    );
    for (name, default, what) in PARAMETERS {
        let default = if default.is_empty() { String::new() } else { format!(" (default: {default})") };
        text += &format!("  {name:<12} {}\n", wrapped(&format!("{what}{default}"), 15, 100));
    }
    text += "\nTopics (remap with -r NAME:=/your/topic):\n";
    for (name, type_name, what) in TOPICS {
        text += &format!("  {name:<15} {type_name}\n  {:<15} {what}\n", "");
    }
    text
}

/// `text` in lines of at most `width` columns, each after the first indented by `indent`.
fn wrapped(text: &str, indent: usize, width: usize) -> String {
    let mut lines = vec![String::new()];
    for word in text.split(' ') {
        let line = lines.last_mut().expect("a line");
        if !line.is_empty() && indent + line.len() + 1 + word.len() > width {
            lines.push(word.to_string());
        } else {
            *line += &format!("{}{word}", if line.is_empty() { "" } else { " " });
        }
    }
    lines.join(&format!("\n{:indent$}", ""))
}

/// The node's memory stays flat while it serves: freed memory is kept for the next touch (the
/// runtime's tensors), and every thread allocates from one heap. glibc otherwise gives a thread
/// that meets a busy heap one of its own, and the node's resident memory grew by steps for
/// minutes (docs/benchmarks.md, "The ROS 2 node").
fn set_up_memory() {
    // SAFETY: first thing in main, before zenoh or anything else starts a thread.
    unsafe { pvt3_runtime::keep_freed_memory() };
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets glibc's allocator's policy, and no other thread exists yet.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}

fn main() -> std::process::ExitCode {
    set_up_memory();
    let (asked_help, words): (Vec<String>, Vec<String>) = std::env::args().skip(1).partition(|w| w == "--help" || w == "-h");
    if !asked_help.is_empty() {
        // The rest of the line is read first, so that `… --help` also checks a command line.
        if let Err(e) = Args::parse(&words, None) {
            eprintln!("pvt3-ros: {e}");
            return std::process::ExitCode::FAILURE;
        }
        print!("{}", help());
        return std::process::ExitCode::SUCCESS;
    }
    let run = || -> Result<(), String> {
        let args = Args::parse(&words, std::env::var("ROS_DOMAIN_ID").ok().as_deref()).map_err(|e| e.to_string())?;
        if args.parameter("model").is_empty() {
            return Err("-p model:=FILE.onnx: the pvt3 file to classify with (see --help)".into());
        }
        let node = Node::start(args).map_err(|e| e.to_string())?;
        eprintln!("pvt3-ros: joined the graph as session {} ({} entities)", node.session_id(), node.entities());
        node.serve().map_err(|e| e.to_string())
    };
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pvt3-ros: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
