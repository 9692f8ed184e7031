//! The RAEC baseline of Gao et al. (IROS 2020), a recurrent autoencoder classifier: an LSTM
//! encoder reads the window frame by frame (after a small convolution and 2 × 2 max-pooling for
//! grids big enough for it; long recordings `tubelet` frames per step), its last hidden state is projected to a latent code, a linear
//! classifier reads the code, and an LSTM decoder reconstructs the (normalised) frames: fed the
//! code at every step, or (`decoder_from_state`, as Gao et al.'s code does it) fed zeros from a
//! hidden state mapped from the code; that decoder mirrors a convolution as theirs does (un-pool
//! to the positions the last frame's pooling chose, a transposed convolution, ReLU). Training
//! minimises cross-entropy plus `reconstruction_weight` × the reconstruction's mean squared error.

use candle_core::{Module, Tensor};
use candle_nn::{linear, Linear, VarBuilder, VarMap};
use pvt3_spec::names;

use crate::dropout::Dropout;
use crate::lstm::Lstm;
use crate::{Config, RaecConfig, Result, Rng};

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
    /// The published decoder's transposed convolution, `[conv_channels, channels, patch_height,
    /// patch_width]`, and its bias (`RaecConfig::decoder_mirrors_conv`).
    deconv: Option<(Tensor, Tensor)>,
    dropout: Dropout,
    cfg: Config,
    raec: RaecConfig,
}

impl Raec {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        cfg.validate()?;
        let Some(&r) = cfg.raec() else {
            return Err(pvt3_spec::Error::Config(format!("the RAEC network: this is a {} model", cfg.architecture())).into());
        };
        let (h, l) = (r.rnn_hidden, r.latent);
        let init = candle_nn::init::DEFAULT_KAIMING_UNIFORM;
        let kernel = |vb: VarBuilder, shape: (usize, usize, usize, usize), bias: usize| -> Result<(Tensor, Tensor)> {
            Ok((vb.get_with_hints(shape, names::WEIGHT, init)?, vb.get_with_hints(bias, names::BIAS, init)?))
        };
        let (k, c) = ((cfg.patch_height, cfg.patch_width), cfg.channels);
        let conv = if r.conv_channels == 0 { None } else { Some(kernel(vb.pp("conv"), (r.conv_channels, c, k.0, k.1), r.conv_channels)?) };
        // PyTorch's ConvTranspose2d weight: [in, out, kh, kw].
        let deconv = if r.decoder_mirrors_conv() { Some(kernel(vb.pp("deconv"), (r.conv_channels, c, k.0, k.1), c)?) } else { None };
        Ok(Self {
            conv,
            encoder: Lstm::new(r.rnn_input(cfg), h, vb.pp("encoder"))?,
            to_latent: linear(h, l, vb.pp("to_latent"))?,
            classifier: linear(l, cfg.classes, vb.pp("classifier"))?,
            decoder: Lstm::new(if r.decoder_from_state { 1 } else { l }, h, vb.pp("decoder"))?,
            to_decoder_state: if r.decoder_from_state { Some(linear(l, h, vb.pp("to_decoder_state"))?) } else { None },
            reconstruct: linear(h, r.decoder_output(cfg), vb.pp("reconstruct"))?,
            deconv,
            dropout: Dropout::new(cfg.dropout),
            cfg: cfg.clone(),
            raec: r,
        })
    }

    pub fn init(cfg: &Config, seed: u64) -> Result<(Self, VarMap)> {
        crate::init::seeded(cfg, seed, Self::new)
    }

    /// `[b, h, w, (c,) t]` → the frames as a sequence of steps, `[b, t / tubelet, tubelet · h · w · c]`
    /// (within a step: frame, then taxel).
    fn frames(&self, x: &Tensor) -> Result<Tensor> {
        let c = &self.cfg;
        let b = c.check_input(x.dims())?;
        let taxels = x.reshape((b, c.height * c.width * c.channels, c.time_tokens(), c.tubelet))?;
        Ok(taxels.permute((0, 2, 3, 1))?.reshape((b, c.time_tokens(), c.step_values()))?)
    }

    /// The encoder's input sequence, `[b, t, rnn_input]`, and, for a decoder that mirrors the
    /// convolution, the last frame's convolution output `[b, conv_channels, ch, cw]` and its
    /// pooling (Gao et al.'s encoder keeps the last frame's pooling indices, and their decoder
    /// un-pools every frame with them).
    fn encoder_input(&self, frames: &Tensor) -> Result<(Tensor, Option<(Tensor, Tensor)>)> {
        let Some((weight, bias)) = &self.conv else {
            return Ok((frames.clone(), None));
        };
        let c = &self.cfg;
        let (b, t, _) = frames.dims3()?;
        let images = frames.reshape((b * t, c.height, c.width, c.channels))?.permute((0, 3, 1, 2))?.contiguous()?;
        let conv = images.conv2d(weight, 0, 1, 1, 1)?.broadcast_add(&bias.reshape((1, (), 1, 1))?)?;
        let pooled = conv.max_pool2d(2)?;
        let last_frame = if self.deconv.is_some() {
            let last = |x: &Tensor| -> Result<Tensor> {
                let (_, k, h, w) = x.dims4()?;
                Ok(x.reshape((b, t, k, h, w))?.narrow(1, t - 1, 1)?.squeeze(1)?.detach())
            };
            Some((last(&conv)?, last(&pooled)?))
        } else {
            None
        };
        Ok((pooled.reshape((b, t, self.raec.rnn_input(c)))?, last_frame))
    }

    /// The published decoder's frames from its linear output `[b · t, rnn_input]`: un-pooled to
    /// where the last frame's pooling (`last_frame`: its convolution output and pooling) took each
    /// maximum, then the transposed convolution and ReLU → `[b · t, step_values]`.
    fn mirror_conv(&self, out: &Tensor, last_frame: &(Tensor, Tensor), steps: usize) -> Result<Tensor> {
        let (weight, bias) = self.deconv.as_ref().expect("a decoder that mirrors the convolution");
        let (conv, pooled) = last_frame;
        let maxima = conv.eq(&unpool(pooled)?)?.to_dtype(conv.dtype())?;
        let (b, k, h, w) = maxima.dims4()?;
        let pooled = out.reshape((b * steps, k, h / 2, w / 2))?;
        let maxima = maxima.unsqueeze(1)?.broadcast_as((b, steps, k, h, w))?.reshape((b * steps, k, h, w))?;
        let unpooled = (unpool(&pooled)? * maxima)?;
        let frames = unpooled.conv_transpose2d(weight, 0, 0, 1, 1)?.broadcast_add(&bias.reshape((1, (), 1, 1))?)?.relu()?;
        // [b · t, channels, height, width] → frame rows of taxels, channels innermost.
        Ok(frames.permute((0, 2, 3, 1))?.reshape((b * steps, self.cfg.step_values()))?)
    }

    /// Logits `[b, classes]` and, when training, the weighted reconstruction loss (to be added
    /// to the classification loss). Pass an `rng` to train (dropout on), `None` to evaluate:
    /// evaluation skips the decoder.
    pub fn forward_with_loss(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<(Tensor, Option<Tensor>)> {
        let frames = self.frames(x)?;
        let (sequence, last_frame) = self.encoder_input(&frames)?;
        let latent = self.to_latent.forward(&self.encoder.last_hidden(&sequence)?)?;
        let training = rng.is_some();
        let logits = self.classifier.forward(&self.dropout.forward(&latent, rng)?)?;
        if !training || self.raec.reconstruction_weight == 0.0 {
            return Ok((logits, None));
        }
        let (b, t, f) = frames.dims3()?;
        let states = match &self.to_decoder_state {
            Some(to_state) => self.decoder.from_state(&to_state.forward(&latent)?, t)?,
            None => self.decoder.repeat_input(&latent, t)?,
        };
        let mut rebuilt = self.reconstruct.forward(&states.reshape((b * t, self.raec.rnn_hidden))?)?;
        if let Some(last_frame) = &last_frame {
            rebuilt = self.mirror_conv(&rebuilt, last_frame, t)?;
        }
        let error = (rebuilt - frames.reshape((b * t, f))?)?.sqr()?.mean_all()?;
        Ok((logits, Some((error * self.raec.reconstruction_weight)?)))
    }

    /// Logits `[b, classes]`.
    pub fn forward(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        Ok(self.forward_with_loss(x, rng)?.0)
    }
}

/// Nearest 2 × up-sampling, `[n, k, h, w]` → `[n, k, 2h, 2w]` (a broadcast, so that its gradient
/// sums each 2 × 2 block): with a mask of the maxima, max-un-pooling.
fn unpool(x: &Tensor) -> Result<Tensor> {
    let (n, k, h, w) = x.dims4()?;
    Ok(x.reshape((n, k, h, 1, w, 1))?.broadcast_as((n, k, h, 2, w, 2))?.reshape((n, k, 2 * h, 2 * w))?)
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use crate::{Config, RaecConfig, Rng};

    /// `cfg` (a RAEC) with the decoder as Gao et al. published it.
    fn published(cfg: Config) -> Config {
        let r = RaecConfig { decoder_from_state: true, ..*cfg.raec().unwrap() };
        Config { network: r.into(), ..cfg }
    }

    #[test]
    fn presets_take_gao_et_al_sizes_and_count_their_parameters() {
        let icub = Config::preset("raec-icub20").unwrap();
        let r = *icub.raec().unwrap();
        assert_eq!((r.conv_channels, icub.patch_height, icub.patch_width), (3, 3, 5));
        // 6 × 10 → 4 × 6 after the 3 × 5 convolution → 2 × 3 after pooling, 3 channels.
        assert_eq!(r.rnn_input(&icub), 18);
        let biotac = Config::preset("raec-biotac20").unwrap();
        let rb = *biotac.raec().unwrap();
        assert_eq!((rb.conv_channels, biotac.time_tokens(), rb.rnn_input(&biotac)), (0, 40, 190));
        let published = published(biotac.clone());
        assert_ne!(published.parameter_count(), biotac.parameter_count());
        // Gao et al.'s iCub decoder: 18 values a step, un-pooled and transposed back to 6 × 10.
        let published_icub = super::tests::published(icub.clone());
        assert_eq!(published_icub.raec().unwrap().decoder_output(&published_icub), 18);
        for cfg in [icub, biotac, published, published_icub] {
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

    /// Gao et al.'s iCub decoder (zeros in, state from the code, un-pooling and a transposed
    /// convolution): the reconstruction loss trains the state map and the transposed convolution.
    #[test]
    fn the_published_decoder_trains_its_state_map() {
        let cfg = published(Config { frames: 8, ..Config::preset("raec-icub20").unwrap() });
        let (raec, varmap) = super::Raec::init(&cfg, 1).unwrap();
        // A positive bias keeps the final ReLU open (this seed's draw, −0.14, closes it for
        // every output, and no gradient passes: a decoder that, like Gao et al.'s, can start dead).
        varmap.data().lock().unwrap()["deconv.bias"].set(&Tensor::new(&[0.5f32], &Device::Cpu).unwrap()).unwrap();
        let x = Tensor::randn(0f32, 1.0, (2, 6, 10, 8), &Device::Cpu).unwrap();
        let loss = raec.forward_with_loss(&x, Some(&mut Rng::new(0))).unwrap().1.unwrap();
        let value = loss.to_scalar::<f32>().unwrap();
        assert!(value > 0.001 && value < 0.1, "{value}");
        let grads = loss.backward().unwrap();
        let data = varmap.data().lock().unwrap();
        for name in ["to_decoder_state.weight", "deconv.weight", "deconv.bias"] {
            let grad = grads.get(data[name].as_tensor()).unwrap_or_else(|| panic!("no gradient for {name}"));
            assert!(grad.abs().unwrap().sum_all().unwrap().to_scalar::<f32>().unwrap() > 0.0, "{name}");
        }
    }

    /// Un-pooling puts each pooled value back where the pooling found it, zeros elsewhere.
    #[test]
    fn unpooling_with_the_maxima_inverts_max_pooling_at_the_maxima() {
        let x = Tensor::new(&[[[[1f32, 5.0, 2.0, 0.0], [3.0, 4.0, 8.0, 1.0]]]], &Device::Cpu).unwrap();
        let pooled = x.max_pool2d(2).unwrap();
        let maxima = x.eq(&super::unpool(&pooled).unwrap()).unwrap().to_dtype(x.dtype()).unwrap();
        let unpooled = (super::unpool(&pooled).unwrap() * maxima).unwrap();
        assert_eq!(unpooled.flatten_all().unwrap().to_vec1::<f32>().unwrap(), [0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 8.0, 0.0]);
    }
}
