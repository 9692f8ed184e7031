//! The training hyper-parameters, as the command line takes them and as a run's provenance
//! records them (`provenance::Provenance`), so that `--resume` continues with the same ones.
//! They come in groups by concern, each passed where it is used: the optimiser's
//! ([`Optimization`]), the augmentation's ([`Augmentation`]), the selection masks' and pruning's
//! ([`Pruning`], [`HeldZeros`]), distillation's ([`Distillation`]) and joint learning's
//! ([`Joint`]). Each group is flattened into one JSON object, its fields in their order of old,
//! so a provenance reads and writes as it did before the groups.

use serde::{Deserialize, Serialize};

// Each group's heading in `--help` (per argument: a heading set for a flattened group would hold
// for every argument after it too).
const OPTIMISATION: &str = "Optimisation";
const AUGMENTATION: &str = "Augmentation";
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

/// How training windows are changed as they are batched ([`crate::data::augment`]) and how a
/// batch is blended or pushed beyond its touches in the learner's forward pass.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct Augmentation {
    /// Each training sample is scaled by a random gain in [1 - g, 1 + g].
    #[arg(long = "aug-gain", id = "aug_gain", value_name = "AUG_GAIN", default_value_t = 0.1, help_heading = AUGMENTATION)]
    #[serde(rename = "aug_gain")]
    pub gain: f64,
    /// Gaussian noise of this standard deviation (in normalised units).
    #[arg(long = "aug-noise", id = "aug_noise", value_name = "AUG_NOISE", default_value_t = 0.05, help_heading = AUGMENTATION)]
    #[serde(rename = "aug_noise")]
    pub noise: f64,
    /// Shift each training sample in time by a random offset in [-N, N] frames
    /// (edge frames repeated).
    #[arg(long = "aug-shift", id = "aug_shift", value_name = "AUG_SHIFT", default_value_t = 0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_shift")]
    pub shift: usize,
    /// Multiply each training window's raw readings by a random factor,
    /// log-uniform in [1 / (1 + S), 1 + S], as a lighter or firmer press would (a capacitive
    /// sensor's readings grow about in proportion to the force: docs/robustness.md). E.g. 0.5.
    /// 0 turns it off.
    #[arg(long = "aug-scale", id = "aug_scale", value_name = "AUG_SCALE", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_scale")]
    pub scale: f64,
    /// Multiply each channel's raw readings in a training window by a random
    /// factor of its own, log-uniform in [1 / (1 + S), 1 + S]: the pattern of levels across the
    /// sensor distorted, as a press beyond the trained forces distorts it (docs/robustness.md,
    /// "What force does to the readings"). E.g. 0.05. 0 turns it off.
    #[arg(long = "aug-channel-scale", id = "aug_channel_scale", value_name = "AUG_CHANNEL_SCALE", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_channel_scale")]
    pub channel_scale: f64,
    /// Multiply each training window's variation about its mean (per channel, the
    /// level kept) by a random factor, log-uniform in [1 / (1 + S), 1 + S]: a firmer press makes
    /// a texture's vibration grow faster than the level (docs/robustness.md). E.g. 0.5. 0 turns
    /// it off.
    #[arg(long = "aug-vibration", id = "aug_vibration", value_name = "AUG_VIBRATION", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_vibration")]
    pub vibration: f64,
    /// Read each training window at a random speed, as if the touch had been made
    /// up to 1 + S times faster or slower (log-uniform; resampled, the touch's own frames beyond
    /// the window read where it has them), so that a model meets speeds it was not trained at.
    /// E.g. 1 (half to twice the speed). 0 turns it off.
    #[arg(long = "aug-stretch", id = "aug_stretch", value_name = "AUG_STRETCH", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_stretch")]
    pub stretch: f64,
    /// With probability P, reverse a training window in time, as if the sensor had slid over
    /// the same texture the other way: its ridges pass under the sensor in the reverse order
    /// (the sensor's layout is not mirrored). E.g. 0.5. 0 turns it off.
    #[arg(long = "aug-reverse", id = "aug_reverse", value_name = "AUG_REVERSE", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_reverse")]
    pub reverse: f64,
    /// Move each training window's image by up to N pixels (or taxels) each way, both axes drawn
    /// alone, edge pixels repeated: a camera's touch pressed a little elsewhere on the gel.
    /// 0 turns it off.
    #[arg(long = "aug-translate", id = "aug_translate", value_name = "AUG_TRANSLATE", default_value_t = 0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_translate")]
    pub translate: usize,
    /// With probability P each, mirror a training window's image left to right, and top to
    /// bottom (drawn alone): a texture's surface is as likely the one way round as the other, and
    /// both mirrors together turn it half round. For an image's rows and columns, where the image
    /// looks alike mirrored: not a GelSight's colour image, lit from fixed sides
    /// (docs/camera.md), nor a grid of taxels that is not a picture. E.g. 0.5. 0 turns it off.
    #[arg(long = "aug-flip", id = "aug_flip", value_name = "AUG_FLIP", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_flip")]
    pub flip: f64,
    /// Mixup: blend each training batch with a shuffled copy of itself, λ ~ Beta(α, α) per batch,
    /// and the two labels' losses alike; this is α (e.g. 0.2). 0 turns it off.
    #[arg(long, default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default)]
    pub mixup: f64,
    /// Same-class extrapolation: move each training sample away from another of its class in the
    /// batch, x + λ (x − x_p) with λ ~ U(0, L) per sample, its label kept; this is L (e.g. 1).
    /// The step between two touches of a material continues past them, as a press firmer or
    /// lighter than any trained would: with 1, unseen forces 0.96 instead of 0.86 on FabricSlide
    /// (docs/robustness.md). 0 turns it off.
    #[arg(long, default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default)]
    pub extrapolate: f64,
    /// With --extrapolate: move only each channel's level (its mean over the window) and keep the
    /// window's own variation. Two touches' vibrations are not aligned in time, so their
    /// difference is noise that a whole-window step adds to the sample: on FabricSlide the levels
    /// alone keep unseen firmer presses at 0.95 and a lighter one at 0.95, where whole windows
    /// give 0.96 and 0.88 (docs/robustness.md).
    #[arg(long, requires = "extrapolate", help_heading = AUGMENTATION)]
    #[serde(default)]
    pub extrapolate_levels: bool,
    /// Training for ways of touching beyond the trained ones. `auto`: where the touches that
    /// train were made in more than one recorded way (a condition of `pvt3 import --name`, such
    /// as force or speed, in two levels or more) and neither --aug-channel-scale nor --extrapolate
    /// is asked, train with `--aug-channel-scale 0.15`, `--aug-stretch 1` unless a stretch is
    /// asked, and a PVT³ of a sensor's channels with `--set spectral_bands=16` unless the bands are
    /// set, and say so (what it changes: docs/robustness.md); a set that records no conditions
    /// trains as asked. `on`: as if it recorded them; `off`: as asked.
    #[arg(long, value_enum, default_value_t = Robust::Auto, help_heading = AUGMENTATION)]
    #[serde(default = "Robust::before_auto")]
    pub robust: Robust,
}

/// Whether training prepares a model for ways of touching beyond the trained ones
/// (`configure::robust`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Robust {
    /// Where the data record that the touches were made in more than one way.
    Auto,
    /// Always.
    On,
    /// Never: the augmentations as asked.
    Off,
}

impl Robust {
    /// What a run recorded before `--robust` was: its options as asked.
    fn before_auto() -> Self {
        Robust::Off
    }
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
