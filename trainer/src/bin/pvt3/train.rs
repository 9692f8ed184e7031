//! `pvt3 train`: one split, then optionally pruning, fine-tuning and export.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use pvt3_trainer::prune::prune_and_fine_tune;
use pvt3_trainer::run_dir::Run;
use pvt3_trainer::train::train;

use crate::export::export_onnx;
use crate::model_args::{prepare, ModelArgs};
use crate::progress;
use crate::prune_args::{report_pruned, PruneArgs};

/// Train on one split: fold K validates (epoch selection), fold 4 tests, the rest trains.
#[derive(clap::Args)]
pub struct TrainArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Validation fold (0..3).
    #[arg(long, default_value_t = 0)]
    pub fold: usize,
    /// Run directory (checkpoint in OUT/model, resume state in OUT/last, metrics.jsonl).
    #[arg(long, short, default_value = "runs/train")]
    pub out: PathBuf,
    /// Continue the interrupted run in OUT.
    #[arg(long)]
    pub resume: bool,
    /// With --prune-channels/--prune-frames: prune the trained model and fine-tune it into OUT/pruned.
    #[command(flatten)]
    pub prune: PruneArgs,
    /// Finally bake the model (the pruned one, if pruning was asked for) and export it as ONNX.
    #[arg(long, value_name = "FILE.onnx")]
    pub export: Option<PathBuf>,
    /// Print the result as one JSON object on standard output (the run's result, its
    /// checkpoint, the pruned run's and the exported file's), the lines of text on standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: TrainArgs) -> Result<()> {
    // With --json the lines of text go to standard error, and one JSON object to standard output.
    let say = |line: String| if a.json { eprintln!("{line}") } else { println!("{line}") };
    let prepared = prepare(&a.model)?;
    let stage = a.prune.stage();
    if stage.is_some() || a.export.is_some() {
        prepared.config.require_pvt3("pruning and export")?;
    }
    let bar = progress::bar(format!("fold {}", a.fold));
    let started = Instant::now();
    let r = train(&prepared.spec(&a.model, a.fold), &a.out, a.resume, &bar)?;
    bar.finish();
    let paused = || {
        say("paused; continue with the same command and --resume".into());
        if a.json {
            println!("{}", serde_json::json!({"paused": true}));
        }
        Ok(())
    };
    let Some(r) = r else { return paused() };
    say(format!(
        "best epoch {} of {}: validation accuracy {:.4}, test accuracy {:.4} ({:.0} s); checkpoint {}",
        r.best_epoch,
        r.epochs,
        r.val_accuracy,
        r.test_accuracy,
        started.elapsed().as_secs_f64(),
        Run(&a.out).model().display()
    ));
    let mut last = a.out.clone();
    let mut pruned = None;
    if let Some(stage) = stage {
        let bar = progress::bar("fine-tune");
        last = Run(&a.out).pruned();
        let Some(p) = prune_and_fine_tune(&a.out, &prepared.data, &stage, &last, a.resume, &bar)? else { return paused() };
        bar.finish();
        say(report_pruned(&p, &last)?);
        pruned = Some(p);
    }
    if let Some(path) = &a.export {
        say(export_onnx(&last, path)?);
    }
    if a.json {
        let checkpoint = |dir: &std::path::Path| Run(dir).model().display().to_string();
        let out = serde_json::json!({
            "run": r, "checkpoint": checkpoint(&a.out),
            "pruned": pruned, "pruned_checkpoint": pruned.as_ref().map(|_| checkpoint(&last)),
            "onnx": a.export.as_ref().map(|p| p.display().to_string()),
        });
        println!("{out}");
    }
    Ok(())
}
