//! `pvt3`: train, cross-validate, prune, export, evaluate and inspect PVT³ tactile texture
//! classifiers. One module per command: its options (clap) and what it does.

mod bench;
mod cv;
mod eval;
mod eval_cv;
mod export;
mod final_model;
mod import;
mod info;
mod model_args;
mod plot;
mod progress;
mod prune;
mod prune_args;
mod shell;
mod train;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// What every command's exit status means, for `--help` (and docs/guide/command-line.md).
const EXIT_STATUS: &str =
    "Exit status: 0 done; 1 refused or failed, the reason on standard error (a file, an option, what it could not do); 2 a command line it cannot read.";

#[derive(Parser)]
#[command(
    name = "pvt3",
    version,
    propagate_version = true,
    about = "PVT³ tactile texture classification: import, train, cross-validate, evaluate, export, inspect",
    after_help = EXIT_STATUS
)]
struct Cli {
    /// CPU threads (default: all cores). Training and evaluation split each batch's sequences
    /// over them (two threads: 1.5-1.7x one; `cv --jobs N` uses the cores best, one fold per
    /// thread); a camera import reads touches on them; export, bake, info and plot run on one.
    /// The result is the same bits on any count.
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    Import(import::ImportArgs),
    Train(train::TrainArgs),
    Cv(cv::CvArgs),
    Final(final_model::FinalArgs),
    Prune(prune::PruneCommand),
    Export(export::ExportArgs),
    Bake(export::BakeArgs),
    Eval(eval::EvalArgs),
    Plot(plot::PlotArgs),
    /// Benchmarks (see docs/training-speed.md).
    #[command(subcommand)]
    Bench(bench::Bench),
    Info(info::InfoArgs),
    Completions(shell::CompletionsArgs),
    Man(shell::ManArgs),
}

/// Process settings, before any other thread starts.
/// - Memory: candle allocates fresh buffers for every op, and glibc hands large ones back to the
///   kernel on free, so training spent a quarter of its time in page faults zeroing new pages.
///   Keeping freed memory in the heap makes the next step reuse it.
/// - SIGPIPE back to its default, so that `pvt3 info | head` ends quietly instead of panicking.
///
/// The first is glibc's (other allocators keep their own policy), the second Unix's: elsewhere
/// (macOS, Windows, musl) the trainer builds without them.
fn set_up_process() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only adjusts glibc's allocator, and no other thread exists yet.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
        libc::mallopt(libc::M_TOP_PAD, 64 << 20);
    }
    #[cfg(unix)]
    // SAFETY: restores a signal's default disposition, before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn main() -> Result<()> {
    set_up_process();
    let cli = Cli::parse();
    let jobs = match &cli.command {
        Command::Cv(a) => a.jobs,
        _ => 1,
    };
    // candle reads the thread count from RAYON_NUM_THREADS; it must be set before its first use.
    if let Some(t) = cli.threads.or((jobs > 1).then_some(1)) {
        std::env::set_var("RAYON_NUM_THREADS", t.to_string());
    }
    match cli.command {
        Command::Import(a) => import::run(a),
        Command::Train(a) => train::run(a),
        Command::Cv(a) => cv::run(a),
        Command::Final(a) => final_model::run(a),
        Command::Prune(a) => prune::run(a),
        Command::Export(a) => export::export_onnx(&a.model, &a.out).map(|done| println!("{done}")),
        Command::Bake(a) => export::bake(a),
        Command::Eval(a) if eval_cv::applies(&a) => eval_cv::run(&a),
        Command::Eval(a) => eval::run(a),
        Command::Plot(a) => plot::run(a),
        Command::Bench(b) => bench::run(b),
        Command::Info(a) => info::run(a),
        Command::Completions(a) => {
            shell::completions::<Cli>(a.shell, &mut std::io::stdout());
            Ok(())
        }
        Command::Man(a) => shell::man::<Cli>(&a.dir).map(|()| println!("manual pages written to {}", a.dir.display())),
    }
}

#[cfg(test)]
mod tests {
    use clap::{CommandFactory, Parser};

    use super::{Cli, Command};

    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    /// `--version` answers on every subcommand.
    #[test]
    fn every_subcommand_tells_its_version() {
        for sub in Cli::command().get_subcommands().map(|c| c.get_name().to_string()) {
            let e = Cli::try_parse_from(["pvt3", sub.as_str(), "--version"]).err().unwrap_or_else(|| panic!("{sub} --version ran"));
            assert_eq!(e.kind(), clap::error::ErrorKind::DisplayVersion, "{sub}");
        }
    }

    /// The completions and the manual pages cover every subcommand, from the same definitions.
    #[test]
    fn completions_and_manual_pages_cover_every_subcommand() {
        let mut bash = Vec::new();
        super::shell::completions::<Cli>(clap_complete::Shell::Bash, &mut bash);
        let bash = String::from_utf8(bash).unwrap();
        let dir = std::env::temp_dir().join(format!("pvt3-man-{}", std::process::id()));
        super::shell::man::<Cli>(&dir).unwrap();
        for sub in Cli::command().get_subcommands().map(|c| c.get_name().to_string()) {
            assert!(bash.contains(&format!("pvt3__subcmd__{sub}")), "no bash completion for {sub}");
            let page = std::fs::read_to_string(dir.join(format!("pvt3-{sub}.1"))).unwrap_or_else(|e| panic!("pvt3-{sub}.1: {e}"));
            assert!(page.contains(".TH pvt3-"), "pvt3-{sub}.1 is no manual page");
        }
        assert!(std::fs::read_to_string(dir.join("pvt3.1")).unwrap().contains(r"\-\-threads"), "the global option, in roff");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Options parse into their types: value enums, seeds, pruning, --only; bad values are
    /// refused by the parser, before any work.
    #[test]
    fn options_parse_into_their_types() {
        let cli =
            Cli::try_parse_from(["pvt3", "cv", "--model", "vit", "--seeds", "0,1,2", "--prune-frames", "50", "--prune-scope", "global"])
                .unwrap();
        let Command::Cv(a) = cli.command else { panic!("not cv") };
        assert_eq!(a.model.architecture, Some(pvt3_models::Architecture::Vit));
        assert_eq!(a.seeds, [0, 1, 2]);
        let stage = a.prune.stage().unwrap();
        assert_eq!((stage.spec.frames, stage.spec.channels, stage.spec.scope), (50.0, 0.0, pvt3_spec::prune::Scope::Global));
        let cli = Cli::try_parse_from(["pvt3", "--threads", "1", "train", "--prefix-training", "0.5", "--fold", "2"]).unwrap();
        let Command::Train(a) = cli.command else { panic!("not train") };
        assert_eq!((cli.threads, a.fold, a.model.options.prefix_training, a.prune.stage().is_none()), (Some(1), 2, 0.5, true));
        let cli = Cli::try_parse_from(["pvt3", "cv", "--only", "seed=1,fold=3"]).unwrap();
        let Command::Cv(a) = cli.command else { panic!("not cv") };
        assert_eq!(a.only, Some((1, 3)));
        for bad in [
            vec!["pvt3", "cv", "--model", "lstm"],
            vec!["pvt3", "train", "--prune-scope", "everywhere"],
            vec!["pvt3", "cv", "--only", "seed=1,fold=4"],
            vec!["pvt3", "cv", "--only", "seed=1,fold=0", "--seeds", "1"],
            vec!["pvt3", "cv", "--report", "runs/x", "--resume"],
            vec!["pvt3", "eval", "runs/x", "--answers", "a.json"],
        ] {
            assert!(Cli::try_parse_from(&bad).is_err(), "{bad:?}");
        }
    }
}
