//! Which data and which model: the options `train` and `cv` share, the data they load and the
//! configuration the library chooses for it ([`pvt3_trainer::configure`]).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use pvt3_models::{Architecture, Config};
use pvt3_trainer::configure::{configure, Configured, ModelChoice};
use pvt3_trainer::data::{Dataset, HoldOut};
use pvt3_trainer::joint::Partner;
use pvt3_trainer::options::{Joint, TrainOptions};
use pvt3_trainer::train::RunSpec;

/// Which data and which model.
#[derive(Clone, clap::Args)]
pub struct ModelArgs {
    /// Data set: an .npz file (x, y, optional fold) or a directory of x.npy, y.npy, fold.npy.
    /// The default is the iCub-20 set shipped in the repository: run from its root, or say which.
    #[arg(long, default_value = SHIPPED_DATA)]
    pub data: PathBuf,
    /// Network: PVT³, or one of the paper's baselines (RAEC as published: add `--lr 5e-4
    /// --weight-decay 0`). Takes the `vit-`/`raec-` variant of the sensor preset; only PVT³ can
    /// be pruned and exported.
    #[arg(long = "model", value_name = "MODEL", value_enum, conflicts_with = "config")]
    pub architecture: Option<Architecture>,
    /// Model preset (icub20, biotac20, gelsight, each also as vit-NAME and raec-NAME); by default
    /// the one whose input fits the data.
    #[arg(long, conflicts_with = "config")]
    pub preset: Option<String>,
    /// Model configuration as JSON (see `pvt3 info --json`).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Override one configuration field, e.g. `--set tubelet=5 --set dim=32` (repeatable).
    #[arg(long = "set", value_name = "FIELD=VALUE")]
    pub overrides: Vec<String>,
    /// Dropout while training (embeddings, attention outputs, feed-forward layers): the
    /// configuration's `dropout` field, 0.1 in every preset.
    #[arg(long)]
    pub dropout: Option<f64>,
    /// Class names, one per line (default: the data's own, as `pvt3 import` writes them, else
    /// class_0, class_1, …).
    #[arg(long)]
    pub class_names: Option<PathBuf>,
    /// Test on touches made in a way the training never saw: the touches whose condition NAME
    /// (as `pvt3 import --name` recorded it) has one of these levels form the test set; the
    /// others train and validate. E.g. `--hold-out force=210,250` or `--hold-out speed=10,-10`.
    #[arg(long, value_name = "NAME=LEVEL,…", value_parser = parse_hold_out)]
    pub hold_out: Option<(String, Vec<String>)>,
    /// With --hold-out, hold out only this class's touches of those levels: the other classes
    /// train and validate at every level. E.g. `--hold-out speed=10,20,50,100,120,150
    /// --hold-out-class Canvas` tests Canvas slid the way it never trained, beside fabrics touched
    /// both ways.
    #[arg(long, value_name = "CLASS", requires = "hold_out")]
    pub hold_out_class: Option<String>,
    /// Joint learning (Gao et al.): train a second PVT³ beside, on this data set of another
    /// sensor touching the same classes (same class order), e.g. `--data data/icub20.npz --joint
    /// data/biotac20.npz`. Each batch pairs every touch with a touch of its class
    /// from the other sensor's training split; after --joint-after epochs the mean squared error
    /// between the two networks' encodings (× --joint-weight) joins their losses. Each network is
    /// selected and tested on its own sensor; the other's run is OUT/…/partner (reported beside,
    /// pruned, exported alone).
    #[arg(long, value_name = "DATA")]
    pub joint: Option<PathBuf>,
    /// Joint learning: weight of the encodings' mean squared error (Gao et al.: 1; 0 trains the
    /// two side by side without pulling them together, e.g. with --joint-share-temporal).
    #[arg(long, default_value_t = 1.0, requires = "joint")]
    pub joint_weight: f64,
    /// Joint learning: epochs each network trains on its own loss before the encodings are pulled
    /// together (Gao et al.: 20).
    #[arg(long, default_value_t = 20, requires = "joint")]
    pub joint_after: usize,
    /// Joint learning: the two networks share one temporal transformer, trained on both sensors'
    /// touches (each keeps its own embedding, spatial transformer and head; each exported file
    /// carries a copy). Needs the same dim, time_depth, heads, dim_head and mlp_dim.
    #[arg(long, requires = "joint")]
    pub joint_share_temporal: bool,
    /// Stop after this many epochs (per run), leaving the work to be continued with --resume.
    #[arg(long)]
    pub pause_after: Option<usize>,
    #[command(flatten)]
    pub options: TrainOptions,
}

/// `--data`'s default: the iCub-20 set in a checkout of pvt3.
const SHIPPED_DATA: &str = "data/icub20.npz";

impl ModelArgs {
    /// What these options ask of the model ([`configure`]).
    fn choice(&self) -> ModelChoice {
        ModelChoice {
            architecture: self.architecture.unwrap_or_default(),
            preset: self.preset.clone(),
            config: self.config.clone(),
            overrides: self.overrides.clone(),
            dropout: self.dropout,
            class_names: self.class_names.clone(),
        }
    }
}

fn parse_hold_out(s: &str) -> std::result::Result<(String, Vec<String>), String> {
    let (name, levels) = s.split_once('=').ok_or_else(|| format!("`{s}`: expected NAME=LEVEL,…, e.g. force=210,250"))?;
    let levels: Vec<String> = levels.split(',').map(|l| l.trim().to_string()).filter(|l| !l.is_empty()).collect();
    if name.trim().is_empty() || levels.is_empty() {
        return Err(format!("`{s}`: expected NAME=LEVEL,…, e.g. force=210,250"));
    }
    Ok((name.trim().to_string(), levels))
}

/// A loaded data set with the model configuration and class names for it, and with `--joint`
/// the other sensor's.
pub struct Prepared {
    pub data: Dataset,
    pub config: Config,
    pub classes: Vec<String>,
    pub options: TrainOptions,
    pub partner: Option<Box<Prepared>>,
}

impl Prepared {
    pub fn spec(&self, args: &ModelArgs, val_fold: usize) -> RunSpec<'_> {
        RunSpec {
            data: &self.data,
            config: self.config.clone(),
            val_fold: Some(val_fold),
            options: self.options.clone(),
            classes: self.classes.clone(),
            pause_after: args.pause_after,
            start: None,
            pruning: None,
            partner: self.partner.as_ref().map(|p| Partner { data: &p.data, config: p.config.clone(), classes: p.classes.clone() }),
        }
    }
}

/// The data set at `path`, its folds drawn with `seed` where the file has none, and `held_out`'s
/// levels held out; a joint partner (`partner`) holds them out where it records that condition.
fn load(path: &Path, seed: u64, held_out: Option<&HoldOut>, partner: bool) -> Result<Dataset> {
    if path == Path::new(SHIPPED_DATA) && !path.exists() {
        bail!(
            "no {SHIPPED_DATA} here: the default data set ships in a checkout of pvt3 (run from its root, {}), or give --data FILE",
            std::env::current_dir().map_or("not this folder".into(), |d| format!("not {}", d.display()))
        );
    }
    let mut data = Dataset::load(path, seed)?;
    if let Some(h) = held_out.filter(|h| !partner || data.conditions.iter().any(|c| c.name == h.condition)) {
        data.hold_out(h)?;
    }
    Ok(data)
}

/// `--hold-out`, its folds drawn with `--seed`.
fn held_out(args: &ModelArgs) -> Option<HoldOut> {
    args.hold_out.clone().map(|(condition, levels)| HoldOut {
        condition,
        levels,
        seed: args.options.seed,
        class: args.hold_out_class.clone(),
    })
}

/// Loads the data set (and a joint partner's) and builds the model configuration for it: one
/// run's, its folds drawn with `--seed`.
pub fn prepare(args: &ModelArgs) -> Result<Prepared> {
    Ok(prepare_seeds(args, &[args.options.seed])?.remove(0))
}

/// A cross-validation's preparation of each seed: where folds are drawn (no fold array, or
/// levels held out), each seed draws its own, so that the seeds' figures vary over splits too,
/// and the window and configuration come from that seed's touches that train. Notes are said
/// for the first seed, and for another where they differ.
pub fn prepare_seeds(args: &ModelArgs, seeds: &[u64]) -> Result<Vec<Prepared>> {
    let h = held_out(args);
    let data = load(&args.data, args.options.seed, h.as_ref(), false)?;
    let partner = args.joint.as_ref().map(|p| load(p, args.options.seed, h.as_ref(), true)).transpose()?;
    let mut said: Option<Vec<String>> = None;
    let mut prepared = Vec::new();
    for &seed in seeds {
        let own = |d: &Dataset| -> Result<Dataset> { Ok(d.reseeded(seed)?.unwrap_or_else(|| d.clone())) };
        let seeded = ModelArgs { options: TrainOptions { seed, ..args.options.clone() }, ..args.clone() };
        let (p, notes) = prepare_with(&seeded, own(&data)?, partner.as_ref().map(own).transpose()?)?;
        for note in notes.iter().filter(|n| said.as_ref().is_none_or(|first| !first.contains(n))) {
            eprintln!("{}{note}", if said.is_some() { format!("seed {seed}: ") } else { String::new() });
        }
        said.get_or_insert(notes);
        prepared.push(p);
    }
    Ok(prepared)
}

/// Builds the model configuration for `data` (and `partner`'s for a joint run), with what to
/// tell the user about the choices made.
fn prepare_with(args: &ModelArgs, data: Dataset, partner: Option<Dataset>) -> Result<(Prepared, Vec<String>)> {
    let Configured { config, classes, mut options, mut notes } = configure(&data, &args.choice(), &args.options)?;
    let partner = match (&args.joint, partner) {
        (Some(path), Some(partner_data)) => {
            // The other sensor: its own data and the network that fits it, the same --set and --dropout.
            let other = ModelArgs { data: path.clone(), preset: None, config: None, class_names: None, joint: None, ..args.clone() };
            let (partner, partner_notes) =
                prepare_with(&other, partner_data, None).with_context(|| format!("--joint {}", path.display()))?;
            notes.extend(partner_notes.into_iter().map(|n| format!("--joint {}: {n}", path.display())));
            options.joint = Some(Joint {
                partner: path.display().to_string(),
                weight: args.joint_weight,
                after_epochs: args.joint_after,
                share_temporal: args.joint_share_temporal,
            });
            Some(Box::new(partner))
        }
        _ => None,
    };
    Ok((Prepared { data, config, classes, options, partner }, notes))
}
