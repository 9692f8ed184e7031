//! Progress bars for long work (training, fine-tuning), one style for every command.

use indicatif::{ProgressBar, ProgressStyle};

pub fn style() -> ProgressStyle {
    ProgressStyle::with_template("{prefix:>14} [{elapsed_precise}] {bar:30} {percent:>3}% eta {eta} {msg}").expect("a valid template")
}

/// A bar for one run, its length set by the run.
pub fn bar(prefix: impl Into<String>) -> ProgressBar {
    let bar = ProgressBar::new(0).with_style(style());
    bar.set_prefix(prefix.into());
    bar
}
