//! The spectral head's standardisation, fitted to the training set before the first step: each
//! feature's scale and shift make it mean 0 and standard deviation 1 over the training samples,
//! as a linear classifier's inputs are standardised, and they stay so: the optimiser leaves them
//! where they were fitted (`Role::is_fitted`). A head over an image's space has its linear map
//! fitted too, as a logistic regression whose penalty its validation fold chooses ([`logistic`]),
//! and held likewise (`train::learner`): the network trains beside it. Its rows, and those of
//! its standardisation, are every frame of the training windows alone, as a touch is read when
//! its first frame arrives: 25 rows a touch where PhysiCLeAR gives 3 or 4 touches an object
//! (docs/camera.md, "Every frame a row"); the penalty is chosen on whole validation windows.
//! With `spectral_pixels`, the pixels' map is a ridge on the training windows ([`ridge`]), and
//! the validation fold chooses whether the head reads the texture, the pixels or both ([`form`]).
//! Such a head reads a pruned patch's pixels as 0 (`Pvt3::head_frames`), so a run that prunes
//! patches fits it again, to what it then reads (`train`).

use std::path::Path;

use candle_core::{Device, Tensor};
use candle_nn::VarMap;
use ndarray::{Array2, Axis};
use pvt3_models::Model;
use pvt3_spec::names;

use crate::data::windows::Samples;
use crate::json::{read_json, write_json_atomically};
use crate::run_dir::Run;
use crate::Result;

pub mod form;
pub mod logistic;
mod ridge;

pub use form::{Choice, Chosen};

/// The logistic regression's penalties, strongest first: the validation fold takes the first of
/// those it reads best.
const PENALTIES: [f64; 6] = [1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4];

/// The least spread a feature is standardised by: a feature that varies less over the training
/// rows (a histogram's tail bin on a few touches, a constant one) is read at most a thousand times
/// its size. Every form computes a feature (a log power, a level, a bin's share: of order one) to
/// about 1e-7 of its size in f32, so that its rounding stays below 1e-4 once standardised, and
/// the forms agree with the f64 reference; 1/σ of a feature that hardly varies multiplied it by
/// up to 10⁶ (tests/shapes.rs). PhysiCLeAR's features vary by 1.7e-3 at least, unchanged: a floor
/// of 1e-2 read its least varying ones less, and its seed 0 lost 3 points (docs/results.md,
/// "Camera sets beside their anchors").
const STD_FLOOR: f64 = 1e-3;

/// The penalty without a validation fold (a final model's): the one most of PhysiCLeAR's
/// validation folds chose for the fit to every frame, 8 of the headline's 12 (docs/camera.md,
/// "Every frame a row").
const PENALTY: f64 = 3e-3;

/// Sets `spectral.scale` and `spectral.shift` of a PVT³ model with a spectral head from the
/// features of `train`, and for a head over an image's space its linear map: the texture's
/// logistic regression, its penalty chosen on `val` (when not empty), and with
/// `spectral_pixels` the pixels' ridge and the form ([`form`]) that `val` reads best, or without
/// `val` the one `given` (a final model's, from its cross-validation; else the texture's).
/// Returns the form a head over an image's space took; does nothing for other models.
pub fn fit(model: &Model, varmap: &VarMap, train: &Samples, val: &Samples, given: Option<Choice>) -> Result<Option<Chosen>> {
    let Some((pvt3, spectrum)) = model.pvt3("the spectral head").ok().and_then(|m| Some((m, m.spectrum()?))) else {
        return Ok(None);
    };
    let whole = pvt3.frame_weights(pvt3.config().time_tokens())?;
    let (features, labels) = match pvt3.config().spectral_space() {
        true => features_of(train, |x| Ok(spectrum.frame_features(&pvt3.head_frames(x)?, &whole)?))?,
        false => features_of(train, |x| Ok(spectrum.features(x, &whole)?))?,
    };
    let mean = features.mean(0)?;
    let std = features.broadcast_sub(&mean)?.sqr()?.mean(0)?.sqrt()?.maximum(STD_FLOOR)?;
    let scale = (std + 1e-6)?.recip()?;
    let shift = (mean.neg()? * &scale)?;
    let mut fitted = vec![(names::spectral(names::SCALE), scale.clone()), (names::spectral(names::SHIFT), shift.clone())];
    let mut chosen = None;
    if pvt3.config().spectral_space() {
        let standard = |f: &Tensor| -> Result<Array2<f64>> {
            let f = f.broadcast_mul(&scale)?.broadcast_add(&shift)?;
            Ok(Array2::from_shape_vec(f.dims2()?, f.flatten_all()?.to_vec1::<f64>()?).expect("a matrix's values"))
        };
        let windows = |set: &Samples| -> Result<(Array2<f64>, Vec<usize>)> {
            let (f, labels) = features_of(set, |x| Ok(spectrum.features(&pvt3.head_frames(x)?, &whole)?))?;
            Ok((standard(&f)?, labels))
        };
        let columns = Columns::of(pvt3.config());
        let validation = if val.is_empty() { None } else { Some(windows(val)?) };
        let texture = regression(
            &rows_of(&standard(&features)?.select(Axis(1), &columns.texture)),
            &labels,
            pvt3.config().classes,
            validation.as_ref().map(|(v, labels)| (rows_of(&v.select(Axis(1), &columns.texture)), labels.clone())),
        );
        let (choice, ridge) = match columns.pixels.is_empty() {
            true => (Chosen { choice: Choice::TEXTURE, validation: Vec::new() }, None),
            false => pixels(&texture, windows(train)?, validation, &columns, pvt3.config().classes, given),
        };
        let (weight, bias) = form::linear_map(
            choice.choice,
            (&texture.weight, &texture.bias),
            ridge.as_ref(),
            (&columns.texture, &columns.pixels),
            columns.all,
        );
        let classes = pvt3.config().classes;
        let linear = |leaf: &str| names::spectral(&names::join(&[names::LINEAR, leaf]));
        fitted.push((linear(names::WEIGHT), Tensor::from_vec(weight, (classes, columns.all), &Device::Cpu)?));
        fitted.push((linear(names::BIAS), Tensor::from_vec(bias, classes, &Device::Cpu)?));
        chosen = (!columns.pixels.is_empty()).then_some(choice);
    }
    let vars = varmap.data().lock().expect("the variable map's lock");
    for (name, value) in fitted {
        let var = vars.get(&name).ok_or(pvt3_spec::Error::MissingTensor { task: "fit the spectral head", name })?;
        var.set(&value.to_dtype(candle_core::DType::F32)?.to_device(&Device::Cpu)?)?;
    }
    Ok(chosen)
}

/// Records in the run directory `dir` what its camera head's fit chose (`Run::head`).
pub fn record(dir: &Path, chosen: &Chosen) -> Result<()> {
    write_json_atomically(&Run(dir).head(), chosen)
}

/// What the run directory `dir`'s camera head's fit chose ([`record`]); `None` without one.
pub fn recorded(dir: &Path) -> Result<Option<Chosen>> {
    let head = Run(dir).head();
    head.exists().then(|| read_json(&head)).transpose()
}

/// The columns of a head over an image's space's features: the texture's (each colour's level,
/// rings and histograms) and the pixels' (the last `h · w` of each colour's), of `all`.
struct Columns {
    texture: Vec<usize>,
    pixels: Vec<usize>,
    all: usize,
}

impl Columns {
    fn of(cfg: &pvt3_models::Config) -> Self {
        let (per, pixels) = (cfg.spectral_features_per_channel(), cfg.spectral_pixel_count());
        let (texture, pixels) = (0..cfg.spectral_features()).partition(|c| c % per < per - pixels);
        Self { texture, pixels, all: cfg.spectral_features() }
    }
}

/// The pixels' ridge on the training windows `train` and the form (with its strength and scale)
/// that the validation windows read best beside the `texture`'s fit, or without them the one
/// `given` (else the texture's).
fn pixels(
    texture: &logistic::Fit,
    train: (Array2<f64>, Vec<usize>),
    validation: Option<(Array2<f64>, Vec<usize>)>,
    columns: &Columns,
    classes: usize,
    given: Option<Choice>,
) -> (Chosen, Option<ridge::Ridge>) {
    let rows = train.0.select(Axis(1), &columns.pixels);
    let Some((val, val_labels)) = validation else {
        let choice = given.unwrap_or(Choice::TEXTURE);
        let ridge = choice.strength.filter(|_| choice.form.reads_pixels()).map(|s| ridge::fits(&rows, &train.1, classes, &[s]).remove(0));
        return (Chosen { choice, validation: Vec::new() }, ridge);
    };
    let mut ridges = ridge::fits(&rows, &train.1, classes, &form::STRENGTHS);
    let val_pixels = val.select(Axis(1), &columns.pixels);
    let scores: Vec<(f64, Array2<f64>)> = form::STRENGTHS.iter().zip(&ridges).map(|(s, r)| (*s, r.scores(&val_pixels))).collect();
    let chosen = form::choose(&texture.logits(&rows_of(&val.select(Axis(1), &columns.texture))), &scores, &val_labels);
    let ridge = chosen.choice.strength.and_then(|s| form::STRENGTHS.iter().position(|v| *v == s)).map(|i| ridges.swap_remove(i));
    (chosen, ridge)
}

/// A matrix's rows as the logistic regression takes them.
fn rows_of(m: &Array2<f64>) -> Vec<Vec<f64>> {
    m.rows().into_iter().map(|r| r.to_vec()).collect()
}

/// The unstandardised features `[rows, features]` (f64) that `read` gives of `set`'s windows
/// (a row a window, or several: its frames), and each row's label. The windows are read in
/// evaluation batches, whose values are bounded: at a camera's full size, batches of 256
/// windows and the head's transforms of them passed 20 GB (docs/camera.md).
fn features_of(set: &Samples, read: impl Fn(&Tensor) -> Result<Tensor>) -> Result<(Tensor, Vec<usize>)> {
    let rows: Vec<usize> = (0..set.len()).collect();
    let (mut features, mut labels) = (Vec::with_capacity(set.len()), Vec::with_capacity(set.len()));
    for chunk in rows.chunks(crate::evaluate::eval_batch(set)) {
        let (x, y) = set.batch(chunk, |_| {})?;
        let f = read(&x)?;
        let per_window = f.dim(0)? / chunk.len();
        let y = y.to_dtype(candle_core::DType::U32)?.to_vec1::<u32>()?;
        labels.extend(y.into_iter().flat_map(|l| std::iter::repeat_n(l as usize, per_window)));
        features.push(f);
    }
    Ok((Tensor::cat(&features, 0)?.to_dtype(candle_core::DType::F64)?, labels))
}

/// The fit whose penalty of [`PENALTIES`] reads the validation windows best (the strongest among
/// equals), or the fit with [`PENALTY`] without them.
fn regression(rows: &[Vec<f64>], labels: &[usize], classes: usize, validation: Option<(Vec<Vec<f64>>, Vec<usize>)>) -> logistic::Fit {
    let Some((val_rows, val_labels)) = validation else { return logistic::fit(rows, labels, classes, PENALTY) };
    let scored = PENALTIES.iter().map(|p| {
        let fit = logistic::fit(rows, labels, classes, *p);
        let correct = fit.predict(&val_rows).iter().zip(&val_labels).filter(|(a, b)| a == b).count();
        (fit, correct)
    });
    scored.reduce(|best, s| if s.1 > best.1 { s } else { best }).expect("penalties to choose from").0
}

#[cfg(test)]
mod tests {
    use pvt3_models::{Config, Model, Rng};

    use crate::data::{windows::Samples, Dataset};

    /// After fitting, the standardised features of the training samples have mean 0 and
    /// standard deviation 1, feature by feature.
    #[test]
    fn standardises_the_training_features() {
        let cfg = Config { network: pvt3_models::Pvt3Config { spectral_bands: 6, ..Default::default() }.into(), ..Config::icub20() };
        let (model, varmap) = Model::init(&cfg, 3).unwrap();
        let mut rng = Rng::new(4);
        let n = 40;
        let l: usize = cfg.sample_shape().iter().product();
        // Channels of different levels and scales, as raw sensors have.
        let x: Vec<f32> = (0..n * l).map(|i| 5.0 * ((i / 75) % 60) as f32 + (1.0 + (i / 75 % 7) as f32) * rng.normal()).collect();
        let data = Dataset::in_memory(x, cfg.sample_shape(), vec![0; n]);
        let train = Samples::unnormalised(&data);
        let empty = Dataset::in_memory(Vec::new(), cfg.sample_shape(), Vec::new());
        super::fit(&model, &varmap, &train, &Samples::unnormalised(&empty), None).unwrap();
        let spectrum = model.pvt3("test").unwrap().spectrum().unwrap();
        let (x, _) = train.batch(&(0..n).collect::<Vec<_>>(), |_| {}).unwrap();
        let data = varmap.data().lock().unwrap();
        let (scale, shift) = (data["spectral.scale"].as_tensor(), data["spectral.shift"].as_tensor());
        let z = spectrum.features(&x, &[1.0; 75]).unwrap().broadcast_mul(scale).unwrap().broadcast_add(shift).unwrap();
        let mean: Vec<f32> = z.mean(0).unwrap().to_vec1().unwrap();
        let var: Vec<f32> = z.sqr().unwrap().mean(0).unwrap().to_vec1().unwrap();
        assert_eq!(mean.len(), cfg.spectral_features());
        assert!(mean.iter().all(|m| m.abs() < 1e-3), "{mean:?}");
        assert!(var.iter().all(|v| (v - 1.0).abs() < 1e-2), "{var:?}");
    }
}
