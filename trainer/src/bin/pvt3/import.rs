//! `pvt3 import`: a folder of CSV touches, or of a camera's videos, frame folders or still
//! images → an `.npz` data set for `train`, `cv` and `eval`.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use pvt3_format::span::FrameSpan;
use pvt3_format::Crop;
use pvt3_trainer::data::import::camera::{read_camera_folder, CameraOptions, CameraSet};
use pvt3_trainer::data::import::csv::{elided, read_folder, ImportOptions};
use pvt3_trainer::data::import::folder::{holds_camera_touches, NamePattern, Naming};
use pvt3_trainer::data::import::labels::Labels;
use pvt3_trainer::data::import::timing::Timing;
use pvt3_trainer::data::Condition;

use crate::progress;

/// Read a folder of touches into a data set: CSV recordings (one CSV file per touch, a header
/// row, touches of any length), or a camera-based sensor's (GelSight, DIGIT: one video, one
/// folder of PNG or JPEG frames, or one ROS 2 bag, per touch; videos decoded by FFmpeg).
///
/// Example: `pvt3 import csvs/ --out data.npz`, then `pvt3 cv --data data.npz`. Where the file
/// names say the class and how each touch was made: `pvt3 import fabric/ --name
/// '{class}_F{force}_V{speed}mmps_*'`, then `pvt3 cv --hold-out force=210,250` tests on forces
/// the training never saw. A camera's videos named `<object>_<n>.mov` (PhysiCLeAR): `pvt3
/// import dataset/ --name '{class}_*' --size 60x80 --frames 25`.
#[derive(clap::Args)]
pub struct ImportArgs {
    /// The folder: DIR/<class>/<touch>, class names the folder names; or, with --name naming the
    /// class, DIR/<touch>. A touch is a .csv file, or a camera's video (.mov, .mp4, .avi, .mkv,
    /// .webm, .m4v, .mpg), folder of frame images (.png, .jpg, in name order), still image (one
    /// .png or .jpg, a touch of one frame) or ROS 2 bag (a folder with metadata.yaml and its
    /// .mcap or .db3 files, or one .mcap file; --topic names the topic: a camera's, or a taxel
    /// array's, read as a CSV touch).
    pub dir: PathBuf,
    /// The data set to write (`x`, `y`, `lengths`, class names, channels, the files read).
    #[arg(short, long, default_value = "data.npz")]
    pub out: PathBuf,
    /// The sensor channels: column names or patterns (`*` any characters, `?` one), comma
    /// separated, e.g. `ff_e*` or `e1,e2,e3`. Default: every numeric column that varies,
    /// time stamps (by name, or rising in every touch) and constant columns left out.
    #[arg(long, value_delimiter = ',')]
    pub columns: Vec<String>,
    /// The chosen channels as a ROWSxCOLS grid, row-major (e.g. `6x10` for the iCub skin).
    /// Default: one column of channels, as for the BioTac's electrodes.
    #[arg(long, value_parser = parse_grid)]
    pub grid: Option<(usize, usize)>,
    /// What each touch's name (without its extension) says: `{field}` reads a value (the longest
    /// that lets the rest match), `*` matches anything, other characters match themselves.
    /// `{class}` names the class (the touches then lie side by side in DIR); every other field is
    /// a condition of the touch (speed, force, …) recorded for `--hold-out`. E.g.
    /// `{class}_F{force}_V{speed}mmps_*`, or `{class}_*` for `aluminium_foil_3.mov`.
    #[arg(long, value_name = "PATTERN")]
    pub name: Option<NamePattern>,
    /// Each touch's class, and its conditions, from a CSV file instead of names: its header names
    /// `path` (the touch's path relative to DIR: a .csv file, a video, a frame folder or an
    /// image) and `class`, and every other column is a condition recorded for `--hold-out`
    /// (e.g. `path,class,object` with `grasp_3/camera_0.avi,slip,mug`). Touches DIR holds that
    /// the file does not list are not read. With `start` and `end` columns, each row cuts a
    /// touch out of a long ROS 2 bag: the seconds from its first message.
    #[arg(long, value_name = "FILE.csv", conflicts_with = "name")]
    pub labels: Option<PathBuf>,
    /// Read every touch by distance travelled, not by time: CONDITION=SPEED names the condition
    /// (of --name or --labels) that holds each touch's sliding speed, and the speed all touches are resampled
    /// to (a touch of n frames at speed v becomes n·|v|/SPEED frames). A texture's ridges then lie
    /// as many frames apart at every speed. E.g. `--per-distance speed=150`.
    #[arg(long, value_name = "CONDITION=SPEED", value_parser = parse_condition_value)]
    pub per_distance: Option<(String, f64)>,
    /// Scale every touch's readings to one pressing force: CONDITION=FORCE names the condition
    /// (of --name or --labels) that holds each touch's force, and the force all touches are scaled to
    /// (readings times FORCE/f for a touch pressed at f). E.g. `--per-force force=150`.
    #[arg(long, value_name = "CONDITION=FORCE", value_parser = parse_condition_value)]
    pub per_force: Option<(String, f64)>,
    /// A bag's topic to read: a camera's frames (sensor_msgs/msg/Image: rgb8, bgr8, rgba8,
    /// bgra8, mono8, mono16; or CompressedImage: png, jpeg), or a taxel array's values
    /// (std_msgs/msg/Float32MultiArray, Float64, Int16, Int32, UInt16 or UInt8MultiArray: each
    /// message a frame, its values the channels data[0], data[1], …, its layout's two
    /// dimensions, where it has two, the grid). Without it, or where a bag lacks it, the import
    /// lists the bag's topics with their types and message counts.
    #[arg(long, value_name = "NAME")]
    pub topic: Option<String>,
    /// The kind of sensor the set records, which the training's layout follows: `array` (a
    /// tactile array's taxels or electrodes, a grid of any size) or `camera` (a camera's images,
    /// cut into patches). Default: what the import read, `array` for CSV files and multi-arrays,
    /// `camera` for videos, frames and images.
    #[arg(long, value_enum)]
    pub sensor: Option<pvt3_spec::Sensor>,
    #[command(flatten)]
    pub camera: CameraArgs,
}

/// How a camera's frames are read (videos, frame folders or still images only).
#[derive(clap::Args)]
#[command(next_help_heading = "Camera touches (videos, frame folders, still images or ROS 2 bags)")]
pub struct CameraArgs {
    /// The rectangle of each frame to keep, HEIGHTxWIDTH+TOP+LEFT in pixels (e.g. 200x280+20+20
    /// to drop a 20-pixel border of 240 × 320 frames). Default: the whole frame.
    #[arg(long, value_name = "GEOMETRY")]
    pub crop: Option<Crop>,
    /// The size every frame is shrunk to, HEIGHTxWIDTH, by area averaging (each new pixel the
    /// mean of the pixels it covers). Default: as recorded.
    #[arg(long, value_name = "HEIGHTxWIDTH", value_parser = parse_size)]
    pub size: Option<(usize, usize)>,
    /// One grey channel instead of RGB.
    #[arg(long)]
    pub grey: bool,
    /// Frames a touch, spread evenly over the frames chosen by --frames-from. Default: 25, or 1
    /// where every touch is a still image (one image file, read once).
    #[arg(long)]
    pub frames: Option<usize>,
    /// Where the frames are taken: `moving`, the span in which the gel moves (the longest run of
    /// frames that change more than the recording's stillest; the whole recording where nothing
    /// moves), or `whole`.
    #[arg(long, value_enum, default_value_t = FrameSpan::default())]
    pub frames_from: FrameSpan,
    /// Keep each touch's first frame (the gel before contact) as its background: training and
    /// evaluation read the frames minus it (the PVT³ report's GelSight preprocessing).
    #[arg(long)]
    pub subtract_first: bool,
    /// Read a recording of fewer frames than --frames with its frames repeated (evenly), and
    /// list it, instead of refusing it.
    #[arg(long)]
    pub allow_short: bool,
}

impl CameraArgs {
    fn options(&self, naming: Naming, topic: Option<String>, sensor: Option<pvt3_spec::Sensor>) -> CameraOptions {
        let (crop, size, grey, frames, span) = (self.crop, self.size, self.grey, self.frames, self.frames_from);
        let (subtract_first, allow_short) = (self.subtract_first, self.allow_short);
        CameraOptions { naming, crop, size, grey, frames, span, subtract_first, allow_short, topic, sensor }
    }

    /// The camera options given on the command line (those left at their defaults not named).
    fn given(&self) -> Vec<&'static str> {
        let defaults = CameraOptions::default();
        let given = [
            (self.crop.is_some(), "--crop"),
            (self.size.is_some(), "--size"),
            (self.grey, "--grey"),
            (self.frames.is_some(), "--frames"),
            (self.frames_from != defaults.span, "--frames-from"),
            (self.subtract_first, "--subtract-first"),
            (self.allow_short, "--allow-short"),
        ];
        given.into_iter().filter_map(|(g, name)| g.then_some(name)).collect()
    }
}

/// `CONDITION=VALUE`, the value a number above 0.
fn parse_condition_value(s: &str) -> std::result::Result<(String, f64), String> {
    let bad = || format!("`{s}`: expected CONDITION=VALUE with a value above 0, e.g. speed=150");
    let (name, value) = s.split_once('=').ok_or_else(bad)?;
    let value = value.trim().parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0).ok_or_else(bad)?;
    Ok((name.trim().to_string(), value))
}

/// Two positive numbers `AxB`, or an error showing `example` (`what`, its form).
fn parse_pair(s: &str, what: &str, example: &str) -> std::result::Result<(usize, usize), String> {
    let parse = |v: &str| v.trim().parse::<usize>().ok().filter(|v| *v > 0);
    let pair = s.split_once(['x', 'X', '×']).and_then(|(a, b)| parse(a).zip(parse(b)));
    pair.ok_or_else(|| format!("`{s}`: expected {what}, e.g. {example}"))
}

fn parse_grid(s: &str) -> std::result::Result<(usize, usize), String> {
    parse_pair(s, "ROWSxCOLS", "6x10")
}

fn parse_size(s: &str) -> std::result::Result<(usize, usize), String> {
    parse_pair(s, "HEIGHTxWIDTH", "60x80")
}

pub fn run(a: ImportArgs) -> Result<()> {
    if !a.dir.is_dir() {
        bail!("{} is not a folder (expected one folder per class of touches)", a.dir.display());
    }
    let naming = match (&a.labels, &a.name) {
        (Some(file), _) => Naming::Labels(Labels::read(file)?),
        (None, Some(pattern)) => Naming::Pattern(pattern.clone()),
        (None, None) => Naming::Folders,
    };
    if holds_camera_touches(&a.dir, &naming, a.topic.as_deref()) {
        return run_camera(a, naming);
    }
    if let Some(option) = a.camera.given().first() {
        bail!("{option} is for a camera's touches (videos or frame folders), and {} holds none", a.dir.display());
    }
    let (columns, grid, topic) = (a.columns, a.grid, a.topic);
    let (per_distance, per_force, sensor) = (a.per_distance, a.per_force, a.sensor);
    let opts = ImportOptions { columns, grid, naming, per_distance, per_force, topic, sensor };
    let set = read_folder(&a.dir, &opts)?;
    set.write_npz(&a.out).with_context(|| format!("writing {}", a.out.display()))?;
    let (shortest, longest) = set.length_range();
    println!("{}, {shortest} to {longest} frames a touch", touches(&set.per_class()));
    let layout = match (set.grid, &set.layout) {
        (Some((h, w)), Some(dims)) if opts.grid.is_none() && dims[..] == [h, w] => format!("a {h} × {w} grid (the messages' layout)"),
        (Some((h, w)), _) => format!("a {h} × {w} grid"),
        (None, _) => "one column".into(),
    };
    println!("{} channels as {layout}, {}: {}", set.channels.len(), recorded_as(set.sensor), elided(&set.channels));
    if let Some((name, speed)) = &opts.per_distance {
        println!("every touch resampled from time to distance: to the frames it would have at {name} {speed}");
    }
    if let Some((name, force)) = &opts.per_force {
        println!("every touch's readings scaled to {name} {force}");
    }
    print_conditions(&set.conditions);
    for (name, why) in &set.left_out {
        println!("left out: {name} ({why})");
    }
    print_timings(&set.timings);
    println!("wrote {}; next: pvt3 cv --data {}", a.out.display(), a.out.display());
    Ok(())
}

/// `pvt3 import` of a camera's touches.
fn run_camera(a: ImportArgs, naming: Naming) -> Result<()> {
    let given: Vec<&str> = [
        (!a.columns.is_empty(), "--columns"),
        (a.grid.is_some(), "--grid"),
        (a.per_distance.is_some(), "--per-distance"),
        (a.per_force.is_some(), "--per-force"),
    ]
    .into_iter()
    .filter_map(|(g, name)| g.then_some(name))
    .collect();
    if let Some(option) = given.first() {
        bail!("{option} is for CSV touches, and {} holds a camera's (videos or frame folders)", a.dir.display());
    }
    let opts = a.camera.options(naming, a.topic, a.sensor);
    let bar = progress::bar("decoding");
    let set = read_camera_folder(&a.dir, &opts, |done, all| {
        bar.set_length(all as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    set.write_npz(&a.out).with_context(|| format!("writing {}", a.out.display()))?;
    describe_camera(&set, &opts);
    println!("wrote {}; next: pvt3 cv --data {}", a.out.display(), a.out.display());
    Ok(())
}

/// The kind of sensor the set records, in words, with the option that changes it.
fn recorded_as(sensor: pvt3_spec::Sensor) -> String {
    let other = match sensor {
        pvt3_spec::Sensor::Array => pvt3_spec::Sensor::Camera,
        pvt3_spec::Sensor::Camera => pvt3_spec::Sensor::Array,
    };
    format!("recorded as {sensor}'s (--sensor {} for {other}'s)", other.name())
}

/// `N touches of K classes (A to B touches a class)`, from the touches per class.
fn touches(per_class: &[usize]) -> String {
    let (fewest, most) = (per_class.iter().min().unwrap_or(&0), per_class.iter().max().unwrap_or(&0));
    format!("{} touches of {} classes ({fewest} to {most} touches a class)", per_class.iter().sum::<usize>(), per_class.len())
}

fn print_conditions(conditions: &[Condition]) {
    for c in conditions {
        println!("condition {}: {}", c.name, c.distinct().join(", "));
    }
}

fn describe_camera(set: &CameraSet, opts: &CameraOptions) {
    let [h, w, c] = set.frame_shape;
    let colour = if c == 1 { "grey" } else { "RGB" };
    if set.spans.iter().all(|s| s.0 == 1) && set.frames == 1 {
        println!(
            "{}: each one still image of {h} × {w} {colour}, read as one frame, stored as 8-bit, {}",
            touches(&set.per_class()),
            recorded_as(set.sensor)
        );
        print_conditions(&set.conditions);
        return;
    }
    println!(
        "{}: {} frames of {h} × {w} {colour} each, stored as 8-bit, {}",
        touches(&set.per_class()),
        set.frames,
        recorded_as(set.sensor)
    );
    let recorded = set.spans.iter().map(|s| s.0);
    let taken = set.spans.iter().map(|s| s.2 + 1 - s.1);
    println!(
        "frames taken from {}: spans of {} to {} of {} to {} recorded",
        match opts.span {
            FrameSpan::Moving => "the span in which the gel moves",
            FrameSpan::Whole => "the whole recording",
        },
        taken.clone().min().unwrap_or(0),
        taken.max().unwrap_or(0),
        recorded.clone().min().unwrap_or(0),
        recorded.max().unwrap_or(0)
    );
    if opts.subtract_first {
        println!("each touch's first frame kept as its background: its frames are read minus it");
    }
    for (source, recorded) in set.short() {
        println!("short: {source} has {recorded} frames, repeated to {}", set.frames);
    }
    print_timings(&set.timings);
    print_conditions(&set.conditions);
}

/// The touches of a bag whose frames' times strayed, each with how.
fn print_timings(timings: &[(String, Timing)]) {
    for (source, t) in timings {
        println!(
            "times: {source} has {} gaps (frames dropped), {} repeated stamps, {} frames out of order",
            t.gaps, t.repeated, t.out_of_order
        );
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn grids_parse_rows_by_columns() {
        assert_eq!(super::parse_grid("6x10"), Ok((6, 10)));
        assert_eq!(super::parse_grid("19×1"), Ok((19, 1)));
        assert!(super::parse_grid("60").unwrap_err().contains("expected ROWSxCOLS"));
        assert!(super::parse_grid("0x4").is_err());
    }
}
