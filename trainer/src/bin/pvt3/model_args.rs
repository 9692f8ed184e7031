//! Which data and which model: the options `train` and `cv` share, and how they become a
//! configuration (a preset, a JSON file, a checkpoint's, or one derived for a new sensor shape)
//! with `--set` overrides.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use pvt3_models::{Architecture, Config};
use pvt3_trainer::checkpoint;
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

fn parse_hold_out(s: &str) -> std::result::Result<(String, Vec<String>), String> {
    let (name, levels) = s.split_once('=').ok_or_else(|| format!("`{s}`: expected NAME=LEVEL,…, e.g. force=210,250"))?;
    let levels: Vec<String> = levels.split(',').map(|l| l.trim().to_string()).filter(|l| !l.is_empty()).collect();
    if name.trim().is_empty() || levels.is_empty() {
        return Err(format!("`{s}`: expected NAME=LEVEL,…, e.g. force=210,250"));
    }
    Ok((name.trim().to_string(), levels))
}

/// A preset name, a JSON file, or a checkpoint directory.
pub fn resolve_config(model: &str) -> Result<Config> {
    let path = Path::new(model);
    if path.is_dir() {
        return Ok(checkpoint::load_meta(path)?.1.config);
    }
    if path.is_file() {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {model}"))?;
        return serde_json::from_str(&text).with_context(|| format!("{model} is not a model configuration"));
    }
    Ok(Config::preset(model)?)
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
    args.hold_out.clone().map(|(condition, levels)| HoldOut { condition, levels, seed: args.options.seed })
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
    let mut notes = Vec::new();
    if let Some(h) = &data.held_out {
        let held = data.folds.iter().filter(|f| **f == pvt3_trainer::data::TEST_FOLD).count();
        notes.push(format!(
            "held out {h}: {held} touches test, the other {} train and validate (stratified folds, seed {})",
            data.len() - held,
            h.seed
        ));
    }
    // `--model vit` turns preset `icub20` into `vit-icub20`.
    let architecture = args.architecture.unwrap_or_default();
    // Touches of unequal length: by default the model reads windows of the shortest that trains
    // or validates.
    let window = data.window_shape();
    if !data.equal_lengths() {
        let (shortest, longest) = (window.last().copied().unwrap_or(0), data.max_frames());
        notes.push(format!(
            "touches of {} to {longest} frames: unless the configuration says otherwise (--set frames=N), the model reads windows of {shortest} frames (the shortest touch that trains or validates), one drawn at random from each touch every epoch, and answers for a touch with the mean probabilities of windows every half window",
            data.lengths.iter().min().unwrap_or(&0)
        ));
    }
    let preset = |name: &str| match architecture {
        Architecture::Pvt3 => Config::preset(name),
        model => Config::preset(&format!("{}-{name}", model.name())),
    };
    let mut cfg = match (&args.preset, &args.config) {
        (Some(p), _) => preset(p)?,
        (None, Some(path)) => resolve_config(&path.display().to_string())?,
        (None, None) => {
            match pvt3_spec::config::PRESETS.iter().map(|p| preset(p).expect("known preset")).find(|c| c.sample_shape() == window) {
                Some(cfg) => cfg,
                None => {
                    let shape = window.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(" × ");
                    let derived = Config::for_sensor(&window)
                        .with_context(|| format!("samples of shape {shape}: expected [height, width, (channels,) frames]"))?;
                    notes.push(format!(
                        "no preset takes samples of {shape}: derived the BioTac layout, one token per {} frames of all {} values of a frame ({} temporal tokens); `pvt3 info --json` and --config FILE to choose otherwise",
                        derived.tubelet,
                        derived.height * derived.width * derived.channels,
                        derived.time_tokens()
                    ));
                    derived.for_model(architecture)
                }
            }
        }
    };
    cfg.classes = data.classes();
    cfg = apply_overrides(cfg, &args.overrides)?;
    cfg.dropout = args.dropout.unwrap_or(cfg.dropout);
    cfg.validate()?;
    let prefix = args.options.prefix_training;
    if !(0.0..=1.0).contains(&prefix) {
        bail!("--prefix-training {prefix}: a probability, from 0 to 1");
    }
    if prefix > 0.0 {
        cfg.require_pvt3("--prefix-training")?;
    }
    let floor = args.options.lr_floor;
    if !(0.0..=1.0).contains(&floor) {
        bail!("--lr-floor {floor}: a share of the peak learning rate, from 0 to 1");
    }
    let classes = match &args.class_names {
        Some(path) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("reading class names from {}", path.display()))?;
            let names: Vec<String> = text.lines().map(str::trim).filter(|l| !l.is_empty()).map(String::from).collect();
            if names.len() != cfg.classes {
                bail!("{} names {} classes, the data has {}", path.display(), names.len(), cfg.classes);
            }
            names
        }
        None => match &data.class_names {
            Some(names) if names.len() == cfg.classes => names.clone(),
            _ => (0..cfg.classes).map(|k| format!("class_{k}")).collect(),
        },
    };
    if data.held_out.is_none() {
        if let Some(seed) = data.fold_seed {
            notes.push(format!("note: {} has no fold array; stratified folds were drawn with seed {seed}", data.path.display()));
        }
    }
    let short = data.short_tests(cfg.frames).len();
    if short > 0 {
        notes.push(format!(
            "{short} test touches are shorter than the window of {} frames: each is answered from the temporal tokens it fills, as a robot's stream answers a touch that ends early",
            cfg.frames
        ));
    }
    let mut options = args.options.clone();
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
    Ok((Prepared { data, config: cfg, classes, options, partner }, notes))
}

fn apply_overrides(cfg: Config, overrides: &[String]) -> Result<Config> {
    let mut value = serde_json::to_value(&cfg)?;
    for o in overrides {
        let (key, raw) = o.split_once('=').with_context(|| format!("--set {o}: expected FIELD=VALUE"))?;
        let fields = value.as_object_mut().expect("a config is a JSON object");
        if !fields.contains_key(key) {
            let mut known: Vec<&str> = fields.keys().map(String::as_str).collect();
            known.sort_unstable();
            bail!("--set {o}: unknown field `{key}`; a {} model's fields are {known:?}", cfg.architecture());
        }
        let parsed = serde_json::from_str(raw).with_context(|| format!("--set {o}: `{raw}` is not a number, true or false"))?;
        fields.insert(key.to_string(), parsed);
    }
    serde_json::from_value(value).context("the overridden configuration does not parse")
}

#[cfg(test)]
mod tests {
    use pvt3_models::Config;

    #[test]
    fn set_reaches_the_network_s_own_fields_and_names_the_unknown() {
        let raec = Config::preset("raec-biotac20").unwrap();
        let set = super::apply_overrides(raec.clone(), &["decoder_from_state=true".into(), "latent=20".into()]).unwrap();
        let r = set.raec().unwrap();
        assert!(r.decoder_from_state);
        assert_eq!(r.latent, 20);
        let err = super::apply_overrides(raec, &["decoder=true".into()]).unwrap_err().to_string();
        assert!(err.contains("unknown field `decoder`") && err.contains("decoder_from_state"), "{err}");
        // PVT³'s own field, and not RAEC's.
        let biotac = Config::preset("biotac20").unwrap();
        let set = super::apply_overrides(biotac.clone(), &["spectral_bands=16".into()]).unwrap();
        assert_eq!(set.spectral_bands(), 16);
        let err = super::apply_overrides(biotac, &["latent=20".into()]).unwrap_err().to_string();
        assert!(err.contains("unknown field `latent`; a pvt3 model's fields"), "{err}");
    }
}
