//! The training hyper-parameters, as the command line takes them and as a run's provenance
//! records them (`checkpoint::Provenance`), so that `--resume` continues with the same ones.

use serde::{Deserialize, Serialize};

/// Training hyper-parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct TrainOptions {
    /// Passes over the training split.
    #[arg(long, default_value_t = 100)]
    pub epochs: usize,
    /// Training windows per optimiser step.
    #[arg(long, default_value_t = 32)]
    pub batch_size: usize,
    /// Peak learning rate (reached after the warm-up, then cosine decay to `--lr-floor` of it).
    #[arg(long, default_value_t = 2e-3)]
    pub lr: f64,
    /// Where the cosine decay ends, as a share of the peak learning rate: 1 holds the rate
    /// constant after the warm-up (the RAEC authors' schedule: Adam at a constant 5e-4).
    #[arg(long, default_value_t = 0.01)]
    #[serde(default = "hundredth")]
    pub lr_floor: f64,
    /// Epochs over which the learning rate rises linearly to its peak.
    #[arg(long, default_value_t = 5)]
    pub warmup_epochs: usize,
    /// Decoupled weight decay on weight matrices.
    #[arg(long, default_value_t = 0.05)]
    pub weight_decay: f64,
    /// Label smoothing: this share of each target is spread evenly over the classes (0: none).
    #[arg(long, default_value_t = 0.1)]
    pub label_smoothing: f64,
    /// Clip the global gradient norm to this (0: no clipping).
    #[arg(long, default_value_t = 1.0)]
    pub clip_grad: f64,
    /// Augmentation: each training sample is scaled by a random gain in [1 - g, 1 + g].
    #[arg(long, default_value_t = 0.1)]
    pub aug_gain: f64,
    /// Augmentation: Gaussian noise of this standard deviation (in normalised units).
    #[arg(long, default_value_t = 0.05)]
    pub aug_noise: f64,
    /// Augmentation: shift each training sample in time by a random offset in [-N, N] frames
    /// (edge frames repeated).
    #[arg(long, default_value_t = 0)]
    #[serde(default)]
    pub aug_shift: usize,
    /// Augmentation: multiply each training window's raw readings by a random factor,
    /// log-uniform in [1 / (1 + S), 1 + S], as a lighter or firmer press would (a capacitive
    /// sensor's readings grow about in proportion to the force: docs/robustness.md). E.g. 0.5.
    /// 0 turns it off.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub aug_scale: f64,
    /// Augmentation: multiply each channel's raw readings in a training window by a random
    /// factor of its own, log-uniform in [1 / (1 + S), 1 + S]: the pattern of levels across the
    /// sensor distorted, as a press beyond the trained forces distorts it (docs/robustness.md,
    /// "What force does to the readings"). E.g. 0.05. 0 turns it off.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub aug_channel_scale: f64,
    /// Augmentation: multiply each training window's variation about its mean (per channel, the
    /// level kept) by a random factor, log-uniform in [1 / (1 + S), 1 + S]: a firmer press makes
    /// a texture's vibration grow faster than the level (docs/robustness.md). E.g. 0.5. 0 turns
    /// it off.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub aug_vibration: f64,
    /// Augmentation: read each training window at a random speed, as if the touch had been made
    /// up to 1 + S times faster or slower (log-uniform; resampled, the touch's own frames beyond
    /// the window read where it has them), so that a model meets speeds it was not trained at.
    /// E.g. 1 (half to twice the speed). 0 turns it off.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub aug_stretch: f64,
    /// Mixup: blend each training batch with a shuffled copy of itself, λ ~ Beta(α, α) per batch,
    /// and the two labels' losses alike; this is α (e.g. 0.2). 0 turns it off.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub mixup: f64,
    /// Same-class extrapolation: move each training sample away from another of its class in the
    /// batch, x + λ (x − x_p) with λ ~ U(0, L) per sample, its label kept; this is L (e.g. 1).
    /// The step between two touches of a material continues past them, as a press firmer or
    /// lighter than any trained would: with 1, unseen forces 0.96 instead of 0.86 on FabricSlide
    /// (docs/robustness.md). 0 turns it off.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub extrapolate: f64,
    /// With --extrapolate: move only each channel's level (its mean over the window) and keep the
    /// window's own variation. Two touches' vibrations are not aligned in time, so their
    /// difference is noise that a whole-window step adds to the sample: on FabricSlide the levels
    /// alone keep unseen firmer presses at 0.95 and a lighter one at 0.95, where whole windows
    /// give 0.96 and 0.88 (docs/robustness.md).
    #[arg(long, requires = "extrapolate")]
    #[serde(default)]
    pub extrapolate_levels: bool,
    /// Weight averaging: evaluate, select and checkpoint an exponential moving average of the
    /// weights with this decay per step (e.g. 0.995: about the last 200 steps), not the raw
    /// weights. 0 turns it off.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub ema: f64,
    /// Seed of initialisation, shuffling, dropout and augmentation: a fixed seed gives the same run.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// L1 penalty on the selection masks (this times the mean |mask| over all entries): drives
    /// unimportant channels and frames towards zero, so that pruning by score is meaningful.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub l1: f64,
    /// Learning rate of the selection masks as a multiple of the weights' (AdamW moves every
    /// value at about the learning rate, so masks need a larger one to separate within a run).
    #[arg(long, default_value_t = 1.0)]
    #[serde(default = "one")]
    pub mask_lr: f64,
    /// Random unstructured pruning as a regulariser: every step, this share of the entries of
    /// each weight matrix is zeroed for the forward and backward pass; the update applies to all.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub random_prune: f64,
    /// Training for provisional answers (PVT³ only): with this probability a batch sees only its
    /// first k temporal tokens, k uniform from 1 to all, so that the touch so far classifies
    /// well (`Session::peek`, `pvt3 eval --anytime`). 0 trains on whole windows only.
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub prefix_training: f64,
    /// Distillation (docs/anytime.md): the runs of this earlier cross-validation (`pvt3 cv
    /// --out DIR`) that share this run's training split, every DIR/seed*/foldK/model with K this
    /// run's validation fold, teach it: each batch's loss adds --distill-weight times the
    /// cross-entropy between their averaged class probabilities for the whole window and this
    /// run's answer (to a prefix too, with --prefix-training). What ships is still one model.
    #[arg(long, value_name = "CV_DIR")]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distill: Option<String>,
    /// With --distill: the weight of the teachers' term in the loss.
    #[arg(long, default_value_t = 1.0, requires = "distill")]
    #[serde(default = "one")]
    pub distill_weight: f64,
    /// Joint learning with a second sensor (`--joint`): what the run was trained beside.
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<Joint>,
    /// Hold mask entries that are zero at the start at zero (fine-tuning after pruning).
    #[arg(skip)]
    #[serde(default)]
    pub hold_pruned: bool,
    /// Hold weight-matrix entries that are zero at the start at zero (fine-tuning after random
    /// weight pruning, `--prune-weights`).
    #[arg(skip)]
    #[serde(default)]
    pub hold_zero_weights: bool,
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
