//! Camera touches made here, written as PNG frame folders and as videos (by FFmpeg, losslessly),
//! imported and read back; and the errors a user's own files can provoke.

use std::path::{Path, PathBuf};

use super::*;
use crate::data::import::folder::holds_camera_touches;
use crate::data::Dataset;

const H: usize = 8;
const W: usize = 10;
const RECORDED: usize = 12;

/// Frame `f` of touch `touch` of class `class`: a level of its class before and after contact,
/// and while the gel moves (frames 4 to 8) a bright square that slides one pixel a frame.
fn frame(class: usize, touch: usize, f: usize) -> Picture {
    let mut data = vec![0u8; H * W * 3];
    for (i, v) in data.iter_mut().enumerate() {
        let (y, x, c) = (i / (W * 3), i / 3 % W, i % 3);
        let in_square = (4..=8).contains(&f) && (2..6).contains(&y) && (f - 3 + touch..f + 1 + touch).contains(&x);
        *v = if in_square { 200 + (10 * c) as u8 } else { (30 * class + 5 * c + y) as u8 };
    }
    Picture { height: H, width: W, channels: 3, data }
}

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-camera-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_png(path: &Path, p: &Picture) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut encoder = png::Encoder::new(file, p.width as u32, p.height as u32);
    encoder.set_color(if p.channels == 3 { png::ColorType::Rgb } else { png::ColorType::Grayscale });
    encoder.write_header().unwrap().write_image_data(&p.data).unwrap();
}

/// A lossless video of `frames` (FFV1 in Matroska, or whatever `path`'s extension holds).
fn write_video(path: &Path, frames: &[Picture]) {
    use std::io::Write;
    let size = format!("{}x{}", frames[0].width, frames[0].height);
    let mut ffmpeg = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", &size, "-r", "25", "-i", "pipe:0"])
        .args(["-c:v", "ffv1", "-pix_fmt", "bgr0"])
        .arg(path)
        .stdin(std::process::Stdio::piped())
        .spawn()
        .expect("ffmpeg runs (apt-get install ffmpeg)");
    let mut stdin = ffmpeg.stdin.take().unwrap();
    frames.iter().for_each(|f| stdin.write_all(&f.data).unwrap());
    drop(stdin);
    assert!(ffmpeg.wait().unwrap().success());
}

/// Two classes of five touches: `DIR/<class>/<touch>/<frame>.png`.
fn frame_folders(tag: &str) -> PathBuf {
    let dir = scratch(tag);
    for (class, name) in ["felt", "rough_cloth"].iter().enumerate() {
        for touch in 0..5 {
            let folder = dir.join(name).join(format!("touch_{touch}"));
            std::fs::create_dir_all(&folder).unwrap();
            for f in 0..RECORDED {
                write_png(&folder.join(format!("frame_{f:03}.png")), &frame(class, touch, f));
            }
        }
    }
    dir
}

/// The same touches as videos side by side, `<class>_t<take>.mkv`.
fn videos(tag: &str) -> PathBuf {
    let dir = scratch(tag);
    for (class, name) in ["felt", "rough_cloth"].iter().enumerate() {
        for touch in 0..5 {
            let frames: Vec<Picture> = (0..RECORDED).map(|f| frame(class, touch, f)).collect();
            write_video(&dir.join(format!("{name}_t{touch}.mkv")), &frames);
        }
    }
    dir
}

fn options(frames: usize, span: FrameSpan) -> CameraOptions {
    CameraOptions { size: Some((4, 5)), frames: Some(frames), span, ..CameraOptions::default() }
}

/// Frame `f` of `x` `[N, H, W, C, T]` for touch `n`, as a picture.
fn taken(set: &CameraSet, n: usize, f: usize) -> Picture {
    let [h, w, c] = set.frame_shape;
    let t = set.frames;
    let data = (0..h * w * c).map(|p| set.x[(n * h * w * c + p) * t + f]).collect();
    Picture { height: h, width: w, channels: c, data }
}

#[test]
fn frame_folders_import_as_shrunk_8_bit_frames_evenly_over_the_touch() {
    let dir = frame_folders("folders");
    assert!(holds_camera_touches(&dir, &Naming::Folders, None));
    let set = read_camera_folder(&dir, &options(4, FrameSpan::Whole), |_, _| {}).unwrap();
    assert_eq!((set.frame_shape, set.frames, set.per_class()), ([4, 5, 3], 4, vec![5, 5]));
    assert_eq!(set.sources[6], "rough_cloth/touch_1");
    // Frames 1, 4, 7 and 10 of 12: the middle of each quarter.
    for (k, f) in [1, 4, 7, 10].into_iter().enumerate() {
        assert_eq!(taken(&set, 6, k), frame(1, 1, f).resize(4, 5), "frame {f}");
    }
    assert_eq!(set.spans[0], (RECORDED, 0, RECORDED - 1));
    let out = dir.join("set.npz");
    set.write_npz(&out).unwrap();
    let data = Dataset::load(&out, 0).unwrap();
    assert_eq!((data.sample_shape.clone(), data.labels[6]), (vec![4, 5, 3, 4], 1));
    assert_eq!(data.class_names.as_deref().unwrap(), ["felt", "rough_cloth"]);
    let at = |n: usize, i: usize| data.sample(n)[i];
    assert_eq!(at(6, 4 * 3 + 1), f32::from(set.x[(6 * 60 + 3) * 4 + 1]));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn videos_import_as_their_frames_do_from_where_the_gel_moves_minus_the_first() {
    let (folders, videos) = (frame_folders("same-a"), videos("same-b"));
    let grey = CameraOptions { grey: true, ..options(4, FrameSpan::Moving) };
    let a = read_camera_folder(&folders, &grey, |_, _| {}).unwrap();
    let named = CameraOptions { naming: Naming::Pattern("{class}_t{take}".parse().unwrap()), subtract_first: true, ..grey.clone() };
    let b = read_camera_folder(&videos, &named, |_, _| {}).unwrap();
    // The square appears at frame 4 and is gone at frame 9: frames 4, 6, 7 and 9 of that span.
    assert_eq!(a.spans[3], (RECORDED, 4, 9));
    assert_eq!(taken(&a, 3, 1), frame(0, 3, 6).resize(4, 5).grey());
    assert_eq!((a.x.clone(), a.labels.clone(), a.frame_shape), (b.x.clone(), b.labels.clone(), [4, 5, 1]), "decoded losslessly");
    assert_eq!(b.classes, ["felt", "rough_cloth"]);
    assert_eq!((b.conditions[0].name.as_str(), b.conditions[0].levels[7].as_str()), ("take", "2"));
    let out = videos.join("set.npz");
    b.write_npz(&out).unwrap();
    // A background that is not x's shape without its frame axis is refused, naming the file.
    let bad = videos.join("bad.npz");
    let mut w = ndarray_npy::NpzWriter::new(std::fs::File::create(&bad).unwrap());
    w.add_array(key::X, &ndarray::Array3::<u8>::zeros((10, 4, 3))).unwrap();
    w.add_array(key::Y, &ndarray::Array1::<i64>::zeros(10)).unwrap();
    w.add_array(key::BACKGROUND, &ndarray::Array2::<u8>::zeros((10, 3))).unwrap();
    w.finish().unwrap();
    let msg = Dataset::load(&bad, 0).unwrap_err().to_string();
    assert!(msg.contains("bad.npz") && msg.contains("`background` has shape [10, 3]; expected [10, 4]"), "{msg}");
    let data = Dataset::load(&out, 0).unwrap();
    let background = frame(1, 2, 0).resize(4, 5).grey();
    let x = data.sample(7);
    assert_eq!(data.sample_shape, [4, 5, 4]);
    for p in 0..20 {
        for f in 0..4 {
            assert_eq!(x[p * 4 + f], f32::from(b.x[(7 * 20 + p) * 4 + f]) - f32::from(background.data[p]));
        }
    }
    std::fs::remove_dir_all(folders).unwrap();
    std::fs::remove_dir_all(videos).unwrap();
}

#[test]
fn a_touch_that_cannot_be_read_is_an_error_naming_its_file() {
    let dir = frame_folders("errors");
    let err = |dir: &Path, opts: &CameraOptions| read_camera_folder(dir, opts, |_, _| {}).unwrap_err().to_string();
    let msg = err(&dir, &options(20, FrameSpan::Whole));
    assert!(msg.contains("felt/touch_0: 12 frames, fewer than the 20 a touch takes (--frames 12 takes 12 frames a touch; --allow-short repeats a short touch's frames)"), "{msg}");
    // A touch's folder of one image: --frames 1 reads it as a still image.
    let one = scratch("one-frame");
    for touch in 0..5 {
        std::fs::create_dir_all(one.join(format!("felt/touch_{touch}"))).unwrap();
        write_png(&one.join(format!("felt/touch_{touch}/frame.png")), &frame(0, touch, 0));
    }
    let msg = err(&one, &options(20, FrameSpan::Whole));
    assert!(
        msg.contains("felt/touch_0: 1 frame, fewer than the 20 a touch takes (--frames 1 takes 1 frame a touch, a still image as itself;"),
        "{msg}"
    );
    std::fs::remove_dir_all(&one).unwrap();
    let short = read_camera_folder(&dir, &CameraOptions { allow_short: true, ..options(20, FrameSpan::Whole) }, |_, _| {}).unwrap();
    assert_eq!((short.short().len(), short.short()[0]), (10, ("felt/touch_0", 12)));
    assert_eq!((taken(&short, 0, 0), taken(&short, 0, 1)), (taken(&short, 0, 1), frame(0, 0, 0).resize(4, 5)), "frame 0 twice");
    let msg = err(&dir, &CameraOptions { size: Some((9, 5)), ..options(4, FrameSpan::Whole) });
    assert!(msg.contains("the size 9 × 5 is not a shrinking of 8 × 10"), "{msg}");
    let msg = err(&dir, &CameraOptions { crop: Some("8x8+1+0".parse().unwrap()), ..options(4, FrameSpan::Whole) });
    assert!(msg.contains("the crop 8x8+1+0 does not fit in a frame of 8 × 10"), "{msg}");
    write_png(&dir.join("felt/touch_2/frame_005.png"), &frame(0, 2, 5).resize(4, 5));
    let msg = err(&dir, &options(4, FrameSpan::Whole));
    assert!(msg.contains("felt/touch_2: its images differ in size or colour") && msg.contains("frame_005.png is 4 × 5 RGB"), "{msg}");
    write_png(&dir.join("felt/touch_2/frame_005.png"), &frame(0, 2, 5).grey());
    let msg = err(&dir, &options(4, FrameSpan::Whole));
    assert!(msg.contains("frame_000.png is 8 × 10 RGB") && msg.contains("frame_005.png is 8 × 10 grey"), "{msg}");
    std::fs::write(dir.join("felt/touch_2/frame_005.png"), b"not a picture").unwrap();
    let msg = err(&dir, &options(4, FrameSpan::Whole));
    assert!(msg.contains("felt/touch_2: frame_005.png: not a readable PNG"), "{msg}");
    std::fs::remove_dir_all(dir.join("felt/touch_2")).unwrap();
    std::fs::write(dir.join("felt/touch_2.mov"), b"not a video").unwrap();
    let msg = err(&dir, &options(4, FrameSpan::Whole));
    assert!(msg.contains("felt/touch_2.mov: not a video ffprobe reads"), "{msg}");
    // Touches of different sizes need --size.
    std::fs::remove_file(dir.join("felt/touch_2.mov")).unwrap();
    let folder = dir.join("felt/touch_2");
    std::fs::create_dir_all(&folder).unwrap();
    (0..RECORDED).for_each(|f| write_png(&folder.join(format!("{f}.png")), &frame(0, 2, f).resize(4, 5)));
    let msg = err(&dir, &CameraOptions { size: None, ..options(4, FrameSpan::Whole) });
    assert!(msg.contains("felt/touch_2: its frames are 4 × 5 RGB") && msg.contains("--size shrinks every touch to one size"), "{msg}");
    // A touch of grey frames beside RGB ones needs --grey.
    (0..RECORDED).for_each(|f| write_png(&folder.join(format!("{f}.png")), &frame(0, 2, f).grey()));
    let msg = err(&dir, &CameraOptions { size: None, ..options(4, FrameSpan::Whole) });
    assert!(
        msg.contains("its frames are 8 × 10 grey") && msg.contains("touch_0's 8 × 10 RGB") && msg.contains("--grey greys them"),
        "{msg}"
    );
    assert_eq!(
        read_camera_folder(&dir, &CameraOptions { size: None, grey: true, ..options(4, FrameSpan::Whole) }, |_, _| {}).unwrap().frame_shape,
        [8, 10, 1]
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Still images listed by a labels file, wherever they lie: a camera's touches of one frame each.
#[test]
fn still_images_a_labels_file_lists_import_as_one_frame_each() {
    let dir = scratch("labelled-stills");
    let mut text = String::from("path,class\n");
    for touch in 0..10 {
        let at = format!("grasp_{touch}/camera_0.png");
        std::fs::create_dir_all(dir.join(format!("grasp_{touch}"))).unwrap();
        write_png(&dir.join(&at), &frame(touch % 2, touch, 6));
        text.push_str(&format!("{at},{}\n", ["held", "slipped"][touch % 2]));
    }
    std::fs::write(dir.join("slip.csv"), text).unwrap();
    let naming = Naming::Labels(crate::data::import::labels::Labels::read(&dir.join("slip.csv")).unwrap());
    assert!(holds_camera_touches(&dir, &naming, None) && !holds_camera_touches(&dir, &Naming::Folders, None));
    let set = read_camera_folder(&dir, &CameraOptions { naming, ..CameraOptions::default() }, |_, _| {}).unwrap();
    assert_eq!((set.frames, set.classes.as_slice(), set.per_class()), (1, &["held".to_string(), "slipped".to_string()][..], vec![5, 5]));
    assert!(set.spans.iter().all(|s| *s == (1, 0, 0)), "{:?}", set.spans);
    std::fs::remove_dir_all(dir).unwrap();
}
