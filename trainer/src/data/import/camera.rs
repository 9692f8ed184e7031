//! `pvt3 import` of camera-based tactile sensors (GelSight, DIGIT, GelSlim). A folder of
//! videos (one file a touch) or of frame folders (one folder of PNG or JPEG images a touch), the
//! classes from folders or from a file-name pattern as for CSV touches, becomes a data set of
//! 8-bit frames `x` `[N, H, W, C, T]` (RGB; grey `[N, H, W, T]`), stored as recorded: a GelSight
//! set is a few gigabytes as u8 and four times that as f32.
//!
//! Each touch gives `T` frames taken evenly over the recording or over the span in which the gel
//! moves ([`pvt3_format::span`]), each cropped and shrunk by area averaging
//! ([`Picture::read_as`]): the reading contract a robot's runtime holds to as well.
//! With `subtract_first`, each touch's first frame (the gel before contact) is kept as its
//! `background` `[N, H, W, C]`, and a reader takes the frames minus it, the PVT³ report's GelSight
//! preprocessing ([`crate::data::Dataset::load`]).

use std::path::Path;

use ndarray::{ArrayViewD, IxDyn};
use rayon::prelude::*;

use super::decode;
use super::folder::{conditions, list_touches, per_class, Naming, Recording};
use super::npz::{self, add_json, Records};
use super::timing::Timing;
use crate::data::{key, Condition};
use crate::{Error, Result};
use pvt3_format::span::FrameSpan;
use pvt3_format::{Camera, Crop, Picture};

/// What to import and how.
#[derive(Clone, Debug)]
pub struct CameraOptions {
    /// Where each touch's class and conditions come from (folders, names or a labels file).
    pub naming: Naming,
    /// The rectangle of each frame to keep (before shrinking); `None`: the whole frame.
    pub crop: Option<Crop>,
    /// The size every frame is shrunk to (height, width), by area averaging; `None`: as recorded.
    pub size: Option<(usize, usize)>,
    /// One grey channel instead of RGB.
    pub grey: bool,
    /// Frames a touch; `None`: [`DEFAULT_FRAMES`], or one where every touch is a still image.
    pub frames: Option<usize>,
    /// Which frames.
    pub span: FrameSpan,
    /// Each touch's first frame kept as its background, which a reader subtracts.
    pub subtract_first: bool,
    /// A recording of fewer frames than `frames` read with its frames repeated, evenly, instead
    /// of refused.
    pub allow_short: bool,
    /// The topic a bag's frames are read from (`sensor_msgs/msg/Image` or `CompressedImage`).
    pub topic: Option<String>,
    /// The kind of sensor the set records; `None`: a camera's (`--sensor array` for a taxel
    /// array's readings stored as images).
    pub sensor: Option<pvt3_spec::Sensor>,
}

impl Default for CameraOptions {
    /// The PVT³ report's GelSight touch: 25 RGB frames as recorded, where the gel moves.
    fn default() -> Self {
        Self {
            naming: Naming::Folders,
            crop: None,
            size: None,
            grey: false,
            frames: None,
            span: FrameSpan::Moving,
            subtract_first: false,
            allow_short: false,
            topic: None,
            sensor: None,
        }
    }
}

/// Frames a touch takes unless asked otherwise: the PVT³ report's GelSight touch.
pub const DEFAULT_FRAMES: usize = 25;

/// Frames a touch takes at most (`--frames`): 2.3 GB a touch at 240 × 320 RGB, where a repeated
/// short recording (`--allow-short`) would otherwise grow without bound.
pub const MAX_FRAMES: usize = 10_000;

/// The imported set, before it is written.
#[derive(Debug)]
pub struct CameraSet {
    /// `[N, H, W, C, T]`.
    pub x: Vec<u8>,
    /// `[N, H, W, C]`: each touch's first frame, where it is subtracted.
    pub background: Option<Vec<u8>>,
    /// One frame's `[H, W, C]`, and `T`.
    pub frame_shape: [usize; 3],
    pub frames: usize,
    pub labels: Vec<u32>,
    pub classes: Vec<String>,
    pub sources: Vec<String>,
    pub conditions: Vec<Condition>,
    /// Each touch's frames recorded and the first and last it took.
    pub spans: Vec<(usize, usize, usize)>,
    /// How the frames were read from the camera's, where every recording's frames have one
    /// shape (what a robot's camera gives the exported model).
    pub camera: Option<Camera>,
    /// The touches whose frames' times were not evenly spaced and rising (bags), by source.
    pub timings: Vec<(String, Timing)>,
    /// The kind of sensor the set records ([`CameraOptions::sensor`]).
    pub sensor: pvt3_spec::Sensor,
}

impl CameraSet {
    /// The touches recorded with fewer frames than they take (their frames repeated), by source.
    pub fn short(&self) -> Vec<(&str, usize)> {
        let short = self.spans.iter().zip(&self.sources).filter(|((recorded, _, _), _)| *recorded < self.frames);
        short.map(|((recorded, _, _), source)| (source.as_str(), *recorded)).collect()
    }
}

/// Reads `dir` as camera touches (videos, frame folders or still images), one folder per class or side by side
/// with `opts.naming` naming the class.
pub fn read_camera_folder(dir: &Path, opts: &CameraOptions, mut progress: impl FnMut(usize, usize)) -> Result<CameraSet> {
    let (files, classes) = list_touches(dir, &opts.naming, Recording::Camera)?;
    // A still image is one frame, read once: a set of them takes one frame a touch.
    let stills = files.iter().all(|f| decode::is_still(&f.path));
    let frames = opts.frames.unwrap_or(if stills { 1 } else { DEFAULT_FRAMES });
    if !(1..=MAX_FRAMES).contains(&frames) {
        return Err(Error::Usage(format!("--frames {frames}: a touch takes 1 to {MAX_FRAMES} frames")));
    }
    let values: Vec<Vec<String>> = files.iter().map(|f| f.values.clone()).collect();
    let mut set = CameraSet::empty(frames, classes, conditions(&opts.naming, &values), opts);
    // The first touch and its first frame: every touch's frames must have its shape.
    let mut first: Option<(&Path, Picture)> = None;
    let mut recorded = Vec::new();
    // Touches decoded a few at a time on every core, appended in order.
    let mut done = 0;
    let decoded = files.chunks(4 * rayon::current_num_threads()).flat_map(|chunk| {
        let read: Vec<_> = chunk.par_iter().map(|f| (f, read_touch(&f.path, f.window, opts, frames))).collect();
        done += chunk.len();
        progress(done, files.len());
        read
    });
    for (file, touch) in decoded {
        let path = file.path.as_path();
        let ReadTouch { frames, background, span, camera, timing } = touch.map_err(|e| Error::import(path, None, e))?;
        recorded.push(camera);
        let source = file.source(dir);
        if let Some(timing) = timing.filter(Timing::strays) {
            set.timings.push((source.clone(), timing));
        }
        match &first {
            Some(first) => same_shape(first, (path, &frames[0]))?,
            None => {
                set.frame_shape = frames[0].shape();
                first = Some((path, frames[0].clone()));
            }
        }
        set.append(&frames, background);
        set.labels.push(set.classes.binary_search(&file.class).expect("a listed class") as u32);
        set.sources.push(source);
        set.spans.push(span);
    }
    set.camera = recorded.first().copied().filter(|c| recorded.iter().all(|r| r == c));
    Ok(set)
}

/// Refuses the touch at `path` whose frame is not the shape of the first touch's.
fn same_shape((first_path, first): &(&Path, Picture), (path, frame): (&Path, &Picture)) -> Result<()> {
    if first.shape() == frame.shape() {
        return Ok(());
    }
    let why = format!(
        "its frames are {}, {}'s {} (--size shrinks every touch to one size, --grey greys them)",
        frame.describe(),
        first_path.display(),
        first.describe()
    );
    Err(Error::import(path, None, why))
}

/// One touch as read: its chosen frames, cropped, shrunk and greyed; its background, where
/// asked; (frames recorded, first taken, last taken); how its frames were read; and, for a bag,
/// how its frames' times strayed.
struct ReadTouch {
    frames: Vec<Picture>,
    background: Option<Picture>,
    span: (usize, usize, usize),
    camera: Camera,
    timing: Option<Timing>,
}

/// The touch at `path` read as `opts` say, `frames` frames of it; of a bag, the seconds
/// `window` says (from its first message), or all of it.
fn read_touch(path: &Path, window: Option<(f64, f64)>, opts: &CameraOptions, frames: usize) -> std::result::Result<ReadTouch, String> {
    #[cfg(feature = "bags")]
    if decode::is_bag(path) {
        return bag_touch::read(path, window, opts, frames);
    }
    debug_assert!(window.is_none(), "the listing cuts bags alone");
    let recorded = decode::frames(path)?;
    enough(recorded.len(), frames, opts)?;
    let taken = opts.span.take(&recorded, frames);
    let camera = opts.camera(&recorded[0]);
    let prepare = |p: &Picture| p.clone().read_as(&camera);
    let chosen = taken.frames.iter().map(|&i| prepare(&recorded[i])).collect::<std::result::Result<Vec<_>, _>>()?;
    let background = if opts.subtract_first { Some(prepare(&recorded[0])?) } else { None };
    Ok(ReadTouch { frames: chosen, background, span: (recorded.len(), taken.first, taken.last), camera, timing: None })
}

/// Refuses a recording of `n` frames that is empty, or shorter than the `frames` a touch takes
/// without `--allow-short`.
fn enough(n: usize, frames: usize, opts: &CameraOptions) -> std::result::Result<(), String> {
    if n == 0 || (n < frames && !opts.allow_short) {
        let (noun, still) = if n == 1 { ("frame", ", a still image as itself") } else { ("frames", "") };
        let fix = match n {
            0 => String::new(),
            _ => format!(" {n} takes {n} {noun} a touch{still}; --allow-short repeats a short touch's frames"),
        };
        return Err(format!("{n} {noun}, fewer than the {frames} a touch takes (--frames{fix})"));
    }
    Ok(())
}

impl CameraOptions {
    /// How frames recorded as `first` is are read.
    fn camera(&self, first: &Picture) -> Camera {
        Camera {
            recorded: first.shape(),
            crop: self.crop,
            size: self.size.map(|(h, w)| [h, w]),
            grey: self.grey,
            subtract_first: self.subtract_first,
        }
    }
}

impl CameraSet {
    /// A set with no touch yet, of `frames` frames a touch, with a background for each touch when
    /// `opts.subtract_first` asks for it.
    fn empty(frames: usize, classes: Vec<String>, conditions: Vec<Condition>, opts: &CameraOptions) -> Self {
        CameraSet {
            x: Vec::new(),
            background: opts.subtract_first.then(Vec::new),
            frame_shape: [0; 3],
            frames,
            labels: Vec::new(),
            classes,
            sources: Vec::new(),
            conditions,
            spans: Vec::new(),
            camera: None,
            timings: Vec::new(),
            sensor: opts.sensor.unwrap_or(pvt3_spec::Sensor::Camera),
        }
    }

    /// A touch's frames appended to `x` in the layout `[H, W, C, T]`, and its background.
    fn append(&mut self, frames: &[Picture], background: Option<Picture>) {
        let (pixels, t) = (frames[0].data.len(), frames.len());
        let at = self.x.len();
        self.x.resize(at + pixels * t, 0);
        for (f, frame) in frames.iter().enumerate() {
            for (p, v) in frame.data.iter().enumerate() {
                self.x[at + p * t + f] = *v;
            }
        }
        if let (Some(all), Some(b)) = (self.background.as_mut(), background) {
            all.extend_from_slice(&b.data);
        }
    }

    /// Touches per class, in class order.
    pub fn per_class(&self) -> Vec<usize> {
        per_class(&self.labels, self.classes.len())
    }

    /// Writes the set as `.npz`: `x` (uint8 `[N, H, W, C, T]`, grey `[N, H, W, T]`, the layouts
    /// [`crate::data::Dataset`] reads), `background` (uint8 `[N, H, W, (C)]`) where asked, `y`,
    /// the names as UTF-8 lines ([`key`]), and `camera`, how the frames were read, where every
    /// recording has one shape.
    pub fn write_npz(&self, path: &Path) -> Result<()> {
        let [h, w, c] = self.frame_shape;
        let n = self.labels.len();
        let frame: Vec<usize> = if c == 1 { vec![n, h, w] } else { vec![n, h, w, c] };
        let (labels, classes, sources, conditions) = (&self.labels, &self.classes, &self.sources, &self.conditions);
        let records = Records { labels, classes, sources, conditions, sensor: self.sensor };
        npz::write(path, records, |npz| {
            npz.add_array(key::X, &ArrayViewD::from_shape(IxDyn(&[&frame[..], &[self.frames]].concat()), &self.x)?)?;
            if let Some(b) = &self.background {
                npz.add_array(key::BACKGROUND, &ArrayViewD::from_shape(IxDyn(&frame), b)?)?;
            }
            if let Some(camera) = &self.camera {
                add_json(npz, key::CAMERA, camera)?;
            }
            Ok(())
        })
    }
}

#[cfg(feature = "bags")]
mod bag_touch;
#[cfg(test)]
mod tests;
