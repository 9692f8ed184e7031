//! The RAEC baseline of Gao et al. (IROS 2020), a recurrent autoencoder classifier: an LSTM
//! encoder reads the window frame by frame (after a small convolution and 2 × 2 max-pooling for
//! grids big enough for it; long recordings `tubelet` frames per step), its last hidden state is projected to a latent code, a linear
//! classifier reads the code, and an LSTM decoder reconstructs the (normalised) frames: fed the
//! code at every step, or (`decoder_from_state`, as Gao et al.'s code does it) fed zeros from a
//! hidden state mapped from the code. Training minimises cross-entropy plus
//! `reconstruction_weight` × the reconstruction's mean squared error.

use candle_core::{Module, Tensor};
use candle_nn::{linear, Linear, VarBuilder, VarMap};

use crate::dropout::Dropout;
use crate::lstm::Lstm;
use crate::{Config, Result, Rng};

#[derive(Clone, Debug)]
pub struct Raec {
    /// `[conv_channels, channels, patch_height, patch_width]` and its bias, if there is a
    /// convolution.
    conv: Option<(Tensor, Tensor)>,
    encoder: Lstm,
    to_latent: Linear,
    classifier: Linear,
    decoder: Lstm,
    /// The published decoder's initial hidden state from the code (`decoder_from_state`).
    to_decoder_state: Option<Linear>,
    reconstruct: Linear,
    dropout: Dropout,
    cfg: Config,
}

impl Raec {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        cfg.validate()?;
        let (h, l) = (cfg.rnn_hidden, cfg.latent);
        let conv = if cfg.conv_channels == 0 {
            None
        } else {
            let init = candle_nn::init::DEFAULT_KAIMING_UNIFORM;
            let shape = (cfg.conv_channels, cfg.channels, cfg.patch_height, cfg.patch_width);
            Some((vb.pp("conv").get_with_hints(shape, "weight", init)?, vb.pp("conv").get_with_hints(cfg.conv_channels, "bias", init)?))
        };
        Ok(Self {
            conv,
            encoder: Lstm::new(cfg.rnn_input(), h, vb.pp("encoder"))?,
            to_latent: linear(h, l, vb.pp("to_latent"))?,
            classifier: linear(l, cfg.classes, vb.pp("classifier"))?,
            decoder: Lstm::new(if cfg.decoder_from_state { 1 } else { l }, h, vb.pp("decoder"))?,
            to_decoder_state: if cfg.decoder_from_state { Some(linear(l, h, vb.pp("to_decoder_state"))?) } else { None },
            reconstruct: linear(h, cfg.step_values(), vb.pp("reconstruct"))?,
            dropout: Dropout::new(cfg.dropout),
            cfg: cfg.clone(),
        })
    }

    pub fn init(cfg: &Config, seed: u64) -> Result<(Self, VarMap)> {
        crate::init::seeded(cfg, seed, Self::new)
    }

    /// `[b, h, w, (c,) t]` → the frames as a sequence of steps, `[b, t / tubelet, tubelet · h · w · c]`
    /// (within a step: frame, then taxel).
    fn frames(&self, x: &Tensor) -> Result<Tensor> {
        let c = &self.cfg;
        let b = c.check_input(x)?;
        let taxels = x.reshape((b, c.height * c.width * c.channels, c.time_tokens(), c.tubelet))?;
        Ok(taxels.permute((0, 2, 3, 1))?.reshape((b, c.time_tokens(), c.step_values()))?)
    }

    /// The encoder's input sequence, `[b, t, rnn_input]`.
    fn encoder_input(&self, frames: &Tensor) -> Result<Tensor> {
        let Some((weight, bias)) = &self.conv else {
            return Ok(frames.clone());
        };
        let c = &self.cfg;
        let (b, t, _) = frames.dims3()?;
        let images = frames.reshape((b * t, c.height, c.width, c.channels))?.permute((0, 3, 1, 2))?.contiguous()?;
        let conv = images.conv2d(weight, 0, 1, 1, 1)?.broadcast_add(&bias.reshape((1, (), 1, 1))?)?;
        Ok(conv.max_pool2d(2)?.reshape((b, t, c.rnn_input()))?)
    }

    /// Logits `[b, classes]` and, when training, the weighted reconstruction loss (to be added
    /// to the classification loss). Pass an `rng` to train (dropout on), `None` to evaluate:
    /// evaluation skips the decoder.
    pub fn forward_with_loss(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<(Tensor, Option<Tensor>)> {
        let frames = self.frames(x)?;
        let latent = self.to_latent.forward(&self.encoder.last_hidden(&self.encoder_input(&frames)?)?)?;
        let training = rng.is_some();
        let logits = self.classifier.forward(&self.dropout.forward(&latent, rng)?)?;
        if !training || self.cfg.reconstruction_weight == 0.0 {
            return Ok((logits, None));
        }
        let (b, t, f) = frames.dims3()?;
        let states = match &self.to_decoder_state {
            Some(to_state) => self.decoder.from_state(&to_state.forward(&latent)?, t)?,
            None => self.decoder.repeat_input(&latent, t)?,
        };
        let rebuilt = self.reconstruct.forward(&states.reshape((b * t, self.cfg.rnn_hidden))?)?;
        let error = (rebuilt - frames.reshape((b * t, f))?)?.sqr()?.mean_all()?;
        Ok((logits, Some((error * self.cfg.reconstruction_weight)?)))
    }

    /// Logits `[b, classes]`.
    pub fn forward(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        Ok(self.forward_with_loss(x, rng)?.0)
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use crate::{Config, Rng};

    #[test]
    fn presets_take_gao_et_al_sizes_and_count_their_parameters() {
        let icub = Config::preset("raec-icub20").unwrap();
        assert_eq!((icub.conv_channels, icub.patch_height, icub.patch_width), (3, 3, 5));
        // 6 × 10 → 4 × 6 after the 3 × 5 convolution → 2 × 3 after pooling, 3 channels.
        assert_eq!(icub.rnn_input(), 18);
        let biotac = Config::preset("raec-biotac20").unwrap();
        assert_eq!((biotac.conv_channels, biotac.time_tokens(), biotac.rnn_input()), (0, 40, 190));
        let published = Config { decoder_from_state: true, ..biotac.clone() };
        assert_ne!(published.parameter_count(), biotac.parameter_count());
        for cfg in [icub, biotac, published] {
            let (_, varmap) = super::Raec::init(&cfg, 0).unwrap();
            let counted: usize = varmap.all_vars().iter().map(|v| v.elem_count()).sum();
            assert_eq!(counted, cfg.parameter_count());
        }
    }

    #[test]
    fn training_adds_a_reconstruction_loss_and_evaluation_does_not() {
        let cfg = Config { frames: 8, ..Config::preset("raec-icub20").unwrap() };
        let (raec, _) = super::Raec::init(&cfg, 1).unwrap();
        let x = Tensor::randn(0f32, 1.0, (2, 6, 10, 8), &Device::Cpu).unwrap();
        let (logits, loss) = raec.forward_with_loss(&x, Some(&mut Rng::new(0))).unwrap();
        assert_eq!(logits.dims(), &[2, 20]);
        let loss = loss.unwrap().to_scalar::<f32>().unwrap();
        // Weight 0.01 times a mean squared error of about the data's variance.
        assert!(loss > 0.001 && loss < 0.1, "{loss}");
        assert!(raec.forward_with_loss(&x, None).unwrap().1.is_none());
    }

    /// Gao et al.'s decoder (zeros in, state from the code): the reconstruction loss trains the
    /// map from the code to the decoder's state.
    #[test]
    fn the_published_decoder_trains_its_state_map() {
        let cfg = Config { frames: 8, decoder_from_state: true, ..Config::preset("raec-icub20").unwrap() };
        let (raec, varmap) = super::Raec::init(&cfg, 1).unwrap();
        let x = Tensor::randn(0f32, 1.0, (2, 6, 10, 8), &Device::Cpu).unwrap();
        let loss = raec.forward_with_loss(&x, Some(&mut Rng::new(0))).unwrap().1.unwrap();
        let value = loss.to_scalar::<f32>().unwrap();
        assert!(value > 0.001 && value < 0.1, "{value}");
        let grads = loss.backward().unwrap();
        let data = varmap.data().lock().unwrap();
        let grad = grads.get(data["to_decoder_state.weight"].as_tensor()).expect("a gradient for the state map");
        assert!(grad.abs().unwrap().sum_all().unwrap().to_scalar::<f32>().unwrap() > 0.0);
    }
}
