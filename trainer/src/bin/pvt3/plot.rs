//! `pvt3 plot`: draws again the pictures `train` and `cv` leave, for a run or a whole
//! cross-validation (e.g. one trained before they drew them).

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use pvt3_trainer::cv::{self, CvSummary};
use pvt3_trainer::json::read_json;
use pvt3_trainer::plot::curves;
use pvt3_trainer::run_dir::{CrossValidation, Run, CV_CURVES, CV_PARTNER_CURVES, CV_SUMMARY};

/// Draw the training curves of a run (DIR/curves.svg), or of every run of a cross-validation
/// and the figure of all of them (DIR/cv-curves.svg). The confusion matrix is `pvt3 eval`'s.
#[derive(clap::Args)]
pub struct PlotArgs {
    /// A run directory (with metrics.jsonl) or a cross-validation's (with cv.json).
    pub dir: PathBuf,
}

/// The run directories of the cross-validation in `out` that have metrics, by seed and fold.
fn cv_runs(out: &Path) -> Result<Vec<PathBuf>> {
    Ok(CrossValidation(out).runs()?.into_iter().map(|(_, _, dir)| dir).filter(|dir| Run(dir).metrics().exists()).collect())
}

pub fn run(a: PlotArgs) -> Result<()> {
    let dir = &a.dir;
    if Run(dir).metrics().exists() {
        println!("drew {}", curves::write_run(dir, curves::selected_epoch(dir))?.display());
        return Ok(());
    }
    if !dir.join(CV_SUMMARY).exists() {
        bail!("{} holds neither a run (metrics.jsonl) nor a cross-validation ({CV_SUMMARY})", dir.display());
    }
    let summary: CvSummary = read_json(&dir.join(CV_SUMMARY))?;
    let dirs = cv_runs(dir)?;
    // A joint cross-validation's other sensor: its runs inside each run, its own figure.
    let partners: Vec<PathBuf> = dirs.iter().map(|d| Run(d).partner()).filter(|p| Run(p).metrics().exists()).collect();
    for run in dirs.iter().chain(&partners) {
        curves::write_run(run, curves::selected_epoch(run))?;
    }
    cv::write_figure(dir, &summary, &dirs, CV_CURVES)?;
    println!("drew the curves of {} runs and {}", dirs.len(), dir.join(CV_CURVES).display());
    if let Some(partner) = &summary.partner {
        cv::write_figure(dir, partner, &partners, CV_PARTNER_CURVES)?;
        println!("drew the curves of the other sensor's {} runs and {}", partners.len(), dir.join(CV_PARTNER_CURVES).display());
    }
    Ok(())
}
