//! A configuration as JSON (a checkpoint's `config.json`, an `.onnx` file's `pvt3.config`): one
//! flat object, `model` naming the network, the shared fields, then the network's own.
//!
//! Files written before configurations were split by network hold every network's fields, the
//! foreign ones at their defaults; they still read. A foreign field set to anything else (a
//! `--set tile_rows=5` on a PVT³ model) is refused, naming it.

use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::network::{Architecture, Network};
use super::Config;
use crate::Error;

#[derive(Clone, Serialize, Deserialize)]
pub(super) struct ConfigFile {
    #[serde(default)]
    model: Architecture,
    height: usize,
    width: usize,
    channels: usize,
    frames: usize,
    patch_height: usize,
    patch_width: usize,
    tubelet: usize,
    dim: usize,
    space_depth: usize,
    time_depth: usize,
    heads: usize,
    dim_head: usize,
    mlp_dim: usize,
    classes: usize,
    #[serde(default = "super::default_dropout")]
    dropout: f64,
    #[serde(default = "super::default_eps")]
    layer_norm_eps: f64,
    /// The network's own fields ([`Network::entries`]): written in their declared order, read
    /// from whatever the fields above leave.
    #[serde(flatten)]
    network: NetworkFields,
}

/// The fields of a file that are not shared: written as [`Network::entries`] says, in order;
/// read as they come.
#[derive(Clone)]
struct NetworkFields(Vec<(String, Value)>);

impl Serialize for NetworkFields {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (name, value) in &self.0 {
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for NetworkFields {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(Self(serde_json::Map::deserialize(d)?.into_iter().collect()))
    }
}

impl TryFrom<ConfigFile> for Config {
    type Error = Error;

    fn try_from(f: ConfigFile) -> Result<Self, Error> {
        let value = |name: &str| f.network.0.iter().find(|(n, v)| n == name && !v.is_null()).map(|(_, v)| v.clone());
        let network = Network::from_values(f.model, value)?;
        Ok(Config {
            height: f.height,
            width: f.width,
            channels: f.channels,
            frames: f.frames,
            patch_height: f.patch_height,
            patch_width: f.patch_width,
            tubelet: f.tubelet,
            dim: f.dim,
            space_depth: f.space_depth,
            time_depth: f.time_depth,
            heads: f.heads,
            dim_head: f.dim_head,
            mlp_dim: f.mlp_dim,
            classes: f.classes,
            dropout: f.dropout,
            layer_norm_eps: f.layer_norm_eps,
            network,
        })
    }
}

impl From<Config> for ConfigFile {
    fn from(c: Config) -> Self {
        let written = c.network.entries().into_iter().filter(|e| e.written).map(|e| (e.name.to_string(), e.value));
        Self {
            model: c.architecture(),
            height: c.height,
            width: c.width,
            channels: c.channels,
            frames: c.frames,
            patch_height: c.patch_height,
            patch_width: c.patch_width,
            tubelet: c.tubelet,
            dim: c.dim,
            space_depth: c.space_depth,
            time_depth: c.time_depth,
            heads: c.heads,
            dim_head: c.dim_head,
            mlp_dim: c.mlp_dim,
            classes: c.classes,
            dropout: c.dropout,
            layer_norm_eps: c.layer_norm_eps,
            network: NetworkFields(written.collect()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::network::Pvt3Config;

    /// A PVT³ configuration as checkpoints and `.onnx` files held it before the split: every
    /// network's fields, the foreign ones at their defaults (tests/fixtures/run-9809af1-paused).
    const BEFORE_THE_SPLIT: &str = r#"{"model":"pvt3","height":6,"width":10,"channels":1,"frames":75,"patch_height":3,"patch_width":5,"tubelet":1,"dim":20,"space_depth":4,"time_depth":4,"heads":1,"dim_head":64,"mlp_dim":40,"classes":20,"dropout":0.1,"layer_norm_eps":1e-5,"tile_rows":1,"rnn_hidden":90,"latent":40,"conv_channels":0,"reconstruction_weight":0.01}"#;

    #[test]
    fn a_file_from_before_the_split_reads_as_its_network_alone() {
        let cfg: Config = serde_json::from_str(BEFORE_THE_SPLIT).unwrap();
        assert_eq!(cfg, Config::icub20());
        let written = serde_json::to_value(&cfg).unwrap();
        let fields: Vec<&str> = written.as_object().unwrap().keys().map(String::as_str).collect();
        assert!(fields.contains(&"spectral_bands") && !fields.contains(&"rnn_hidden") && !fields.contains(&"tile_rows"), "{fields:?}");
        // The RAEC preset round-trips with its own fields.
        let raec = Config::preset("raec-icub20").unwrap();
        assert_eq!(serde_json::from_value::<Config>(serde_json::to_value(&raec).unwrap()).unwrap(), raec);
    }

    #[test]
    fn a_foreign_field_set_is_refused_by_name() {
        let set = BEFORE_THE_SPLIT.replace(r#""tile_rows":1"#, r#""tile_rows":5"#);
        let msg = serde_json::from_str::<Config>(&set).unwrap_err().to_string();
        assert!(msg.contains("tile_rows = 5: not a field of a pvt3 model"), "{msg}");
        let vit = BEFORE_THE_SPLIT.replace(r#""model":"pvt3""#, r#""model":"vit""#).replace('}', r#","spectral_bands":4}"#);
        let msg = serde_json::from_str::<Config>(&vit).unwrap_err().to_string();
        assert!(msg.contains("spectral_bands = 4: not a field of a vit model"), "{msg}");
    }

    #[test]
    fn patch_selection_is_written_only_when_on() {
        let off = serde_json::to_value(Config::icub20()).unwrap();
        assert!(off.get("patch_selection").is_none(), "{off}");
        let on = Config { network: Pvt3Config { patch_selection: true, ..Default::default() }.into(), ..Config::icub20() };
        let written = serde_json::to_value(&on).unwrap();
        assert_eq!(written["patch_selection"], true);
        assert_eq!(serde_json::from_value::<Config>(written).unwrap(), on);
        let raec = BEFORE_THE_SPLIT.replace(r#""model":"pvt3""#, r#""model":"raec""#).replace('}', r#","patch_selection":true}"#);
        let msg = serde_json::from_str::<Config>(&raec).unwrap_err().to_string();
        assert!(msg.contains("patch_selection = true: not a field of a raec model"), "{msg}");
    }

    #[test]
    fn spectral_levels_are_written_only_when_off() {
        let with = Config { network: Pvt3Config { spectral_bands: 4, ..Default::default() }.into(), ..Config::icub20() };
        assert!(serde_json::to_value(&with).unwrap().get("spectral_levels").is_none());
        let without = Config { network: Pvt3Config { spectral_bands: 4, spectral_levels: false, ..Default::default() }.into(), ..with };
        let written = serde_json::to_value(&without).unwrap();
        assert_eq!(written["spectral_levels"], false);
        assert_eq!(serde_json::from_value::<Config>(written).unwrap(), without);
        assert_eq!((with.spectral_features(), without.spectral_features()), (60 * 5, 60 * 4));
    }

    #[test]
    fn patch_dropout_is_written_only_when_on_and_must_be_a_probability() {
        assert!(serde_json::to_value(Config::icub20()).unwrap().get("patch_dropout").is_none());
        let on = Config { network: Pvt3Config { patch_dropout: 0.3, ..Default::default() }.into(), ..Config::icub20() };
        let written = serde_json::to_value(&on).unwrap();
        assert_eq!(written["patch_dropout"], 0.3);
        assert_eq!(serde_json::from_value::<Config>(written).unwrap(), on);
        let all = Config { network: Pvt3Config { patch_dropout: 1.0, ..Default::default() }.into(), ..Config::icub20() };
        assert!(all.validate().unwrap_err().to_string().contains("patch_dropout = 1 is not in [0, 1)"));
    }

    /// Frames' logs are written only when on, read back, and refused without a head over an
    /// image's space.
    #[test]
    fn log_frames_are_written_only_when_on() {
        let layout = Config::for_sensor(crate::Sensor::Camera, &[30, 40, 3, 25]).unwrap();
        assert!(serde_json::to_value(&layout).unwrap().get("spectral_log_frames").is_none());
        let Network::Pvt3(p) = layout.network else { unreachable!() };
        let on = Config { network: Pvt3Config { spectral_log_frames: true, ..p }.into(), ..layout };
        assert!(on.spectral_log_frames());
        let written = serde_json::to_value(&on).unwrap();
        assert_eq!(written["spectral_log_frames"], true);
        assert_eq!(serde_json::from_value::<Config>(written).unwrap(), on);
        let frames = Config {
            network: Pvt3Config { spectral_bands: 4, spectral_log_frames: true, ..Default::default() }.into(),
            ..Config::icub20()
        };
        assert!(frames.validate().unwrap_err().to_string().contains("set spectral_log_frames=false too"));
    }

    /// The histogram and its gradients are written only when the head has them, read back, count
    /// in the features, and are refused where no head over an image's space (or no histogram)
    /// reads them.
    #[test]
    fn a_histogram_is_written_only_when_there_is_one() {
        let layout = Config::for_sensor(crate::Sensor::Camera, &[30, 40, 3, 25]).unwrap();
        assert_eq!((layout.spectral_histogram(), layout.spectral_gradients()), (24, false));
        assert!(layout.spectral_pixels());
        assert_eq!(layout.spectral_features(), 3 * (1 + 12 + 24 + 30 * 40));
        let layout_file = serde_json::to_value(&layout).unwrap();
        assert!(layout_file.get("spectral_gradients").is_none());
        let Network::Pvt3(p) = layout.network else { unreachable!() };
        let camera = Config { network: Pvt3Config { spectral_gradients: true, ..p }.into(), ..layout };
        assert_eq!(camera.spectral_features(), 3 * (1 + 12 + 3 * 24 + 30 * 40));
        let written = serde_json::to_value(&camera).unwrap();
        assert_eq!((&written["spectral_histogram"], &written["spectral_gradients"]), (&24.into(), &true.into()));
        assert_eq!(serde_json::from_value::<Config>(written).unwrap(), camera);
        let icub = Config { network: Pvt3Config { spectral_bands: 4, ..Default::default() }.into(), ..Config::icub20() };
        let icub_file = serde_json::to_value(&icub).unwrap();
        assert!(icub_file.get("spectral_histogram").is_none() && icub_file.get("spectral_gradients").is_none());
        let frames = Config { network: Pvt3Config { spectral_bands: 4, spectral_histogram: 8, ..Default::default() }.into(), ..icub };
        let msg = frames.validate().unwrap_err().to_string();
        assert!(msg.contains("spectral_histogram = 8") && msg.contains("spectral_space"), "{msg}");
        let pixels = Config { network: Pvt3Config { spectral_bands: 4, spectral_pixels: true, ..Default::default() }.into(), ..icub };
        assert!(pixels.validate().unwrap_err().to_string().contains("set spectral_pixels=false too"));
        let Network::Pvt3(p) = camera.network else { unreachable!() };
        let flat = Config { network: Pvt3Config { spectral_histogram: 0, ..p }.into(), ..camera };
        assert!(flat.validate().unwrap_err().to_string().contains("set spectral_gradients=false too"));
    }
}
