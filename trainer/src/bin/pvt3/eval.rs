//! `pvt3 eval`: a checkpoint's accuracy on a fold (by default its own data's test fold), per
//! class, at each level of the touches' recorded conditions (`evaluate::levels`) and as a
//! confusion matrix (printed, and drawn as SVG), or with `--anytime` against the
//! share of each touch it has seen (printed, and drawn). A cross-validation's directory is
//! eval_cv.rs's: all its runs together.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use pvt3_models::Model;
use pvt3_trainer::anytime::{self, Prefixes};
use pvt3_trainer::checkpoint::{self, Meta};
use pvt3_trainer::data::{windows::Samples, Condition};
use pvt3_trainer::data::{Dataset, TEST_FOLD};
use pvt3_trainer::evaluate::levels::{self, Level};
use pvt3_trainer::evaluate::{evaluate, Evaluation};
use pvt3_trainer::json;
use pvt3_trainer::plot::{self, anytime as anytime_picture, confusion};
use pvt3_trainer::provenance::CalibratedOn;
use pvt3_trainer::run_dir::CV_SUMMARY;

/// Accuracy of a checkpoint on a data set (by default its test fold, or all samples): overall,
/// per class, at each level of the conditions its touches record (speed, force) and as a
/// confusion matrix.
#[derive(clap::Args)]
pub struct EvalArgs {
    /// Checkpoint directory (or a run directory holding model/), or a cross-validation's
    /// directory (with cv.json): then every finished run of it, their answers together.
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
    /// share of the touch read (default: confusion-fold<K>.svg or anytime-fold<K>.svg, -all.svg
    /// with `--fold all`, in the checkpoint's or cross-validation's directory; with --pruned
    /// confusion-pruned-fold<K>.svg and anytime-pruned-fold<K>.svg).
    #[arg(long, value_name = "FILE.svg", alias = "confusion")]
    pub picture: Option<PathBuf>,
    /// Print one JSON object instead of the tables: the accuracy, loss, accuracy per class and
    /// confusion matrix (with --anytime: the curve and the stopping rule).
    #[arg(long)]
    pub json: bool,
    /// With --anytime: also write every sample's class probabilities after each temporal token
    /// to this JSON file (`probabilities[sample][token][class]`, `labels`), to study other
    /// stopping rules (bench/stop_rules.py).
    #[arg(long, value_name = "FILE.json", requires = "anytime")]
    pub answers: Option<PathBuf>,
    /// Of a cross-validation: each run's pruned and fine-tuned model (its pruned/) instead.
    #[arg(long)]
    pub pruned: bool,
}

/// The pictures `pvt3 eval` draws: the confusion matrix, and with --anytime what part of a touch
/// gives.
pub const CONFUSION: &str = "confusion";
pub const ANYTIME: &str = "anytime";

impl EvalArgs {
    /// Where to draw the picture of `what` ([`CONFUSION`], [`ANYTIME`]): --picture, or beside the
    /// checkpoint (`-pruned` in its name with --pruned).
    pub fn picture_of(&self, what: &str) -> PathBuf {
        let what = if self.pruned { format!("{what}-pruned") } else { what.to_string() };
        self.picture.clone().unwrap_or_else(|| self.checkpoint.join(self.fold.picture(&what)))
    }
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
    pub fn picture(self, what: &str) -> String {
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

/// A checkpoint with the data set it is evaluated on and the samples of the fold asked for.
pub struct Loaded {
    pub meta: Meta,
    pub model: Model,
    pub data: Dataset,
    pub indices: Vec<usize>,
}

impl Loaded {
    /// The checkpoint in `path`, on `data` (by default the data set it was trained on, its folds
    /// drawn as in training), the samples of `fold`.
    pub fn new(path: &Path, data: Option<&Path>, fold: Folds) -> Result<Self> {
        let (meta, model, _) = checkpoint::load(path)?;
        let own = PathBuf::from(&meta.provenance.data);
        let data_path = data.unwrap_or(&own);
        if let Some(note) = meta.provenance.split_note() {
            eprintln!("{note}");
        }
        let data = meta.provenance.dataset(data).with_context(|| format!("loading {} for {}", data_path.display(), path.display()))?;
        data.check_fits(&meta.config)?;
        let indices: Vec<usize> = match fold {
            Folds::All => (0..data.len()).collect(),
            Folds::One(k) => (0..data.len()).filter(|&i| data.folds[i] == k).collect(),
        };
        meta.provenance.check_testable_on(&data, &indices)?;
        if indices.is_empty() {
            bail!("fold {fold} of {} holds no samples", data_path.display());
        }
        Ok(Self { meta, model, data, indices })
    }

    pub fn samples(&self) -> Samples<'_> {
        Samples::new(&self.data, &self.indices, &self.meta.normalization)
    }
}

pub fn run(a: EvalArgs) -> Result<()> {
    if a.pruned {
        bail!(
            "--pruned reads a cross-validation's pruned runs, and {} holds no {CV_SUMMARY}: give a pruned/ checkpoint itself",
            a.checkpoint.display()
        );
    }
    let fold = a.fold;
    let run = Loaded::new(&a.checkpoint, a.data.as_deref(), fold)?;
    let samples = run.samples();
    if a.anytime {
        return anytime_report(&run, &samples, &a);
    }
    let e = evaluate(&run.model, &samples)?;
    let title = format!("{}: fold {fold}, {} touches, accuracy {:.4}", a.checkpoint.display(), e.labels.len(), e.accuracy);
    let conditions = by_condition(&run.data.conditions, &run.indices, &e.labels, &e.predictions);
    if a.json {
        return print_json(&run.meta.classes, &e, &conditions, (fold, samples.len()), (&title, &a.picture_of(CONFUSION)));
    }
    let windows = if samples.len() > run.indices.len() { format!(", {} windows", samples.len()) } else { String::new() };
    println!("{} samples (fold {fold}{windows}): accuracy {:.4}, loss {:.4}", run.indices.len(), e.accuracy, e.loss);
    if let (true, Some(test)) = (fold == Folds::One(TEST_FOLD), run.meta.provenance.test_accuracy) {
        println!("(the checkpoint's own record: test accuracy {test:.4})");
    }
    report_levels(&conditions);
    report_classes(&run.meta.classes, &e.labels, &e.predictions, &title, &a.picture_of(CONFUSION))
}

/// `pvt3 eval --json`: the evaluation `e` of `(fold, windows)` as one JSON object, with its
/// accuracy at each level of the touches' `conditions`; its confusion matrix drawn to `picture`
/// under `title` as the table's is.
fn print_json(
    classes: &[String],
    e: &Evaluation,
    conditions: &[(String, Vec<Level>)],
    (fold, windows): (Folds, usize),
    (title, picture): (&str, &Path),
) -> Result<()> {
    let m = confusion::matrix(&e.labels, &e.predictions, classes.len());
    plot::write(picture, &confusion::svg(&m, classes, title)).with_context(|| format!("drawing {}", picture.display()))?;
    let per_class: Vec<_> = classes
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let (n, right) = (m[c].iter().sum::<usize>(), m[c][c]);
            serde_json::json!({"class": name, "samples": n, "accuracy": if n == 0 { None } else { Some(right as f64 / n as f64) }})
        })
        .collect();
    let per_condition: serde_json::Map<String, serde_json::Value> = conditions
        .iter()
        .map(|(name, levels)| {
            let levels = levels.iter().map(|l| serde_json::json!({"level": l.level, "touches": l.touches, "accuracy": l.accuracy()}));
            (name.clone(), levels.collect())
        })
        .collect();
    let out = serde_json::json!({
        "fold": fold.to_string(), "touches": e.labels.len(), "windows": windows, "accuracy": e.accuracy, "loss": e.loss,
        "classes": classes, "per_class": per_class, "per_condition": per_condition, "confusion": m, "picture": picture,
    });
    println!("{out}");
    Ok(())
}

/// Each condition the touches record (`conditions`), its accuracy at each level answered: answer
/// `k` is `predictions[k]` to the data set's touch `touches[k]`, labelled `labels[k]`.
pub fn by_condition(conditions: &[Condition], touches: &[usize], labels: &[u32], predictions: &[u32]) -> Vec<(String, Vec<Level>)> {
    conditions.iter().map(|c| (c.name.clone(), levels::by_level(c, touches, labels, predictions))).collect()
}

/// [`by_condition`] as a table a condition.
pub fn report_levels(conditions: &[(String, Vec<Level>)]) {
    for (name, levels) in conditions {
        println!("{name:<24} {:>8} {:>8}", "touches", "accuracy");
        for l in levels {
            println!("{:<24} {:>8} {:>8.3}", l.level, l.touches, l.accuracy());
        }
        println!();
    }
}

/// Accuracy per class and the confusion matrix of `labels` answered `predictions`, printed; the
/// matrix drawn to `path` under `title`.
pub fn report_classes(classes: &[String], labels: &[u32], predictions: &[u32], title: &str, path: &Path) -> Result<()> {
    println!("{:<24} {:>8} {:>8}", "class", "samples", "accuracy");
    for (c, name) in classes.iter().enumerate() {
        let rows: Vec<usize> = (0..labels.len()).filter(|&r| labels[r] as usize == c).collect();
        if rows.is_empty() {
            continue;
        }
        let ok = rows.iter().filter(|&&r| predictions[r] as usize == c).count();
        println!("{:<24} {:>8} {:>8.3}", name, rows.len(), ok as f64 / rows.len() as f64);
    }
    let m = confusion::matrix(labels, predictions, classes.len());
    println!("\nconfusion matrix (rows: true class, columns: answer)\n{}", confusion::text(&m, classes));
    plot::write(path, &confusion::svg(&m, classes, title)).with_context(|| format!("drawing {}", path.display()))?;
    println!("drew {}", path.display());
    Ok(())
}

/// [`Prefixes::tenths`] as a table.
pub fn print_tenths(curve: &[(f64, usize, f64)]) {
    println!("{:>8} {:>7} {:>9}", "touch", "tokens", "accuracy");
    for (share, k, acc) in curve {
        println!("{:>7.0}% {k:>7} {acc:>9.4}", share * 100.0);
    }
}

/// Draws `prefixes` stopped by `rule` to `path`, titled `heading` and the rule.
pub fn draw_anytime(path: &Path, heading: &str, prefixes: &Prefixes, rule: pvt3_format::StopRule) -> Result<()> {
    let title = format!("{heading}; rule: top probability ≥ {:.4}, {} agreeing", rule.top_probability, rule.agreeing);
    plot::write(path, &anytime_picture::svg(&title, prefixes, rule)).with_context(|| format!("drawing {}", path.display()))
}

/// `pvt3 eval --anytime`: accuracy against the share of the touch, and the stopping rule
/// the checkpoint records, as the exported file carries it (calibrated on its own validation
/// fold, or by `pvt3 cv` on all its runs' validation answers), applied to `samples`.
fn anytime_report(run: &Loaded, samples: &Samples, a: &EvalArgs) -> Result<()> {
    let (meta, fold) = (&run.meta, a.fold);
    let pvt3 = run.model.pvt3("pvt3 eval --anytime")?;
    let answers = anytime::answers(pvt3, samples)?;
    if let Some(path) = &a.answers {
        json::write_json_atomically(path, &answers).with_context(|| format!("writing {}", path.display()))?;
    }
    let prefixes = Prefixes::from(&answers);
    let calibrated = anytime::carried_rule(pvt3, meta, &run.data)?;
    let here = prefixes.stop_by(calibrated.rule);
    let picture = a.picture_of(ANYTIME);
    let rule = calibrated.rule;
    let heading = format!("{}: fold {fold}, {} samples", a.checkpoint.display(), samples.len());
    draw_anytime(&picture, &heading, &prefixes, rule)?;
    let t = prefixes.tokens;
    let curve = prefixes.tenths();
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
    print_tenths(&curve);
    let on = match calibrated.calibrated_on {
        CalibratedOn::ValidationFold => match meta.provenance.val_fold {
            Some(k) => format!("validation fold {k}"),
            None => "the validation fold".into(),
        },
        CalibratedOn::CrossValidation { runs, samples } => {
            format!("the validation answers of the cross-validation's {runs} runs, {samples} samples")
        }
    };
    println!(
        "stopping rule: {} ({on}: accuracy {:.4} against {:.4} for the whole touch, {:.0} % of the touch used)",
        calibrated.rule,
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
        assert_eq!(Folds::One(4).picture(super::CONFUSION), "confusion-fold4.svg");
        assert_eq!(Folds::All.picture(super::ANYTIME), "anytime-all.svg");
    }
}
