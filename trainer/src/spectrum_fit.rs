//! The spectral head's standardisation, fitted to the training set before the first step: each
//! feature's scale and shift make it mean 0 and standard deviation 1 over the training samples,
//! as a linear classifier's inputs are standardised, and they stay so: the optimiser leaves them
//! where they were fitted (`Role::is_fitted`).

use candle_core::{Device, Tensor};
use candle_nn::VarMap;
use pvt3_models::Model;
use pvt3_spec::names;

use crate::data::windows::Samples;
use crate::Result;

/// Sets `spectral.scale` and `spectral.shift` of a PVT³ model with a spectral head from the
/// features of `train`; does nothing for other models.
pub fn fit(model: &Model, varmap: &VarMap, train: &Samples) -> Result<()> {
    let Some((pvt3, spectrum)) = model.pvt3("the spectral head").ok().and_then(|m| Some((m, m.spectrum()?))) else {
        return Ok(());
    };
    let whole = pvt3.frame_weights(pvt3.config().time_tokens())?;
    let rows: Vec<usize> = (0..train.len()).collect();
    let mut features = Vec::with_capacity(train.len());
    for chunk in rows.chunks(256) {
        let (x, _) = train.batch(chunk, |_| {})?;
        features.push(spectrum.features(&x, &whole)?);
    }
    let features = Tensor::cat(&features, 0)?.to_dtype(candle_core::DType::F64)?;
    let mean = features.mean(0)?;
    let std = features.broadcast_sub(&mean)?.sqr()?.mean(0)?.sqrt()?;
    let scale = (std + 1e-6)?.recip()?;
    let shift = (mean.neg()? * &scale)?;
    let vars = varmap.data().lock().expect("the variable map's lock");
    for (name, value) in [(names::spectral(names::SCALE), scale), (names::spectral(names::SHIFT), shift)] {
        let var = vars.get(&name).ok_or(pvt3_spec::Error::MissingTensor { task: "fit the spectral standardisation", name })?;
        var.set(&value.to_dtype(candle_core::DType::F32)?.to_device(&Device::Cpu)?)?;
    }
    Ok(())
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
        super::fit(&model, &varmap, &train).unwrap();
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
