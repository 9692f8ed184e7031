//! What a configuration costs: trainable parameters and multiply-adds per sample, as the
//! exported graph computes them; pruning reports and `pvt3 info` read them.

use super::network::Network;
use super::{spectral_bins, Config};

impl Config {
    /// Trainable parameters of one transformer layer, channel masks included.
    fn layer_parameters(&self) -> usize {
        let (d, i, m) = (self.dim, self.inner_dim(), self.mlp_dim);
        let norms = 2 * 2 * d;
        let attn = d * 3 * i + i + i * d + d;
        let ffn = d * m + m + m + m * d + d;
        norms + attn + ffn
    }

    /// Trainable parameters, channel masks included, the frame-selection mask not.
    pub fn parameter_count(&self) -> usize {
        let (d, n, c) = (self.dim, self.num_patches(), self.classes);
        let head = 2 * d + d * c + c;
        match &self.network {
            Network::Pvt3(_) => {
                let embed = self.patch_dim() * d + d;
                let pos = self.time_tokens() * (n + 1) * d;
                let transformers = (self.space_depth + self.time_depth) * self.layer_parameters() + 2 * 2 * d;
                embed + pos + 2 * d + transformers + head + self.spectral_parameters()
            }
            Network::Vit(_) => {
                let embed = self.patch_dim() * d + d;
                let transformer = (self.space_depth + self.time_depth) * self.layer_parameters() + 2 * d;
                embed + (n + 1) * d + d + transformer + head
            }
            Network::Raec(r) => {
                let (h, l) = (r.rnn_hidden, r.latent);
                let lstm = |input: usize| 4 * h * (input + h) + 2 * 4 * h;
                let conv = r.conv_channels * (self.patch_height * self.patch_width * self.channels + 1);
                let out = r.decoder_output(self);
                // The published decoder: an LSTM of one (zero) input, its state mapped from the
                // code; with a convolution, a transposed one mirrors it.
                let decoder = if r.decoder_from_state { lstm(1) + (l * h + h) } else { lstm(l) };
                let deconv = if r.decoder_mirrors_conv() {
                    r.conv_channels * self.channels * self.patch_height * self.patch_width + self.channels
                } else {
                    0
                };
                conv + lstm(r.rnn_input(self)) + (h * l + l) + (l * c + c) + decoder + (h * out + out) + deconv
            }
        }
    }

    /// PVT³: the spectral head's features, per channel (per colour, for a head over the image's
    /// space) a level (unless `spectral_levels` is off), `spectral_bands` log powers and, over
    /// the image's space, the histogram's bins and the pixels (0 without the head).
    pub fn spectral_features(&self) -> usize {
        let read = if self.spectral_space() { self.channels } else { self.sensor_channels() };
        if self.spectral_bands() == 0 {
            0
        } else {
            read * self.spectral_features_per_channel()
        }
    }

    /// The spectral head's features of one channel (of one colour over the image's space).
    pub fn spectral_features_per_channel(&self) -> usize {
        usize::from(self.spectral_levels()) + self.spectral_bands() + self.spectral_histogram_bins() + self.spectral_pixel_count()
    }

    /// The pixels of one colour a head over the image's space reads (0 unless `spectral_pixels`).
    pub fn spectral_pixel_count(&self) -> usize {
        if self.spectral_pixels() {
            self.height * self.width
        } else {
            0
        }
    }

    /// The bins of every histogram of one colour of a head over the image's space (0 without one).
    pub fn spectral_histogram_bins(&self) -> usize {
        self.spectral_histograms().len() * self.spectral_histogram()
    }

    /// The spectral head's parameters: a scale and a shift per feature, and the linear map.
    fn spectral_parameters(&self) -> usize {
        let f = self.spectral_features();
        if f == 0 {
            0
        } else {
            2 * f + f * self.classes + self.classes
        }
    }

    /// The spectral head's multiply-adds as the exported graph computes them: over an image's
    /// space, the products of its transform; otherwise per channel a
    /// Fourier transform of the frames (counted as a radix-2 FFT's `2 T log2 T`), the band sums of
    /// the squared transform, then the linear map.
    pub fn spectral_mult_adds(&self) -> u64 {
        if self.spectral_bands() == 0 {
            return 0;
        }
        let linear = (self.spectral_features() * self.classes) as u64;
        if self.spectral_space() {
            // Per colour of each frame: the products with the width's and the height's cos | sin
            // matrices, then the band sums of the powers.
            let (h, w, k) = (self.height, self.width, crate::spectrum::space::width_bins(self.width));
            // Each histogram: each interior edge's mean over its values, then the bins' differences.
            let (bins, edges) = (self.spectral_histogram(), self.spectral_histogram().saturating_sub(1));
            let histogram: usize = self.spectral_histograms().iter().map(|k| k.values(h, w) * edges + edges * bins).sum();
            let frame = h * w * 2 * k + 2 * k * h * 2 * h + h * k * self.spectral_bands() + histogram;
            return (self.frames * self.channels * frame) as u64 + linear;
        }
        let t = self.frames as f64;
        let fft = (2.0 * t * t.log2()).ceil() as u64;
        let bands = (2 * spectral_bins(self.frames) * self.spectral_bands()) as u64;
        self.sensor_channels() as u64 * (fft + bands) + linear
    }

    /// Multiply-adds of one transformer layer over `seqs` sequences of `len` tokens.
    fn layer_mult_adds(&self, seqs: usize, len: usize) -> u64 {
        let (d, i, m) = (self.dim, self.inner_dim(), self.mlp_dim);
        let per_token = d * 3 * i + i * d + 2 * d * m;
        let attention = 2 * len * len * i;
        (seqs * (len * per_token + attention)) as u64
    }

    /// Multiply-adds for one sample (matrix products and convolutions only; norms, softmax,
    /// activations and gates are not counted).
    pub fn mult_adds(&self) -> u64 {
        let (n, d, c) = (self.num_patches(), self.dim, self.classes);
        let head = (d * c) as u64;
        match &self.network {
            Network::Pvt3(_) => {
                let t = self.time_tokens();
                let embed = (t * n * self.patch_dim() * d) as u64;
                let space = self.space_depth as u64 * self.layer_mult_adds(t, n + 1);
                let time = self.time_depth as u64 * self.layer_mult_adds(1, t + 1);
                embed + space + time + head + self.spectral_mult_adds()
            }
            Network::Vit(_) => {
                let embed = (n * self.patch_dim() * d) as u64;
                embed + (self.space_depth + self.time_depth) as u64 * self.layer_mult_adds(1, n + 1) + head
            }
            Network::Raec(r) => {
                let (h, l, t) = (r.rnn_hidden, r.latent, self.time_tokens());
                let (ch, cw) = r.conv_output(self);
                let conv = if r.conv_channels == 0 { 0 } else { ch * cw * r.conv_channels * self.patch_height * self.patch_width };
                let lstm = |input: usize| 4 * h * (input + h);
                // The decoder's input is the same at every step (the latent code, projected once)
                // or zeros (the published decoder, whose state is mapped from the code once).
                // A transposed convolution costs what the convolution it mirrors does.
                let deconv = if r.decoder_mirrors_conv() { conv * self.channels } else { 0 };
                let per_step = conv * self.channels + lstm(r.rnn_input(self)) + 4 * h * h + h * r.decoder_output(self) + deconv;
                let decoder_once = if r.decoder_from_state { h * l } else { 4 * h * l };
                (t * per_step + decoder_once + h * l + l * c) as u64
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icub20_matches_the_published_parameter_count() {
        let cfg = Config::icub20();
        assert_eq!(cfg.num_patches(), 4);
        assert_eq!(cfg.patch_dim(), 15);
        assert_eq!(cfg.parameter_count(), 64_272);
    }
}
