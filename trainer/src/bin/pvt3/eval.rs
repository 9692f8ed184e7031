//! `pvt3 eval`: a checkpoint's accuracy on a fold (by default its own data's test fold), per
//! class and as a confusion matrix (printed, and drawn as SVG), or with `--anytime` against the
//! share of each touch it has seen (printed, and drawn).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use pvt3_models::Classifier;
use pvt3_trainer::anytime::{self, CalibratedOn, Stopping};
use pvt3_trainer::checkpoint;
use pvt3_trainer::data::{Dataset, TEST_FOLD};
use pvt3_trainer::evaluate::{evaluate, Samples};
use pvt3_trainer::plot::{self, anytime as anytime_picture, confusion};

/// Accuracy of a checkpoint on a data set (by default its test fold, or all samples).
#[derive(clap::Args)]
pub struct EvalArgs {
    /// Checkpoint directory (or a run directory holding model/).
    pub checkpoint: PathBuf,
    /// The data set; by default the one the checkpoint was trained on.
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Which samples: a fold number, or `all`.
    #[arg(long, default_value = "4")]
    pub fold: Folds,
    /// Provisional answers (PVT³): accuracy from the first 10 %, 20 % … of each touch, and
    /// what the checkpoint's stopping rule (calibrated on its validation fold, or by `pvt3 cv`
    /// on all its runs' validation answers) does here; drawn with where the rule ends touches.
    #[arg(long)]
    pub anytime: bool,
    /// Where to draw the picture: the confusion matrix, or with --anytime accuracy against the
    /// share of the touch read (default: confusion-fold<K>.svg or anytime-fold<K>.svg, with
    /// `--fold all` confusion-all.svg or anytime-all.svg, in the checkpoint's directory).
    #[arg(long, value_name = "FILE.svg", alias = "confusion")]
    pub picture: Option<PathBuf>,
    /// With --anytime: print one JSON object instead of the table.
    #[arg(long, requires = "anytime")]
    pub json: bool,
    /// With --anytime: also write every sample's class probabilities after each temporal token
    /// to this JSON file (`probabilities[sample][token][class]`, `labels`), to study other
    /// stopping rules (bench/stop_rules.py).
    #[arg(long, value_name = "FILE.json", requires = "anytime")]
    pub answers: Option<PathBuf>,
}

/// The samples `pvt3 eval` reads: one fold's, or all.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Folds {
    One(usize),
    All,
}

impl std::str::FromStr for Folds {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "all" => Ok(Folds::All),
            _ => s.parse().map(Folds::One).map_err(|_| format!("`{s}` is neither a fold number nor `all`")),
        }
    }
}

impl Folds {
    /// The picture of `what` for these samples: `confusion-fold4.svg`, `anytime-all.svg`.
    fn picture(self, what: &str) -> String {
        match self {
            Folds::One(k) => format!("{what}-fold{k}.svg"),
            Folds::All => format!("{what}-all.svg"),
        }
    }
}

impl std::fmt::Display for Folds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Folds::One(k) => write!(f, "{k}"),
            Folds::All => f.write_str("all"),
        }
    }
}

pub fn run(a: EvalArgs) -> Result<()> {
    let (checkpoint_path, fold) = (a.checkpoint.as_path(), a.fold);
    let (meta, model, _) = checkpoint::load(checkpoint_path)?;
    let own = PathBuf::from(&meta.provenance.data);
    let data_path = a.data.as_deref().unwrap_or(&own);
    let data = Dataset::load_as_trained(data_path, meta.provenance.seed, meta.provenance.held_out.as_ref())
        .with_context(|| format!("loading {}", data_path.display()))?;
    data.check_fits(&meta.config)?;
    let indices: Vec<usize> = match fold {
        Folds::All => (0..data.len()).collect(),
        Folds::One(k) => (0..data.len()).filter(|&i| data.folds[i] == k).collect(),
    };
    if indices.is_empty() {
        bail!("fold {fold} of {} holds no samples", data_path.display());
    }
    let samples = Samples::new(&data, &indices, &meta.normalization);
    if a.anytime {
        return anytime_report(&meta, &model, &data, &samples, fold, &a);
    }
    let e = evaluate(&model, &samples)?;
    let windows = if samples.len() > indices.len() { format!(", {} windows", samples.len()) } else { String::new() };
    println!("{} samples (fold {fold}{windows}): accuracy {:.4}, loss {:.4}", indices.len(), e.accuracy, e.loss);
    if let (true, Some(test)) = (fold == Folds::One(TEST_FOLD), meta.provenance.test_accuracy) {
        println!("(the checkpoint's own record: test accuracy {test:.4})");
    }
    println!("{:<24} {:>8} {:>8}", "class", "samples", "accuracy");
    for (c, name) in meta.classes.iter().enumerate() {
        let rows: Vec<usize> = (0..e.labels.len()).filter(|&r| e.labels[r] as usize == c).collect();
        if rows.is_empty() {
            continue;
        }
        let ok = rows.iter().filter(|&&r| e.predictions[r] as usize == c).count();
        println!("{:<24} {:>8} {:>8.3}", name, rows.len(), ok as f64 / rows.len() as f64);
    }
    let m = confusion::matrix(&e.labels, &e.predictions, meta.classes.len());
    println!("\nconfusion matrix (rows: true class, columns: answer)\n{}", confusion::text(&m, &meta.classes));
    let path = a.picture.clone().unwrap_or_else(|| a.checkpoint.join(fold.picture("confusion")));
    let title = format!("{}: fold {fold}, {} touches, accuracy {:.4}", a.checkpoint.display(), e.labels.len(), e.accuracy);
    plot::write(&path, &confusion::svg(&m, &meta.classes, &title)).with_context(|| format!("drawing {}", path.display()))?;
    println!("drew {}", path.display());
    Ok(())
}

/// A stopping rule in words.
pub fn describe(s: &Stopping) -> String {
    format!("top probability ≥ {:.4} with {} answers in a row agreeing", s.rule.top_probability, s.rule.agreeing)
}

/// `pvt3 eval --anytime`: accuracy against the share of the touch, and the stopping rule
/// the checkpoint records, as the exported file carries it (calibrated on its own validation
/// fold, or by `pvt3 cv` on all its runs' validation answers), applied to `samples`.
fn anytime_report(meta: &checkpoint::Meta, model: &Classifier, data: &Dataset, samples: &Samples, fold: Folds, a: &EvalArgs) -> Result<()> {
    let pvt3 = model.pvt3("pvt3 eval --anytime")?;
    let answers = anytime::answers(pvt3, samples)?;
    if let Some(path) = &a.answers {
        checkpoint::write_json_atomically(path, &answers).with_context(|| format!("writing {}", path.display()))?;
    }
    let prefixes = anytime::Prefixes::from(&answers);
    // The rule training recorded; a run from before there was one is calibrated here the same way.
    let calibrated = match &meta.provenance.stopping {
        Some(recorded) => recorded.clone(),
        None => {
            let val = Samples::new(data, &data.split(meta.provenance.val_fold)?.val, &meta.normalization);
            anytime::prefixes(pvt3, &val)?.calibrate()
        }
    };
    let here = prefixes.stop_by(calibrated.rule);
    let picture = a.picture.clone().unwrap_or_else(|| a.checkpoint.join(fold.picture("anytime")));
    let rule = calibrated.rule;
    let title = format!(
        "{}: fold {fold}, {} samples; rule: top probability ≥ {:.4}, {} agreeing",
        a.checkpoint.display(),
        samples.len(),
        rule.top_probability,
        rule.agreeing
    );
    plot::write(&picture, &anytime_picture::svg(&title, &prefixes, rule)).with_context(|| format!("drawing {}", picture.display()))?;
    let t = prefixes.tokens;
    let curve: Vec<(f64, usize, f64)> = (1..=10)
        .map(|tenth| {
            let k = (tenth * t).div_ceil(10).max(1);
            (tenth as f64 / 10.0, k, prefixes.accuracy_at(k))
        })
        .collect();
    if a.json {
        let curve: Vec<_> = curve.iter().map(|(share, k, acc)| serde_json::json!({"share": share, "tokens": k, "accuracy": acc})).collect();
        let out = serde_json::json!({
            "samples": samples.len(), "fold": fold.to_string(), "tokens": t, "curve": curve,
            "calibrated": calibrated, "stopping": here, "picture": picture,
        });
        println!("{out}");
        return Ok(());
    }
    println!("provisional answers on {} samples (fold {fold}), {t} temporal tokens per touch", samples.len());
    println!("{:>8} {:>7} {:>9}", "touch", "tokens", "accuracy");
    for (share, k, acc) in &curve {
        println!("{:>7.0}% {k:>7} {acc:>9.4}", share * 100.0);
    }
    let on = match calibrated.calibrated_on {
        CalibratedOn::ValidationFold => format!("validation fold {}", meta.provenance.val_fold),
        CalibratedOn::CrossValidation { runs, samples } => {
            format!("the validation answers of the cross-validation's {runs} runs, {samples} samples")
        }
    };
    println!(
        "stopping rule: {} ({on}: accuracy {:.4} against {:.4} for the whole touch, {:.0} % of the touch used)",
        describe(&calibrated),
        calibrated.accuracy,
        calibrated.full_accuracy,
        calibrated.mean_share * 100.0
    );
    println!(
        "here: accuracy {:.4} against {:.4} for the whole touch, {:.1} % of the touch used on average",
        here.accuracy,
        here.full_accuracy,
        here.mean_share * 100.0
    );
    println!("drew {}", picture.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::Folds;

    #[test]
    fn folds_parse_a_number_or_all_and_name_anything_else() {
        assert_eq!("3".parse(), Ok(Folds::One(3)));
        assert_eq!("all".parse(), Ok(Folds::All));
        assert_eq!(Folds::One(4).to_string(), "4");
        let err = "four".parse::<Folds>().unwrap_err();
        assert!(err.contains("`four` is neither a fold number nor `all`"), "{err}");
        assert_eq!(Folds::One(4).picture("confusion"), "confusion-fold4.svg");
        assert_eq!(Folds::All.picture("anytime"), "anytime-all.svg");
    }
}
