//! Choosing the model for a data set: a preset (by name, or the one whose input fits the data), a
//! JSON file, a checkpoint's, or a configuration derived for a new sensor's shape; `--set`
//! overrides and dropout; the class names; the options that only make sense for some models, and
//! those the data decide (`--robust`). What was chosen for the user is said in notes, which the
//! command line prints.

use std::path::{Path, PathBuf};

use pvt3_models::{Architecture, Config};
use pvt3_spec::Sensor;

use crate::checkpoint;
use crate::data::augment::Robust;
use crate::data::{Dataset, TEST_FOLD};
use crate::options::TrainOptions;
use crate::{Error, Result};

/// What the user asked of the model: the network, and where its configuration comes from.
#[derive(Clone, Debug, Default)]
pub struct ModelChoice {
    /// PVT³ or a baseline; a sensor preset is taken in this network's variant.
    pub architecture: Architecture,
    /// A preset by name ([`Config::preset`]); by default the one whose input fits the data.
    pub preset: Option<String>,
    /// A configuration file, or a checkpoint directory ([`resolve_config`]).
    pub config: Option<PathBuf>,
    /// `FIELD=VALUE` overrides of the configuration ([`apply_overrides`]).
    pub overrides: Vec<String>,
    /// Dropout while training, instead of the configuration's.
    pub dropout: Option<f64>,
    /// A file of class names, one per line, instead of the data's.
    pub class_names: Option<PathBuf>,
}

/// The model chosen for a data set.
#[derive(Clone, Debug)]
pub struct Configured {
    pub config: Config,
    pub classes: Vec<String>,
    /// The training options asked, with what the data decide ([`robust`]).
    pub options: TrainOptions,
    /// What was chosen or found for the user, one sentence each.
    pub notes: Vec<String>,
}

/// A preset name, a JSON file, or a checkpoint directory.
pub fn resolve_config(model: &str) -> Result<Config> {
    let path = Path::new(model);
    if path.is_dir() {
        return Ok(checkpoint::load_meta(path)?.1.config);
    }
    if path.is_file() {
        let text = std::fs::read_to_string(path).map_err(Error::io(path))?;
        return serde_json::from_str(&text).map_err(|e| Error::Usage(format!("{model} is not a model configuration: {e}")));
    }
    Ok(Config::preset(model)?)
}

/// The model for `data` as `choice` asks, checked with the training `options` it will train with.
pub fn configure(data: &Dataset, choice: &ModelChoice, options: &TrainOptions) -> Result<Configured> {
    let mut notes = Vec::new();
    if let Some(h) = &data.held_out {
        let held = data.folds.iter().filter(|f| **f == TEST_FOLD).count();
        notes.push(format!(
            "held out {h}: {held} touches test, the other {} train and validate (stratified folds, seed {})",
            data.len() - held,
            h.seed
        ));
    }
    // Touches of unequal length: by default the model reads windows of the shortest that trains
    // or validates.
    if !data.equal_lengths() {
        let (shortest, longest) = (data.window_shape().last().copied().unwrap_or(0), data.max_frames());
        notes.push(format!(
            "touches of {} to {longest} frames: unless the configuration says otherwise (--set frames=N), the model reads windows of {shortest} frames (the shortest touch that trains or validates), one drawn at random from each touch every epoch, and answers for a touch with the mean probabilities of windows every half window",
            data.lengths.iter().min().unwrap_or(&0)
        ));
    }
    let (mut cfg, derived) = base_config(data, choice)?;
    cfg.classes = data.classes();
    cfg = apply_overrides(cfg, &choice.overrides)?;
    if derived {
        notes.push(derived_layout(&cfg, data, &data.window_shape()));
    }
    cfg.dropout = choice.dropout.unwrap_or(cfg.dropout);
    let (cfg, mut options) = robust(data, cfg, options, &choice.overrides, &mut notes)?;
    if let Some(note) = patience(&cfg, &mut options) {
        notes.push(note);
    }
    cfg.validate()?;
    check_options(&cfg, &options)?;
    let classes = class_names(data, choice.class_names.as_deref(), cfg.classes)?;
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
    Ok(Configured { config: cfg, classes, options, notes })
}

/// `--robust` applied to `data`: where asked (`on`), or (`auto`) where the touches that train
/// record a condition (of `pvt3 import --name`) in two levels or more, the model is trained for
/// ways of touching beyond the trained ones. Each channel's readings are scaled by a factor of
/// their own ([`ROBUST_CHANNEL_SCALE`]) and windows are read at other speeds
/// ([`ROBUST_STRETCH`]), and a PVT³ for a sensor of channels (not a camera) whose window holds
/// the bands reads each channel's spectrum beside ([`ROBUST_SPECTRAL_BANDS`]); each only where the
/// user left it unasked (`--aug-stretch`, `--set spectral_bands`). A user who asked for
/// `--extrapolate` or `--aug-channel-scale` trains as asked.
pub fn robust(
    data: &Dataset,
    cfg: Config,
    options: &TrainOptions,
    overrides: &[String],
    notes: &mut Vec<String>,
) -> Result<(Config, TrainOptions)> {
    let mut options = options.clone();
    let augmentation = &mut options.augmentation;
    if augmentation.channel_scale > 0.0 || augmentation.extrapolate > 0.0 {
        return Ok((cfg, options));
    }
    let varied = data.conditions.iter().find_map(|c| {
        let levels = c.distinct_among(|i| data.folds[i] != TEST_FOLD).len();
        (levels > 1).then(|| format!("condition {} in {levels} levels", c.name))
    });
    let why = match (augmentation.robust, varied) {
        (Robust::Off, _) | (Robust::Auto, None) => return Ok((cfg, options)),
        (Robust::On, _) => "--robust on".to_string(),
        (Robust::Auto, Some(varied)) => format!("the touches that train were made in more than one way ({varied})"),
    };
    augmentation.channel_scale = ROBUST_CHANNEL_SCALE;
    let mut chose = vec![format!("--aug-channel-scale {ROBUST_CHANNEL_SCALE}")];
    let mut does = vec!["scales each channel's readings by a factor of its own"];
    if augmentation.stretch == 0.0 {
        augmentation.stretch = ROBUST_STRETCH;
        chose.push(format!("--aug-stretch {ROBUST_STRETCH}"));
        does.push("reads windows at other speeds");
    }
    let fits = cfg.architecture() == Architecture::Pvt3 && cfg.frames / 2 >= ROBUST_SPECTRAL_BANDS;
    // A spectral head over each channel's frames: an array's channels read as channels (frames read
    // as images have the image's head, spectral_bands > 0).
    let cfg = match data.sensor {
        Sensor::Array if fits && cfg.spectral_bands() == 0 && !overridden(overrides, "spectral_bands") => {
            let spectral = format!("spectral_bands={ROBUST_SPECTRAL_BANDS}");
            chose.push(format!("--set {spectral}"));
            does.push("reads each channel's spectrum beside");
            apply_overrides(cfg, &[spectral])?
        }
        Sensor::Array | Sensor::Camera => cfg,
    };
    let last = does.pop().expect("the channel scale is always chosen");
    let does = if does.is_empty() { last.to_string() } else { format!("{} and {last}", does.join(", ")) };
    notes.push(format!(
        "{why}, so a robot will touch in others: training {does} ({}; --robust off trains as asked: docs/robustness.md)",
        chose.join(" ")
    ));
    Ok((cfg, options))
}

/// `--patience` where the user left it unasked: [`FITTED_HEAD_PATIENCE`] for a PVT³ whose spectral
/// head over an image's space is fitted before the first step (a camera's layout), else none.
/// Says so when it sets it.
fn patience(cfg: &Config, options: &mut TrainOptions) -> Option<String> {
    let patience = &mut options.optimization.patience;
    if patience.is_some() || !cfg.spectral_space() {
        return None;
    }
    *patience = Some(FITTED_HEAD_PATIENCE);
    Some(format!(
        "the head over the image's space is fitted before the first step, and validation peaks in the first epochs: a run stops once it has not risen for {FITTED_HEAD_PATIENCE} epochs (--patience {FITTED_HEAD_PATIENCE}; --patience 0 trains every epoch: docs/camera.md)"
    ))
}

/// `--patience` of a model whose spectral head over an image's space is fitted: on PhysiCLeAR its
/// validation accuracy is highest within the first 30 epochs and falls after (a run's longest
/// wait between two rises was 17 epochs), so 20 epochs without a rise end a run where 100
/// would select the same epoch (docs/camera.md, "Memory and time at image size").
pub const FITTED_HEAD_PATIENCE: usize = 20;

/// The spread of `--robust`'s per-channel factors: on FabricSlide the best measured for the other
/// sliding direction, and no worse than none for unseen forces (docs/robustness.md).
pub const ROBUST_CHANNEL_SCALE: f64 = 0.15;
/// `--robust`'s range of speeds (`--aug-stretch`): half to twice the touch's, which carries the
/// spectrum to speeds beyond the trained ones (docs/robustness.md).
pub const ROBUST_STRETCH: f64 = 1.0;
/// `--robust`'s spectral head (`--set spectral_bands`): a texture's vibration does not depend on
/// the direction it is slid in, where the channels' levels do (docs/robustness.md).
pub const ROBUST_SPECTRAL_BANDS: usize = 16;

/// The configuration before overrides: the preset named (in the chosen network's variant), the
/// file given, else the preset whose window is the data's, else one derived for the data's shape
/// (then `true`: [`derived_layout`] says what was derived, once the overrides are applied).
fn base_config(data: &Dataset, choice: &ModelChoice) -> Result<(Config, bool)> {
    let architecture = choice.architecture;
    let preset = |name: &str| match architecture {
        Architecture::Pvt3 => Config::preset(name),
        model => Config::sensor_preset(name, model),
    };
    if let Some(p) = &choice.preset {
        return Ok((preset(p)?, false));
    }
    if let Some(path) = &choice.config {
        return Ok((resolve_config(&path.display().to_string())?, false));
    }
    let window = data.window_shape();
    let fitting = pvt3_spec::config::PRESETS.iter().map(|p| Config::sensor_preset(p, architecture).expect("known preset"));
    if let Some(cfg) = fitting.into_iter().find(|c| c.sample_shape() == window) {
        return Ok((cfg, false));
    }
    let derived = Config::for_sensor(data.sensor, &window)
        .ok_or_else(|| Error::Usage(format!("samples of shape {}: expected [height, width, (channels,) frames]", shape(&window))))?;
    Ok((derived.for_model(architecture), true))
}

/// The note on a layout derived for the samples of `window` of `data`'s sensor
/// (`Config::for_sensor`), as `cfg` has it after the user's overrides; where the set does not
/// record its sensor's kind, how it was taken.
fn derived_layout(cfg: &Config, data: &Dataset, window: &[usize]) -> String {
    let layout = if data.sensor.reads_images(cfg.height, cfg.width) {
        let (ph, pw) = (cfg.patch_height, cfg.patch_width);
        let grid = format!("{} × {}", cfg.height / ph, cfg.width / pw);
        let head = match cfg.spectral_space() {
            true => format!(
                ", a spectral head over the image's space ({} rings, a histogram of {} bins{}{})",
                cfg.spectral_bands(),
                cfg.spectral_histogram(),
                if cfg.spectral_gradients() { " of the values and of their gradients across and down" } else { "" },
                if cfg.spectral_pixels() { " and the pixels, the form chosen on validation" } else { "" }
            ),
            false => String::new(),
        };
        let whose = match data.sensor {
            Sensor::Camera => "a camera's layout",
            Sensor::Array => "an image's layout for a taxel grid this large (docs/results.md, \"A large taxel grid\")",
        };
        format!("{whose}, patches of {ph} × {pw} pixels ({grid} a frame){head}, one token per {} frames", cfg.tubelet)
    } else {
        format!("the BioTac layout, one token per {} frames of all {} values of a frame", cfg.tubelet, cfg.sensor_channels())
    };
    let kind = match data.sensor_recorded {
        true => String::new(),
        false => format!(
            " ({} does not record its sensor's kind: taken as {} by its frames' size; `pvt3 import --sensor` records it)",
            data.path.display(),
            data.sensor
        ),
    };
    format!(
        "no preset takes samples of {}: derived {layout} ({} temporal tokens){kind}; `pvt3 info --json` and --config FILE to choose otherwise",
        shape(window),
        cfg.time_tokens()
    )
}

/// `30 × 40 × 3 × 25`.
fn shape(window: &[usize]) -> String {
    window.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(" × ")
}

/// The options that only some models or values allow.
fn check_options(cfg: &Config, options: &TrainOptions) -> Result<()> {
    options.check()?;
    if options.prefix_training > 0.0 {
        cfg.require_pvt3("--prefix-training")?;
    }
    Ok(())
}

/// The names of `classes` classes: the file's, one per line, else the data's own (as `pvt3
/// import` writes them), else `class_0`, `class_1`, ….
fn class_names(data: &Dataset, file: Option<&Path>, classes: usize) -> Result<Vec<String>> {
    let Some(path) = file else {
        return Ok(match &data.class_names {
            Some(names) if names.len() == classes => names.clone(),
            _ => (0..classes).map(|k| format!("class_{k}")).collect(),
        });
    };
    let text = std::fs::read_to_string(path).map_err(Error::io(path))?;
    let names: Vec<String> = text.lines().map(str::trim).filter(|l| !l.is_empty()).map(String::from).collect();
    if names.len() != classes {
        return Err(Error::Usage(format!("{} names {} classes, the data has {classes}", path.display(), names.len())));
    }
    Ok(names)
}

/// `cfg` with each `FIELD=VALUE` of `overrides` set, the value read as JSON (a number, true or
/// false); a field the configuration does not have is refused, naming the ones it has.
pub fn apply_overrides(cfg: Config, overrides: &[String]) -> Result<Config> {
    let usage = |s: String| Error::Usage(s);
    let mut value = serde_json::to_value(&cfg).map_err(|e| usage(format!("the configuration does not serialise: {e}")))?;
    // A file leaves some of the network's fields out while they are at their defaults.
    let fields = value.as_object_mut().expect("a config is a JSON object");
    for field in cfg.network.entries() {
        fields.insert(field.name.into(), field.value);
    }
    for o in overrides {
        let (key, raw) = field_and_value(o)?;
        let fields = value.as_object_mut().expect("a config is a JSON object");
        if !fields.contains_key(key) {
            let mut known: Vec<&str> = fields.keys().map(String::as_str).collect();
            known.sort_unstable();
            return Err(usage(format!("--set {o}: unknown field `{key}`; a {} model's fields are {known:?}", cfg.architecture())));
        }
        let parsed = serde_json::from_str(raw).map_err(|_| usage(format!("--set {o}: `{raw}` is not a number, true or false")))?;
        fields.insert(key.to_string(), parsed);
    }
    serde_json::from_value(value).map_err(|e| usage(format!("the overridden configuration does not parse: {e}")))
}

/// Whether `overrides` (`--set FIELD=VALUE`, as [`apply_overrides`] reads them) set `field`.
fn overridden(overrides: &[String], field: &str) -> bool {
    overrides.iter().any(|o| field_and_value(o).is_ok_and(|(key, _)| key == field))
}

/// An override's field and its value, as written.
fn field_and_value(o: &str) -> Result<(&str, &str)> {
    o.split_once('=').ok_or_else(|| Error::Usage(format!("--set {o}: expected FIELD=VALUE")))
}

#[cfg(test)]
mod tests {
    use pvt3_models::Config;

    use crate::data::augment::Robust;
    use crate::data::{Condition, Dataset, TEST_FOLD};
    use crate::options::TrainOptions;

    #[test]
    fn robust_trains_for_other_touches_where_the_touches_that_train_vary_in_a_recorded_condition() {
        // Four touches: two forces among those that train, a third only in the test fold.
        let mut data = Dataset::in_memory(vec![0.0f32; 4 * 64], vec![1, 1, 64], vec![0, 1, 0, 1]);
        let cfg = Config { frames: 64, ..Config::biotac20() };
        let asked = TrainOptions::default();
        assert_eq!(asked.augmentation.robust, Robust::Auto);
        let robust = |data: &Dataset, asked: &TrainOptions, overrides: &[String]| {
            let mut notes = Vec::new();
            let (cfg, o) = super::robust(data, cfg.clone(), asked, overrides, &mut notes).unwrap();
            let o = o.augmentation;
            ((o.channel_scale, o.extrapolate, o.stretch, cfg.spectral_bands()), notes)
        };
        // No conditions recorded: as asked, and nothing said.
        assert_eq!(robust(&data, &asked, &[]), ((0.0, 0.0, 0.0, 0), vec![]));
        let forces = |l: [&str; 4]| vec![Condition { name: "force".into(), levels: l.map(String::from).to_vec() }];
        data.folds = vec![0, 1, 2, TEST_FOLD];
        // One level among the touches that train: the test touch's other level decides nothing.
        data.conditions = forces(["120", "120", "120", "250"]);
        assert_eq!(robust(&data, &asked, &[]).0, (0.0, 0.0, 0.0, 0));
        data.conditions = forces(["120", "150", "120", "250"]);
        let (on, notes) = robust(&data, &asked, &[]);
        let all = (super::ROBUST_CHANNEL_SCALE, 0.0, super::ROBUST_STRETCH, super::ROBUST_SPECTRAL_BANDS);
        assert_eq!(on, all);
        assert!(notes[0].contains("condition force in 2 levels") && notes[0].contains("--robust off"), "{notes:?}");
        assert!(notes[0].contains("(--aug-channel-scale 0.15 --aug-stretch 1 --set spectral_bands=16;"), "{notes:?}");
        assert!(notes[0].contains("other speeds and reads each channel's spectrum beside ("), "{notes:?}");
        // What the user asked is kept, and the note names only what training does: a stretch of
        // their own, the spectral head off.
        let mut stretch = asked.clone();
        stretch.augmentation.stretch = 0.5;
        let (kept, notes) = robust(&data, &stretch, &["spectral_bands=0".into()]);
        assert_eq!(kept, (super::ROBUST_CHANNEL_SCALE, 0.0, 0.5, 0));
        assert!(
            notes[0].contains("training scales each channel's readings by a factor of its own (--aug-channel-scale 0.15;"),
            "{notes:?}"
        );
        // A camera's frames: no spectral head, however long the window.
        let mut notes = Vec::new();
        let camera = Config { frames: 64, ..Config::gelsight() };
        let camera_data = Dataset { sensor: pvt3_spec::Sensor::Camera, ..data.clone() };
        assert_eq!(super::robust(&camera_data, camera, &asked, &[], &mut notes).unwrap().0.spectral_bands(), 0);
        // A window too short for the bands: no spectral head.
        let short = Dataset::in_memory(vec![0.0f32; 4 * 16], vec![1, 1, 16], vec![0, 1, 0, 1]);
        let short = Dataset { conditions: data.conditions.clone(), folds: data.folds.clone(), ..short };
        let mut notes = Vec::new();
        let (c, _) = super::robust(&short, Config { frames: 16, ..Config::biotac20() }, &asked, &[], &mut notes).unwrap();
        assert_eq!(c.spectral_bands(), 0);
        // Off, or a robustness of the user's own asked: as asked.
        let mut off = asked.clone();
        off.augmentation.robust = Robust::Off;
        assert_eq!(robust(&data, &off, &[]), ((0.0, 0.0, 0.0, 0), vec![]));
        let mut own = asked.clone();
        own.augmentation.extrapolate = 0.5;
        assert_eq!(robust(&data, &own, &[]), ((0.0, 0.5, 0.0, 0), vec![]));
        let mut own = asked.clone();
        own.augmentation.channel_scale = 0.05;
        assert_eq!(robust(&data, &own, &[]), ((0.05, 0.0, 0.0, 0), vec![]));
        // On: whatever the data record.
        data.conditions.clear();
        let mut on = asked;
        on.augmentation.robust = Robust::On;
        assert_eq!(robust(&data, &on, &[]).0, all);
    }

    #[test]
    fn a_derived_layout_is_told_as_the_overrides_leave_it() {
        // Four touches of 30 × 40 RGB, 25 frames: a camera's layout is derived.
        let data = Dataset::in_memory(vec![0.0f32; 4 * 30 * 40 * 3 * 25], vec![30, 40, 3, 25], vec![0, 1, 0, 1]);
        let note = |overrides: &[&str]| {
            let choice = super::ModelChoice { overrides: overrides.iter().map(|o| o.to_string()).collect(), ..Default::default() };
            let configured = super::configure(&data, &choice, &TrainOptions::default()).unwrap();
            configured.notes.into_iter().find(|n| n.starts_with("no preset takes samples of 30 × 40 × 3 × 25")).unwrap()
        };
        let default = note(&[]);
        assert!(default.contains("patches of 10 × 10 pixels (3 × 4 a frame), a spectral head over the image's space"), "{default}");
        // The set does not record its sensor's kind: it is taken by the frames' size, and said so.
        assert!(default.contains("mem does not record its sensor's kind: taken as a camera by its frames' size"), "{default}");
        assert!(default.contains("one token per 1 frames (25 temporal tokens)"), "{default}");
        let asked = note(&["tubelet=5", "spectral_histogram=0", "spectral_bands=0"]);
        assert!(asked.contains("(3 × 4 a frame), one token per 5 frames (5 temporal tokens)"), "{asked}");
    }

    #[test]
    fn a_model_with_a_fitted_head_over_the_image_stops_when_validation_stalls_unless_asked() {
        let data = Dataset::in_memory(vec![0.0f32; 4 * 30 * 40 * 3 * 25], vec![30, 40, 3, 25], vec![0, 1, 0, 1]);
        let patience = |overrides: &[&str], asked: Option<usize>| {
            let choice = super::ModelChoice { overrides: overrides.iter().map(|o| o.to_string()).collect(), ..Default::default() };
            let mut options = TrainOptions::default();
            options.optimization.patience = asked;
            let configured = super::configure(&data, &choice, &options).unwrap();
            let said = configured.notes.iter().any(|n| n.contains("--patience 20; --patience 0 trains every epoch"));
            (configured.options.optimization.patience, said)
        };
        assert_eq!(patience(&[], None), (Some(super::FITTED_HEAD_PATIENCE), true));
        // Asked, even as 0: as asked, and nothing said.
        assert_eq!(patience(&[], Some(0)), (Some(0), false));
        assert_eq!(patience(&[], Some(5)), (Some(5), false));
        // No head over the image: every epoch.
        assert_eq!(patience(&["spectral_histogram=0", "spectral_bands=0"], None), (None, false));
        let icub = Dataset::in_memory(vec![0.0f32; 4 * 6 * 10 * 75], vec![6, 10, 75], vec![0, 1, 0, 1]);
        let configured = super::configure(&icub, &super::ModelChoice::default(), &TrainOptions::default()).unwrap();
        assert_eq!(configured.options.optimization.patience, None);
    }

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
        let set = super::apply_overrides(biotac.clone(), &["spectral_bands=16".into(), "patch_selection=true".into()]).unwrap();
        assert_eq!((set.spectral_bands(), set.spectral_levels(), set.patch_selection()), (16, true, true));
        let set = super::apply_overrides(biotac.clone(), &["spectral_bands=16".into(), "spectral_levels=false".into()]).unwrap();
        assert_eq!((set.spectral_bands(), set.spectral_levels()), (16, false));
        let err = super::apply_overrides(biotac, &["latent=20".into()]).unwrap_err().to_string();
        assert!(err.contains("unknown field `latent`; a pvt3 model's fields"), "{err}");
    }

    /// `--set` takes every field a network declares (`network_fields!`), at its default too, with
    /// no list of its own to keep.
    #[test]
    fn set_takes_every_declared_field() {
        for name in ["icub20", "vit-icub20", "raec-icub20"] {
            let cfg = Config::preset(name).unwrap();
            for field in cfg.network.entries() {
                let set = super::apply_overrides(cfg.clone(), &[format!("{}={}", field.name, field.value)]);
                assert_eq!(set.unwrap(), cfg, "{name}: --set {}={}", field.name, field.value);
            }
        }
    }
}
