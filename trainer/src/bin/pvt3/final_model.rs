//! `pvt3 final CV`: the model to ship, trained on every labelled touch as the cross-validation
//! in CV chose ([`pvt3_trainer::final_model`]), and exported.

use std::path::PathBuf;

use anyhow::Result;
use pvt3_trainer::final_model::Plan;
use pvt3_trainer::run_dir::FINAL;

use crate::export::export_onnx;
use crate::progress;

/// Train the model to ship on every labelled touch, as a cross-validation chose: the median of
/// the epochs its runs selected by validation, its options, pruning and fine-tuning, and its
/// stopping rule; then export it. Nothing is left to test it: the file states the accuracy the
/// cross-validation measured, with its interval.
#[derive(clap::Args)]
pub struct FinalArgs {
    /// The cross-validation's directory (`pvt3 cv --out`), all of its runs finished.
    pub cv: PathBuf,
    /// The ONNX file to write.
    #[arg(long, short, default_value = "model.onnx")]
    pub out: PathBuf,
    /// The final run's directory (default: CV/final).
    #[arg(long, value_name = "DIR")]
    pub run: Option<PathBuf>,
    /// The data set, if it has moved since the cross-validation (its touches must be the same).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Continue an interrupted final run.
    #[arg(long)]
    pub resume: bool,
    /// Print the result as one JSON object on standard output (what was trained, the expected
    /// accuracy, the file), the lines of text on standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: FinalArgs) -> Result<()> {
    let say = |line: String| if a.json { eprintln!("{line}") } else { println!("{line}") };
    let plan = Plan::read(&a.cv)?;
    let data = plan.dataset(a.data.as_deref())?;
    let run = a.run.clone().unwrap_or_else(|| a.cv.join(FINAL));
    let epochs = &plan.expected.selected_epochs;
    say(format!(
        "training on all {} touches for {} epochs, the median of the {} epochs the cross-validation's runs selected ({}), into {}",
        data.len(),
        plan.epochs,
        epochs.len(),
        list(epochs),
        run.display()
    ));
    if let Some((stage, expected, _)) = &plan.pruned {
        say(format!(
            "then pruned as the cross-validation did and fine-tuned {} epochs, the median of its pruned runs' ({})",
            stage.epochs,
            list(&expected.selected_epochs)
        ));
    }
    let bar = progress::bar("final");
    let model = plan.train(&data, &run, a.resume, &bar)?;
    bar.finish();
    let exported = export_onnx(&model, &a.out)?;
    let expected = plan.pruned.as_ref().map_or(&plan.expected, |(_, e, _)| e);
    say(exported);
    say(format!("expected accuracy: {expected}"));
    if a.json {
        let out = serde_json::json!({
            "checkpoint": model.display().to_string(), "onnx": a.out.display().to_string(),
            "touches": data.len(), "epochs": plan.epochs, "expected": expected,
        });
        println!("{out}");
    }
    Ok(())
}

fn list(epochs: &[usize]) -> String {
    epochs.iter().map(|e| e.to_string()).collect::<Vec<_>>().join(", ")
}
