//! A camera touch's frames from its file: a video through `ffmpeg` (any format it reads: the
//! MPEG-4 of PhysiCLeAR's GelSight videos, H.264, …), a folder of PNG or JPEG frames read in
//! name order, or one PNG or JPEG image, a still touch of one frame (pure Rust). Every frame
//! comes out as 8-bit RGB or grey, as recorded.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use pvt3_format::Picture;

/// The video files `pvt3 import` reads (by extension, any case).
pub const VIDEO_EXTENSIONS: [&str; 7] = ["mov", "mp4", "avi", "mkv", "webm", "m4v", "mpg"];
/// The frame images a folder of frames holds (by extension, any case).
pub const IMAGE_EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

fn has_extension(path: &Path, extensions: &[&str]) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| extensions.iter().any(|x| x.eq_ignore_ascii_case(e)))
}

/// Whether `path` is a camera touch: a video file, a folder holding frame images, a still
/// image ([`is_still`]), or a ROS 2 bag ([`is_bag`]; its topic is checked as it is read).
pub fn is_camera_touch(path: &Path) -> bool {
    (path.is_file() && has_extension(path, &VIDEO_EXTENSIONS))
        || is_still(path)
        || is_bag(path)
        || (path.is_dir() && !frame_files(path).unwrap_or_default().is_empty())
}

/// Whether `path` is a still touch: one image file, its one frame (as still-image sets lay out
/// their touches: a class folder of images).
pub fn is_still(path: &Path) -> bool {
    path.is_file() && has_extension(path, &IMAGE_EXTENSIONS)
}

/// Whether `path` is a ROS 2 bag, in a build that reads them (the `bags` feature, on by default).
pub fn is_bag(path: &Path) -> bool {
    #[cfg(feature = "bags")]
    let bag = super::bag::is_bag(path);
    #[cfg(not(feature = "bags"))]
    let bag = {
        let _ = path;
        false
    };
    bag
}

/// Whether the bag at `path` holds a camera's frames on `topic`, or no topic it can read (the
/// camera's import then says why, listing its topics): not a taxel array's values.
pub fn bag_holds_camera(path: &Path, topic: Option<&str>) -> bool {
    #[cfg(feature = "bags")]
    let camera = super::bag::Bag::open(path).and_then(|bag| bag.topic_kind(topic)).map_or(true, |(_, kind)| kind.is_camera());
    #[cfg(not(feature = "bags"))]
    let camera = {
        let _ = (path, topic);
        true
    };
    camera
}

/// Every frame of a touch, in order: a video's, a folder's images by name, or a still image.
pub fn frames(path: &Path) -> Result<Vec<Picture>, String> {
    if is_still(path) {
        return Ok(vec![image(path)?]);
    }
    if path.is_dir() {
        let files = frame_files(path).map_err(|e| e.to_string())?;
        let pictures = files.iter().map(|f| image(f).map_err(|e| format!("{}: {e}", f.file_name().unwrap_or_default().to_string_lossy())));
        let pictures = pictures.collect::<Result<Vec<_>, _>>()?;
        if let Some(odd) = pictures.iter().position(|p| p.shape() != pictures[0].shape()) {
            return Err(format!(
                "its images differ in size or colour: {} is {}, {} is {}",
                files[0].display(),
                pictures[0].describe(),
                files[odd].display(),
                pictures[odd].describe()
            ));
        }
        Ok(pictures)
    } else {
        video(path)
    }
}

/// The frame images of folder `dir`, in name order.
fn frame_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && has_extension(p, &IMAGE_EXTENSIONS))
        .collect();
    files.sort();
    Ok(files)
}

/// One PNG or JPEG image as 8-bit RGB, or grey where the file is grey.
fn image(path: &Path) -> Result<Picture, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    if has_extension(path, &["png"]) {
        pvt3_messages::png(&bytes)
    } else {
        pvt3_messages::jpeg(&bytes)
    }
}

/// Every frame of a video, as `ffmpeg` decodes it to 8-bit RGB.
fn video(path: &Path) -> Result<Vec<Picture>, String> {
    let probe = run(Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-show_entries", "stream=width,height"])
        .args(["-of", "csv=p=0:s=x"]))
    .arg(path)
    .output()
    .map_err(missing("ffprobe"))?;
    if !probe.status.success() {
        return Err(format!("not a video ffprobe reads: {}", String::from_utf8_lossy(&probe.stderr).trim()));
    }
    let size = String::from_utf8_lossy(&probe.stdout).trim().to_string();
    let (width, height) = size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<usize>().ok()?, h.parse::<usize>().ok()?)))
        .filter(|(w, h)| *w > 0 && *h > 0)
        .ok_or_else(|| format!("ffprobe found no video stream (it says `{size}`)"))?;
    let decoded = run(Command::new("ffmpeg").args(["-v", "error", "-nostdin", "-i"]))
        .arg(path)
        .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "pipe:1"])
        .output()
        .map_err(missing("ffmpeg"))?;
    if !decoded.status.success() {
        return Err(format!("ffmpeg could not decode it: {}", String::from_utf8_lossy(&decoded.stderr).trim()));
    }
    let frame = height * width * 3;
    Ok(decoded.stdout.chunks_exact(frame).map(|data| Picture { height, width, channels: 3, data: data.to_vec() }).collect())
}

/// `command` with its output captured and nothing read from the terminal.
fn run(command: &mut Command) -> &mut Command {
    command.stdin(Stdio::null())
}

/// The error of a decoder that does not run, naming the package that installs it.
fn missing(program: &'static str) -> impl Fn(std::io::Error) -> String {
    move |e| {
        format!("{program} does not run ({e}): videos are decoded by FFmpeg (Debian and Ubuntu: apt-get install ffmpeg; macOS: brew install ffmpeg)")
    }
}
