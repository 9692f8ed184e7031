//! [`Header`]: the metadata a runtime needs to read an exported file, typed. The exporter
//! writes it with [`Header::entries`]; the runtime reads it with [`Header::parse`], which checks
//! the format version first and refuses a file of another major version, then checks that the
//! parts agree with each other. A file with more metadata (provenance, the full configuration)
//! is fine: unknown keys and fields are ignored.

use serde::{Deserialize, Serialize};

use crate::{keys, Camera};

/// The file format this crate reads and writes, `major.minor`. A runtime reads every file of
/// its major version; a new minor version only adds what older runtimes may ignore.
/// 1.1 added the temporal stage's key bias ([`crate::TOKEN_BIAS`]).
pub const FORMAT_VERSION: (u32, u32) = (1, 1);

/// Why a file's metadata is not one this crate reads.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum HeaderError {
    /// An entry missing or not of its form.
    #[error("metadata `{key}` {problem}")]
    Invalid {
        /// The entry's key.
        key: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    #[error("format {found}, which this runtime (format {}.{}) does not read: use a runtime of the same major version, or export the model again", FORMAT_VERSION.0, FORMAT_VERSION.1)]
    /// A format version of another major version.
    Version {
        /// The version the file states.
        found: String,
    },
}

/// The shape of the model's input and tokens: the part of `pvt3.config` a runtime reads.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Dims {
    /// The window's first axis (taxel rows, electrodes, image rows).
    pub height: usize,
    /// The window's second axis.
    pub width: usize,
    /// 1 for a sensor without a channel axis.
    pub channels: usize,
    /// Frames per window, pruned ones included.
    pub frames: usize,
    /// Frames per temporal token.
    pub tubelet: usize,
    /// Width of a token's encoding.
    pub dim: usize,
}

/// What a runtime reads from a file's metadata.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// The class names, in the outputs' order ([`keys::CLASSES`]).
    pub classes: Vec<String>,
    /// The frames of a window the model reads, ascending; whole tokens.
    pub kept_frames: Vec<usize>,
    /// The input's and the tokens' shape ([`keys::CONFIG`]).
    pub dims: Dims,
    /// The stopping rule of provisional answers ([`keys::STOP_RULE`]); `None` when the file has none.
    pub stop_rule: Option<StopRule>,
    /// How the model reads a touch ([`keys::READING`]); `None`: as the sensor records it.
    pub reading: Option<Reading>,
    /// How a camera's frames become the model's ([`keys::CAMERA`]); `None`: given as it reads them.
    pub camera: Option<Camera>,
}

/// How a model reads a touch when its training touches were brought to one sliding speed and one
/// pressing force (`pvt3 import --per-distance`, `--per-force`): a robot, which knows the speed and
/// force it commands, brings its frames to them before it classifies (the runtime's `read_touch`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Reading {
    /// Touches resampled from time to distance travelled: a touch of `n` frames at speed `v` is
    /// read as the `n · |v| / speed` frames it would have at this speed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
    /// Readings scaled to this force: times `force / f` for a touch pressed at `f`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<f64>,
}

impl Reading {
    /// Why the reading cannot be a file's, if it cannot: a speed or force that is not above 0.
    pub fn problem(&self) -> Option<String> {
        [("speed", self.speed), ("force", self.force)]
            .into_iter()
            .find_map(|(what, v)| v.filter(|v| !(v.is_finite() && *v > 0.0)).map(|v| format!("{what} {v} is not above 0")))
    }
}

/// When a touch may end early: at the first whole temporal token whose provisional answer's top
/// class probability is at least `top_probability` and whose top class is that of the answers
/// after each of the `agreeing - 1` tokens before it (`agreeing` answers in a row agree).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StopRule {
    /// The least top class probability at which an answer may stop the touch.
    pub top_probability: f32,
    /// How many answers in a row must agree on the top class.
    pub agreeing: usize,
}

/// The answer in a row of class probabilities: the index of the largest (the first on a tie, as
/// numpy's and ONNX's ArgMax choose) and its probability. The runtime's predictions and the
/// trainer's calibration of the [`StopRule`] both read answers through this one function.
pub fn top_class(probabilities: &[f32]) -> (usize, f32) {
    probabilities.iter().enumerate().fold((0, f32::NEG_INFINITY), |best, (c, &p)| if p.total_cmp(&best.1).is_gt() { (c, p) } else { best })
}

impl StopRule {
    /// Why the rule cannot be a file's, if it cannot: a probability outside (0, 1], or no answer
    /// to agree.
    pub fn problem(&self) -> Option<String> {
        let p = self.top_probability;
        if !(p > 0.0 && p <= 1.0) {
            return Some(format!("top probability {p} is not in (0, 1]"));
        }
        (self.agreeing == 0).then(|| "no answer to agree (agreeing = 0)".to_string())
    }

    /// The stopping decision, written once for the runtime's streams and the trainer's
    /// calibration and replay: a touch stops after its `k`-th temporal token when the answer then,
    /// `class` with `probability`, is at least [`StopRule::top_probability`] sure and
    /// [`answers_agree`] over the last [`StopRule::agreeing`] tokens.
    pub fn stops<E>(
        &self,
        k: usize,
        class: usize,
        probability: f32,
        class_after: impl FnMut(usize) -> Result<usize, E>,
    ) -> Result<bool, E> {
        let sure = probability >= self.top_probability;
        if !sure {
            return Ok(false);
        }
        answers_agree(self.agreeing, k, class, class_after)
    }
}

/// The rule in words, as reports and pictures give it.
impl std::fmt::Display for StopRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "top probability ≥ {:.4} with {} answers in a row agreeing", self.top_probability, self.agreeing)
    }
}

/// Whether the answers after each of the last `agreeing` tokens up to the `k`-th name `class`,
/// the `k`-th's: `class_after(j)` gives the class answered after `j` tokens, asked for `j` from
/// `k + 1 − agreeing` to `k − 1` in order, until one differs. False while fewer than `agreeing`
/// tokens are in.
pub fn answers_agree<E>(
    agreeing: usize,
    k: usize,
    class: usize,
    mut class_after: impl FnMut(usize) -> Result<usize, E>,
) -> Result<bool, E> {
    if k < agreeing {
        return Ok(false);
    }
    for j in k + 1 - agreeing..k {
        if class_after(j)? != class {
            return Ok(false);
        }
    }
    Ok(true)
}

impl Header {
    /// One window: `[height, width, (channels,) frames]`, without a channel axis when there is
    /// one channel.
    pub fn sample_shape(&self) -> Vec<usize> {
        let l = &self.dims;
        let mut shape = vec![l.height, l.width];
        if l.channels > 1 {
            shape.push(l.channels);
        }
        shape.push(l.frames);
        shape
    }

    /// The metadata entries the exporter writes, `config` being the model's whole configuration
    /// (a JSON object holding at least the [`Dims`]'s fields).
    pub fn entries(&self, config: &serde_json::Value) -> Vec<(&'static str, String)> {
        let layout = if self.dims.channels == 1 { "[batch, height, width, frames]" } else { "[batch, height, width, channels, frames]" };
        let dims = self.sample_shape().iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", ");
        let mut entries = vec![
            (keys::FORMAT, format!("{}.{}", FORMAT_VERSION.0, FORMAT_VERSION.1)),
            (keys::CLASSES, serde_json::to_string(&self.classes).expect("strings serialise")),
            (keys::INPUT_LAYOUT, format!("{layout} = [batch, {dims}], raw sensor values as float32")),
            (keys::INPUT_UNITS, "the data set's raw units (normalisation is inside the graph)".into()),
            (keys::KEPT_FRAMES, serde_json::to_string(&self.kept_frames).expect("integers serialise")),
            (keys::CONFIG, config.to_string()),
        ];
        if let Some(rule) = self.stop_rule {
            entries.push((keys::STOP_RULE, serde_json::to_string(&rule).expect("plain data serialises")));
        }
        if let Some(reading) = self.reading {
            entries.push((keys::READING, serde_json::to_string(&reading).expect("plain data serialises")));
        }
        if let Some(camera) = self.camera {
            entries.push((keys::CAMERA, serde_json::to_string(&camera).expect("plain data serialises")));
        }
        entries
    }

    /// The header of a file whose metadata entries are `entries` (key, value).
    pub fn parse<'a>(entries: impl IntoIterator<Item = (&'a str, &'a str)> + Clone) -> Result<Self, HeaderError> {
        let get = |key: &'static str| {
            entries
                .clone()
                .into_iter()
                .find(|(k, _)| *k == key)
                .map(|(_, v)| v)
                .ok_or(HeaderError::Invalid { key, problem: "is missing".into() })
        };
        let version = get(keys::FORMAT).map_err(|_| HeaderError::Invalid {
            key: keys::FORMAT,
            problem: "is missing: the file was exported by a pvt3 older than format 1.0; export it again".into(),
        })?;
        let major = version.split('.').next().and_then(|m| m.parse::<u32>().ok());
        if major != Some(FORMAT_VERSION.0) || version.split('.').nth(1).and_then(|m| m.parse::<u32>().ok()).is_none() {
            return Err(HeaderError::Version { found: version.to_string() });
        }
        fn json<T: serde::de::DeserializeOwned>(key: &'static str, value: &str) -> Result<T, HeaderError> {
            serde_json::from_str(value).map_err(|e| HeaderError::Invalid { key, problem: format!("has an unexpected form ({e})") })
        }
        let header = Header {
            classes: json(keys::CLASSES, get(keys::CLASSES)?)?,
            kept_frames: json(keys::KEPT_FRAMES, get(keys::KEPT_FRAMES)?)?,
            dims: json(keys::CONFIG, get(keys::CONFIG)?)?,
            stop_rule: get(keys::STOP_RULE).ok().map(|t| json(keys::STOP_RULE, t)).transpose()?,
            reading: get(keys::READING).ok().map(|t| json(keys::READING, t)).transpose()?,
            camera: get(keys::CAMERA).ok().map(|t| json(keys::CAMERA, t)).transpose()?,
        };
        header.check()?;
        Ok(header)
    }

    /// The parts agree: classes exist, whole tokens are kept, in order, within the window.
    fn check(&self) -> Result<(), HeaderError> {
        let l = &self.dims;
        let bad = |key, problem: &str| Err(HeaderError::Invalid { key, problem: problem.into() });
        if self.classes.is_empty() {
            return bad(keys::CLASSES, "names no class");
        }
        if [l.height, l.width, l.channels, l.frames, l.tubelet, l.dim].contains(&0) || !l.frames.is_multiple_of(l.tubelet) {
            return bad(keys::CONFIG, "has an empty axis, or frames that are not whole tokens");
        }
        let f = &self.kept_frames;
        let whole_tokens = f.len().is_multiple_of(l.tubelet)
            && f.chunks(l.tubelet).all(|t| t[0].is_multiple_of(l.tubelet) && t.iter().enumerate().all(|(i, v)| *v == t[0] + i));
        if f.is_empty() || !whole_tokens || !f.windows(2).all(|w| w[0] < w[1]) || f.iter().any(|v| *v >= l.frames) {
            return bad(keys::KEPT_FRAMES, "is not a rising list of whole tokens within the window");
        }
        if let Some(problem) = self.stop_rule.and_then(|r| r.problem()) {
            return bad(keys::STOP_RULE, &problem);
        }
        if let Some(problem) = self.reading.and_then(|r| r.problem()) {
            return bad(keys::READING, &problem);
        }
        if let Some(problem) = self.camera.and_then(|c| c.problem(&self.dims)) {
            return bad(keys::CAMERA, &problem);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> Header {
        let dims = Dims { height: 6, width: 10, channels: 1, frames: 75, tubelet: 5, dim: 40 };
        Header {
            classes: vec!["felt".into(), "wood".into()],
            kept_frames: (10..20).chain(40..45).collect(),
            dims,
            stop_rule: Some(StopRule { top_probability: 0.875, agreeing: 3 }),
            reading: None,
            camera: None,
        }
    }

    fn config(h: &Header) -> serde_json::Value {
        let mut c = serde_json::to_value(&h.dims).unwrap();
        c["heads"] = 4.into();
        c
    }

    fn parse(entries: &[(&'static str, String)]) -> Result<Header, HeaderError> {
        Header::parse(entries.iter().map(|(k, v)| (*k, v.as_str())))
    }

    #[test]
    fn a_touch_stops_when_sure_and_the_last_answers_agree() {
        let rule = StopRule { top_probability: 0.8, agreeing: 3 };
        // The classes after tokens 1, 2, 3, …: 2, 1, 1, 1.
        let classes = [2, 1, 1, 1];
        let mut asked = Vec::new();
        let mut after = |j: usize| -> Result<usize, ()> {
            asked.push(j);
            Ok(classes[j - 1])
        };
        assert_eq!(rule.stops(2, 1, 0.99, &mut after), Ok(false), "fewer tokens than answers to agree");
        assert_eq!(rule.stops(3, 1, 0.99, &mut after), Ok(false), "the first answer differs");
        assert_eq!(rule.stops(4, 1, 0.99, &mut after), Ok(true));
        assert_eq!(rule.stops(4, 1, 0.79, &mut after), Ok(false), "not sure enough");
        assert_eq!(rule.stops(4, 1, f32::NAN, &mut after), Ok(false));
        assert_eq!(asked, [1, 2, 3], "only the answers before, until one differs; none when not sure");
        assert_eq!(rule.stops(4, 1, 0.99, |_| Err("no answer")), Err("no answer"));
        assert_eq!(rule.to_string(), "top probability ≥ 0.8000 with 3 answers in a row agreeing");
    }

    #[test]
    fn the_top_class_is_the_first_largest_probability() {
        assert_eq!(top_class(&[0.1, 0.6, 0.3]), (1, 0.6));
        assert_eq!(top_class(&[0.4, 0.2, 0.4]), (0, 0.4), "a tie goes to the first, as ArgMax");
        assert_eq!(top_class(&[0.25; 4]), (0, 0.25));
    }

    #[test]
    fn what_the_exporter_writes_the_runtime_reads() {
        let h = header();
        let entries = h.entries(&config(&h));
        assert_eq!(parse(&entries).unwrap(), h);
        assert_eq!(h.sample_shape(), vec![6, 10, 75]);
        // The stopping threshold is optional.
        let h = Header { stop_rule: None, ..h };
        let entries = h.entries(&config(&h));
        assert!(entries.iter().all(|(k, _)| *k != keys::STOP_RULE));
        assert_eq!(parse(&entries).unwrap(), h);
        // How a touch is read is optional too, each part of it.
        for reading in [Reading { speed: Some(150.0), force: Some(120.0) }, Reading { speed: None, force: Some(2.5) }] {
            let h = Header { reading: Some(reading), ..h.clone() };
            assert_eq!(parse(&h.entries(&config(&h))).unwrap(), h);
        }
        assert!(entries.iter().all(|(k, _)| *k != keys::READING && *k != keys::CAMERA));
        // So is how a camera's frames are read.
        let camera = Camera { recorded: [12, 20, 3], crop: None, size: Some([6, 10]), grey: true, subtract_first: true };
        let h = Header { camera: Some(camera), ..h };
        assert_eq!(parse(&h.entries(&config(&h))).unwrap(), h);
    }

    #[test]
    fn another_major_version_is_refused_and_a_newer_minor_read() {
        let h = header();
        let mut entries = h.entries(&config(&h));
        entries[0].1 = "1.7".into();
        assert_eq!(parse(&entries).unwrap(), h);
        for found in ["2.0", "0.9", "1", "one.zero"] {
            entries[0].1 = found.into();
            assert_eq!(parse(&entries), Err(HeaderError::Version { found: found.into() }), "{found}");
        }
        entries.remove(0);
        assert!(matches!(parse(&entries), Err(HeaderError::Invalid { key: keys::FORMAT, .. })));
    }

    #[test]
    fn inconsistent_metadata_is_refused() {
        let h = header();
        let broken: [fn(&mut Header); 16] = [
            |h| h.camera = Some(Camera { recorded: [12, 20, 3], crop: None, size: Some([6, 10]), grey: false, subtract_first: false }),
            |h| h.reading = Some(Reading { speed: Some(0.0), force: None }),
            |h| h.reading = Some(Reading { speed: Some(150.0), force: Some(-3.0) }),
            |h| h.reading = Some(Reading { speed: None, force: Some(0.0) }),
            |h| h.stop_rule = Some(StopRule { top_probability: 0.0, agreeing: 1 }),
            |h| h.stop_rule = Some(StopRule { top_probability: 1.5, agreeing: 1 }),
            |h| h.stop_rule = Some(StopRule { top_probability: f32::NAN, agreeing: 1 }),
            |h| h.stop_rule = Some(StopRule { top_probability: 0.9, agreeing: 0 }),
            |h| h.classes.clear(),
            |h| h.kept_frames.clear(),
            |h| h.kept_frames.reverse(),
            |h| h.kept_frames.truncate(7),
            |h| h.kept_frames = (11..21).collect(),
            |h| h.kept_frames = (70..80).collect(),
            |h| h.dims.tubelet = 4,
            |h| h.dims.dim = 0,
        ];
        for (i, damage) in broken.iter().enumerate() {
            let mut bad = h.clone();
            damage(&mut bad);
            assert!(matches!(parse(&bad.entries(&config(&bad))), Err(HeaderError::Invalid { .. })), "case {i}");
        }
        let mut entries = h.entries(&config(&h));
        entries.retain(|(k, _)| *k != keys::CONFIG);
        entries.push((keys::CONFIG, r#"{"height": 6}"#.into()));
        assert!(matches!(parse(&entries), Err(HeaderError::Invalid { key: keys::CONFIG, .. })));
    }
}
