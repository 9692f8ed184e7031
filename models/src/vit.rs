//! The paper's ViT baseline: every frame of a window tiled into one large frame (row-major in
//! time, `VitConfig::tile_rows` frames high), cut into patches, and one transformer over all of them, with a
//! CLS token and one learned position embedding per patch. It sees the same data as PVT³ without
//! the factorisation into space and time, and without frame selection.

use candle_core::Tensor;
use candle_nn::{linear, Init, Linear, Module, VarBuilder, VarMap};

use pvt3_spec::names;

use crate::dropout::Dropout;
use crate::head::Head;
use crate::transformer::Transformer;
use crate::{Config, Result, Rng};

#[derive(Clone, Debug)]
pub struct Vit {
    patch_embed: Linear,
    cls: Tensor,
    pos_embed: Tensor,
    transformer: Transformer,
    head: Head,
    dropout: Dropout,
    cfg: Config,
}

impl Vit {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        cfg.validate()?;
        let (n, d) = (cfg.num_patches(), cfg.dim);
        let small = Init::Randn { mean: 0.0, stdev: 0.02 };
        Ok(Self {
            patch_embed: linear(cfg.patch_dim(), d, vb.pp(names::PATCH_EMBED))?,
            cls: vb.get_with_hints((1, 1, d), names::CLS, small)?,
            pos_embed: vb.get_with_hints((1, n + 1, d), names::POS_EMBED, small)?,
            transformer: Transformer::new(cfg, cfg.space_depth + cfg.time_depth, vb.pp(names::TRANSFORMER))?,
            head: Head::new(cfg, vb.clone())?,
            dropout: Dropout::new(cfg.dropout),
            cfg: cfg.clone(),
        })
    }

    pub fn init(cfg: &Config, seed: u64) -> Result<(Self, VarMap)> {
        crate::init::seeded(cfg, seed, Self::new)
    }

    /// Tiles `[b, h, w, (c,) t]` into one frame and cuts it into `[b, num_patches, patch_dim]`;
    /// patches are row-major over the tiled frame, features `(dy · pw + dx) · c + ci`.
    pub fn patchify(&self, x: &Tensor) -> Result<Tensor> {
        let c = &self.cfg;
        let b = c.check_input(x.dims())?;
        let rows = c.tiled_size().0 / c.height;
        let cols = c.frames / rows;
        let frames = x.reshape(vec![b, c.height, c.width, c.channels, rows, cols])?;
        // → [b, rows, h, cols, w, c]: the tiled frame, (rows · h) × (cols · w) × c.
        let tiled = frames.permute(vec![0, 4, 1, 5, 2, 3])?.contiguous()?;
        let (th, tw) = c.tiled_size();
        let (ph, pw) = (c.patch_height, c.patch_width);
        let grid = tiled.reshape(vec![b, th / ph, ph, tw / pw, pw, c.channels])?;
        let patches = grid.permute(vec![0, 1, 3, 2, 4, 5])?;
        Ok(patches.reshape((b, c.num_patches(), c.patch_dim()))?)
    }

    /// Logits `[b, classes]`. Pass an `rng` to train (dropout on), `None` to evaluate.
    pub fn forward(&self, x: &Tensor, mut rng: Option<&mut Rng>) -> Result<Tensor> {
        let patches = self.patchify(x)?;
        let (b, n, p) = patches.dims3()?;
        let d = self.cfg.dim;
        let embedded = self.patch_embed.forward(&patches.reshape((b * n, p))?)?.reshape((b, n, d))?;
        let cls = self.cls.broadcast_as((b, 1, d))?;
        let tokens = Tensor::cat(&[&cls, &embedded], 1)?.broadcast_add(&self.pos_embed)?;
        let tokens = self.dropout.forward(&tokens, rng.as_deref_mut())?;
        let pooled = self.transformer.forward_cls(&tokens, rng)?;
        Ok(self.head.forward(&pooled)?)
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    use crate::{Architecture, Config};

    /// Tiling and patching put every taxel value exactly once, where the layout says.
    #[test]
    fn patches_of_the_tiled_frame_hold_the_right_taxels() {
        let cfg = Config::icub20().for_model(Architecture::Vit);
        let (vit, _) = super::Vit::init(&cfg, 0).unwrap();
        let n = 6 * 10 * 75;
        let x = Tensor::arange(0f32, n as f32, &Device::Cpu).unwrap().reshape((1, 6, 10, 75)).unwrap();
        let p = vit.patchify(&x).unwrap().squeeze(0).unwrap().to_vec2::<f32>().unwrap();
        assert_eq!((p.len(), p[0].len()), (150, 30));
        // Value at (y, x, t) is (y · 10 + x) · 75 + t. Tiles: 5 frames high, 15 wide; patch
        // (gy, gx) of the 30 × 150 frame covers rows 6 gy.., columns 5 gx..
        for (k, patch) in p.iter().enumerate() {
            let (gy, gx) = (k / 30, k % 30);
            for (j, &v) in patch.iter().enumerate() {
                let (row, col) = (6 * gy + j / 5, 5 * gx + j % 5);
                let (t, y, xx) = ((row / 6) * 15 + col / 10, row % 6, col % 10);
                assert_eq!(v as usize, (y * 10 + xx) * 75 + t, "patch {k} value {j}");
            }
        }
    }

    #[test]
    fn presets_come_near_the_backbone_size() {
        for sensor in ["icub20", "biotac20"] {
            let pvt3 = Config::preset(sensor).unwrap();
            let vit = Config::preset(&format!("vit-{sensor}")).unwrap();
            let (_, varmap) = super::Vit::init(&vit, 0).unwrap();
            let counted: usize = varmap.all_vars().iter().map(|v| v.elem_count()).sum();
            assert_eq!(counted, vit.parameter_count(), "{sensor}");
            let ratio = vit.parameter_count() as f64 / pvt3.parameter_count() as f64;
            assert!((0.8..1.2).contains(&ratio), "{sensor}: {} vs {}", vit.parameter_count(), pvt3.parameter_count());
        }
    }
}
