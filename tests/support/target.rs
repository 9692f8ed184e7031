//! Running a program built for the target: under the emulator that `PVT3_TARGET_RUNNER` names
//! when the tests run for another architecture, as `tests/run.sh` does for aarch64.

use std::path::Path;
use std::process::Command;

/// The emulator command line that runs the target's binaries (`PVT3_TARGET_RUNNER`, e.g.
/// `qemu-aarch64 -L /usr/aarch64-linux-gnu`), when the tests run for another architecture.
fn target_runner() -> Option<String> {
    std::env::var("PVT3_TARGET_RUNNER").ok().filter(|r| !r.trim().is_empty())
}

/// Whether the tests run under an emulator, where a plan built or a frame streamed costs a
/// hundred times what it does natively: there they show the target's arithmetic on fewer
/// windows and loads than the host's run (tests/run.sh).
pub fn emulated() -> bool {
    target_runner().is_some()
}

/// A command running `program`, a binary built for the target: through `PVT3_TARGET_RUNNER`
/// when it is set.
pub fn target_command(program: impl AsRef<Path>) -> Command {
    match target_runner() {
        Some(runner) => {
            let mut words = runner.split_whitespace();
            let mut c = Command::new(words.next().unwrap());
            c.args(words).arg(program.as_ref());
            c
        }
        None => Command::new(program.as_ref()),
    }
}
