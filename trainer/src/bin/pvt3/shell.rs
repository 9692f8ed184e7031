//! `pvt3 completions SHELL` and `pvt3 man DIR`: the shell's completions and the manual pages,
//! both generated from the command line's own clap definitions, so neither can drift from it.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::CommandFactory;

/// Prints the completions of every command and option for a shell, e.g.
/// `pvt3 completions bash > ~/.local/share/bash-completion/completions/pvt3`.
#[derive(clap::Args)]
pub struct CompletionsArgs {
    /// The shell: bash, elvish, fish, powershell or zsh.
    pub shell: clap_complete::Shell,
}

/// Writes the manual pages, `pvt3.1` and one a subcommand (`pvt3-train.1`, …), e.g.
/// `pvt3 man ~/.local/share/man/man1`, then `man pvt3-train`.
#[derive(clap::Args)]
pub struct ManArgs {
    /// The folder the pages go to; made if missing.
    pub dir: PathBuf,
}

pub fn completions<C: CommandFactory>(shell: clap_complete::Shell, out: &mut dyn std::io::Write) {
    clap_complete::generate(shell, &mut C::command(), "pvt3", out);
}

pub fn man<C: CommandFactory>(dir: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("making {}", dir.display()))?;
    clap_mangen::generate_to(C::command(), dir).with_context(|| format!("writing the manual pages into {}", dir.display()))
}
