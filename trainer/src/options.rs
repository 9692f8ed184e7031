//! The training hyper-parameters, as the command line takes them and as a run's provenance
//! records them (`provenance::Provenance`), so that `--resume` continues with the same ones.
//! They come in groups by concern, each passed where it is used: the optimiser's
//! ([`Optimization`]), the augmentation's ([`Augmentation`]), the selection masks' and pruning's
//! ([`Pruning`], [`HeldZeros`]), distillation's ([`Distillation`]) and joint learning's
//! ([`Joint`]). Each group is flattened into one JSON object, its fields in their order of old,
//! so a provenance reads and writes as it did before the groups.

use serde::{Deserialize, Serialize};

use crate::data::augment::Augmentation;

// Each group's heading in `--help` (per argument: a heading set for a flattened group would hold
// for every argument after it too).
const OPTIMISATION: &str = "Optimisation";
const PRUNING: &str = "Selection masks and pruning";
const DISTILLATION: &str = "Distillation";

/// Training hyper-parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct TrainOptions {
    #[command(flatten)]
    #[serde(flatten)]
    pub optimization: Optimization,
    #[command(flatten)]
    #[serde(flatten)]
    pub augmentation: Augmentation,
    /// Weight averaging: evaluate, select and checkpoint an exponential moving average of the
    /// weights with this decay per step (e.g. 0.995: about the last 200 steps), not the raw
    /// weights. 0 turns it off.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub ema: f64,
    /// Seed of initialisation, shuffling, dropout and augmentation: a fixed seed gives the same run.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    #[serde(flatten)]
    pub pruning: Pruning,
    /// Training for provisional answers (PVT³ only): with this probability a batch sees only its
    /// first k temporal tokens, k uniform from 1 to all, so that the touch so far classifies
    /// well (`Session::peek`, `pvt3 eval --anytime`). 0 trains on whole windows only.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub prefix_training: f64,
    #[command(flatten)]
    #[serde(flatten)]
    pub distillation: Distillation,
    /// Joint learning with a second sensor (`--joint`): what the run was trained beside.
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<Joint>,
    /// A final model's camera head: the form its cross-validation's runs chose on their
    /// validation folds (`crate::final_model`), which a run without one cannot choose.
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_head: Option<crate::spectrum_fit::form::Choice>,
    /// What fine-tuning after pruning holds at zero.
    #[arg(skip)]
    #[serde(flatten)]
    pub held: HeldZeros,
}

/// The optimiser's options: AdamW's schedule and steps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct Optimization {
    /// Passes over the training split.
    #[arg(long, default_value_t = 100, help_heading = OPTIMISATION)]
    pub epochs: usize,
    /// Training windows per optimiser step.
    #[arg(long, default_value_t = 32, help_heading = OPTIMISATION)]
    pub batch_size: usize,
    /// Peak learning rate (reached after the warm-up, then cosine decay to `--lr-floor` of it).
    #[arg(long, default_value_t = 2e-3, help_heading = OPTIMISATION)]
    pub lr: f64,
    /// Where the cosine decay ends, as a share of the peak learning rate: 1 holds the rate
    /// constant after the warm-up (the RAEC authors' schedule: Adam at a constant 5e-4).
    #[arg(long, default_value_t = 0.01, help_heading = OPTIMISATION)]
    #[serde(default = "hundredth")]
    pub lr_floor: f64,
    /// Epochs over which the learning rate rises linearly to its peak.
    #[arg(long, default_value_t = 5, help_heading = OPTIMISATION)]
    pub warmup_epochs: usize,
    /// Decoupled weight decay on weight matrices.
    #[arg(long, default_value_t = 0.05, help_heading = OPTIMISATION)]
    pub weight_decay: f64,
    /// Label smoothing: this share of each target is spread evenly over the classes (0: none).
    #[arg(long, default_value_t = 0.1, help_heading = OPTIMISATION)]
    pub label_smoothing: f64,
    /// Clip the global gradient norm to this (0: no clipping).
    #[arg(long, default_value_t = 1.0, help_heading = OPTIMISATION)]
    pub clip_grad: f64,
    /// Stop a run once its validation accuracy has not risen (nor, at equal accuracy, its loss
    /// fallen) for this many epochs; the best epoch is kept as always. 0 trains every epoch.
    /// Unless asked: 0, and 20 for a model whose spectral head over an image's space is fitted
    /// before the first step (a camera's layout), whose validation peaks in the first epochs
    /// (docs/camera.md).
    #[arg(long, help_heading = OPTIMISATION)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub patience: Option<usize>,
}

/// The selection masks' training, and random weight pruning as a regulariser.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct Pruning {
    /// L1 penalty on the selection masks (this times the mean |mask| over all entries): drives
    /// unimportant channels and frames towards zero, so that pruning by score is meaningful.
    #[arg(long, default_value_t = 0.0, help_heading = PRUNING)]
    #[serde(default)]
    pub l1: f64,
    /// Learning rate of the selection masks as a multiple of the weights' (AdamW moves every
    /// value at about the learning rate, so masks need a larger one to separate within a run).
    #[arg(long, default_value_t = 1.0, help_heading = PRUNING)]
    #[serde(default = "one")]
    pub mask_lr: f64,
    /// Random unstructured pruning as a regulariser: every step, this share of the entries of
    /// each weight matrix is zeroed for the forward and backward pass; the update applies to all.
    #[arg(long, default_value_t = 0.0, help_heading = PRUNING)]
    #[serde(default)]
    pub random_prune: f64,
}

/// Distillation from an earlier cross-validation's runs (docs/anytime.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct Distillation {
    /// The runs of this earlier cross-validation (`pvt3 cv
    /// --out DIR`) that share this run's training split, every DIR/seed*/foldK/model with K this
    /// run's validation fold, teach it: each batch's loss adds --distill-weight times the
    /// cross-entropy between their averaged class probabilities for the whole window and this
    /// run's answer (to a prefix too, with --prefix-training). What ships is still one model.
    #[arg(long = "distill", id = "distill", value_name = "CV_DIR", help_heading = DISTILLATION)]
    #[serde(default, skip_serializing_if = "Option::is_none", rename = "distill")]
    pub teachers: Option<String>,
    /// With --distill: the weight of the teachers' term in the loss.
    #[arg(long = "distill-weight", id = "distill_weight", value_name = "DISTILL_WEIGHT", default_value_t = 1.0, requires = "distill", help_heading = DISTILLATION)]
    #[serde(default = "one", rename = "distill_weight")]
    pub weight: f64,
}

/// What a fine-tuning run holds at zero, set by the pruning commands, never on the command line.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HeldZeros {
    /// Hold mask entries that are zero at the start at zero (fine-tuning after pruning).
    #[serde(default, rename = "hold_pruned")]
    pub pruned: bool,
    /// Hold weight-matrix entries that are zero at the start at zero (fine-tuning after random
    /// weight pruning, `--prune-weights`).
    #[serde(default, rename = "hold_zero_weights")]
    pub zero_weights: bool,
}

/// Joint learning as Gao et al. train their two sensors' networks (`--joint`): beside this run, a
/// network of another sensor trains on touches of the same classes, and the mean squared error
/// between the two networks' encodings of same-class touches joins the loss.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    /// The other sensor's data set.
    pub partner: String,
    /// Weight of the mean squared error between the encodings.
    pub weight: f64,
    /// Epochs trained before the encodings are pulled together (each network on its own loss).
    pub after_epochs: usize,
    /// The two networks share one temporal transformer (each keeps its embedding, spatial
    /// transformer and head).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub share_temporal: bool,
}

fn one() -> f64 {
    1.0
}

fn hundredth() -> f64 {
    0.01
}

/// A numeric option's range: from `low` (inclusive, or not) to `high` (inclusive, or not).
struct Range {
    low: f64,
    high: f64,
    low_in: bool,
    high_in: bool,
}

/// `[0, 1]`: a probability or a share.
const SHARE: Range = Range { low: 0.0, high: 1.0, low_in: true, high_in: true };
/// `[0, 1)`: a share that may not be all.
const PART: Range = Range { low: 0.0, high: 1.0, low_in: true, high_in: false };
/// `[0, 1000]`: a size, a weight or a spread, 0 turning it off.
const AMOUNT: Range = Range { low: 0.0, high: 1000.0, low_in: true, high_in: true };
/// `(0, 10]`: a learning rate.
const RATE: Range = Range { low: 0.0, high: 10.0, low_in: false, high_in: true };
/// Epochs and batch sizes at most: a million (far beyond what any data set here trains with).
pub const MAX_COUNT: usize = 1_000_000;

impl TrainOptions {
    /// Refuses a numeric option that is not finite or lies outside its range, naming the option
    /// and the range: a learning rate of `nan`, a probability of 2, a batch of 0 would train on
    /// garbage or not at all.
    pub fn check(&self) -> crate::Result<()> {
        let (o, a, p) = (&self.optimization, &self.augmentation, &self.pruning);
        let floats = [
            ("--lr", o.lr, RATE),
            ("--lr-floor", o.lr_floor, SHARE),
            ("--weight-decay", o.weight_decay, AMOUNT),
            ("--label-smoothing", o.label_smoothing, PART),
            ("--clip-grad", o.clip_grad, AMOUNT),
            ("--ema", self.ema, PART),
            ("--prefix-training", self.prefix_training, SHARE),
            ("--aug-gain", a.gain, SHARE),
            ("--aug-noise", a.noise, AMOUNT),
            ("--aug-scale", a.scale, AMOUNT),
            ("--aug-channel-scale", a.channel_scale, AMOUNT),
            ("--aug-vibration", a.vibration, AMOUNT),
            ("--aug-stretch", a.stretch, AMOUNT),
            ("--aug-reverse", a.reverse, SHARE),
            ("--aug-flip", a.flip, SHARE),
            ("--mixup", a.mixup, AMOUNT),
            ("--extrapolate", a.extrapolate, AMOUNT),
            ("--l1", p.l1, AMOUNT),
            ("--mask-lr", p.mask_lr, AMOUNT),
            ("--random-prune", p.random_prune, PART),
            ("--distill-weight", self.distillation.weight, AMOUNT),
        ];
        for (option, value, r) in floats.iter().chain(self.joint.as_ref().map(|j| ("--joint-weight", j.weight, AMOUNT)).iter()) {
            let above = if r.low_in { *value >= r.low } else { *value > r.low };
            let below = if r.high_in { *value <= r.high } else { *value < r.high };
            if !(value.is_finite() && above && below) {
                let (open, close) = (if r.low_in { '[' } else { '(' }, if r.high_in { ']' } else { ')' });
                return Err(crate::Error::Usage(format!("{option} {value}: expected a number in {open}{}, {}{close}", r.low, r.high)));
            }
        }
        for (option, value) in [("--epochs", o.epochs), ("--batch-size", o.batch_size)] {
            if !(1..=MAX_COUNT).contains(&value) {
                return Err(crate::Error::Usage(format!("{option} {value}: expected 1 to {MAX_COUNT}")));
            }
        }
        Ok(())
    }
}

impl Default for TrainOptions {
    /// The command line's defaults.
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Defaults {
            #[command(flatten)]
            options: TrainOptions,
        }
        <Defaults as clap::Parser>::parse_from(["pvt3"]).options
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The groups are flattened: a provenance's options are one object with its keys in the order
    /// runs have always written them, and an older provenance, without the later options, reads
    /// with their defaults.
    #[test]
    fn the_groups_write_and_read_one_flat_object_in_the_recorded_order() {
        let mut options = TrainOptions::default();
        options.distillation.teachers = Some("runs/cv".into());
        options.optimization.patience = Some(20);
        let json = serde_json::to_string(&options).unwrap();
        let order = "epochs batch_size lr lr_floor warmup_epochs weight_decay label_smoothing clip_grad patience aug_gain aug_noise \
            aug_shift aug_scale aug_channel_scale aug_vibration aug_stretch aug_reverse aug_translate aug_flip mixup extrapolate extrapolate_levels robust ema seed l1 \
            mask_lr random_prune prefix_training distill distill_weight hold_pruned hold_zero_weights";
        let positions: Vec<usize> = order.split_whitespace().map(|k| json.find(&format!("\"{k}\":")).expect(k)).collect();
        assert!(positions.windows(2).all(|w| w[0] < w[1]), "{json}");
        assert_eq!(json.matches("\":").count(), positions.len(), "{json}");
        assert_eq!(serde_json::from_str::<TrainOptions>(&json).unwrap(), options);
        let older = r#"{"epochs":3,"batch_size":8,"lr":0.001,"warmup_epochs":1,"weight_decay":0.05,"label_smoothing":0.1,
            "clip_grad":1.0,"aug_gain":0.2,"aug_noise":0.05,"seed":7}"#;
        let read: TrainOptions = serde_json::from_str(older).unwrap();
        assert_eq!((read.optimization.epochs, read.optimization.lr_floor, read.augmentation.gain), (3, 0.01, 0.2));
        assert_eq!((read.pruning.mask_lr, read.distillation.weight, read.held.pruned, read.seed), (1.0, 1.0, false, 7));
        assert_eq!(read.optimization.patience, None);
        // Left out while unasked, so that a run without it records the options it always did.
        assert!(!serde_json::to_string(&TrainOptions::default()).unwrap().contains("patience"));
    }
}
