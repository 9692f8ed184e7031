//! The pictures looked at: each SVG is rendered by librsvg (`rsvg-convert`, Debian's
//! librsvg2-bin, which tests/run.sh installs) and its pixels are checked where the curves, the
//! marked epoch and the matrix's cells must be.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::chart::COLORS;
use super::{anytime, confusion, curves};
use crate::metrics::EpochMetrics;

/// `svg` rendered to RGBA pixels: (width, height, pixels).
fn render(svg: &str, tag: &str) -> (usize, usize, Vec<u8>) {
    let dir = std::env::temp_dir().join(format!("pvt3-plot-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (svg_path, png_path): (PathBuf, PathBuf) = (dir.join("a.svg"), dir.join("a.png"));
    super::write(&svg_path, svg).unwrap();
    let out = Command::new("rsvg-convert")
        .arg(&svg_path)
        .arg("-o")
        .arg(&png_path)
        .output()
        .unwrap_or_else(|e| panic!("rsvg-convert ({e}): apt-get install librsvg2-bin, as tests/run.sh does"));
    assert!(out.status.success(), "librsvg refused the picture: {}", String::from_utf8_lossy(&out.stderr));
    let pixels = decode(&png_path);
    std::fs::remove_dir_all(dir).unwrap();
    pixels
}

fn decode(path: &Path) -> (usize, usize, Vec<u8>) {
    let mut decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    let rgba = match info.color_type {
        png::ColorType::Rgba => buf,
        png::ColorType::Rgb => buf.chunks(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect(),
        other => panic!("librsvg rendered {other:?}, expected RGB or RGBA"),
    };
    (info.width as usize, info.height as usize, rgba)
}

fn rgb(hex: &str) -> [u8; 3] {
    let v = u32::from_str_radix(&hex[1..], 16).unwrap();
    [(v >> 16) as u8, (v >> 8) as u8, v as u8]
}

/// Pixels within 40 of `color` (each channel) in the columns `x0..x1`.
fn count(image: &(usize, usize, Vec<u8>), color: [u8; 3], x0: usize, x1: usize) -> usize {
    count_near(image, color, x0, x1, 40)
}

fn count_near(image: &(usize, usize, Vec<u8>), color: [u8; 3], x0: usize, x1: usize, tolerance: i32) -> usize {
    let (w, _, px) = image;
    px.chunks(4).enumerate().filter(|(i, p)| (x0..x1).contains(&(i % w)) && near(p, color, tolerance)).count()
}

/// An RGBA pixel, opaque and within `tolerance` of `color` in each channel.
fn near(p: &[u8], color: [u8; 3], tolerance: i32) -> bool {
    p[3] > 200 && (0..3).all(|c| (p[c] as i32 - color[c] as i32).abs() <= tolerance)
}

/// `color` drawn at `opacity` on white.
fn on_white(color: [u8; 3], opacity: f64) -> [u8; 3] {
    color.map(|c| (c as f64 * opacity + 255.0 * (1.0 - opacity)).round() as u8)
}

fn epochs(n: usize) -> Vec<EpochMetrics> {
    (1..=n)
        .map(|e| {
            let t = e as f64 / n as f64;
            EpochMetrics {
                epoch: e,
                lr: 1e-3 * (1.0 - 0.9 * t),
                train_loss: 2.0 * (1.0 - t) + 0.1,
                train_accuracy: 0.3 + 0.6 * t,
                val_loss: 2.1 * (1.0 - t) + 0.3,
                val_accuracy: 0.25 + 0.6 * t,
                test_accuracy: (e % 3 == 0).then_some(0.2 + 0.6 * t),
                seconds: 1.0,
                encodings_apart: None,
            }
        })
        .collect()
}

#[test]
fn a_run_s_curves_show_both_losses_both_accuracies_and_the_selected_epoch() {
    let image = render(&curves::run_figure("run", &epochs(30), Some(24)), "run");
    let (w, h, _) = image;
    assert_eq!((w, h), (1260, 330), "three panels");
    // Training (blue) and validation (vermilion) in the loss panel and the accuracy panel.
    for panel in 0..2 {
        let (x0, x1) = (panel * 420, (panel + 1) * 420);
        for color in [COLORS[0], COLORS[1]] {
            assert!(count(&image, rgb(color), x0, x1) > 150, "panel {panel}: {color}");
        }
    }
    assert!(count(&image, rgb(COLORS[2]), 420, 840) > 20, "test accuracies as dots");
    assert!(count(&image, rgb(COLORS[6]), 840, 1260) > 150, "the learning rate");
    // The selected epoch's dashed grey line, at epoch 24 of 1..=30 on the 348 px wide axes
    // that start at x = 56 (x = 332); half of its 220 px drawn.
    let grey = |(w, _, px): &(usize, usize, Vec<u8>)| {
        // Inside the axes' frame (y = 66 to 286), clear of its edges.
        let column = |i: usize| (330..335).contains(&(i % w)) && (70..282).contains(&(i / w));
        px.chunks(4).enumerate().filter(|(i, p)| column(*i) && p[0] == p[1] && p[1] == p[2] && (0x30..0xd0).contains(&p[0])).count()
    };
    assert!(grey(&image) > 80, "the marked epoch: {}", grey(&image));
    // Without a selected epoch (a run still at its first epoch), no marker.
    let unmarked = render(&curves::run_figure("run", &epochs(30), None), "unmarked");
    assert!(grey(&unmarked) < 10, "{}", grey(&unmarked));
}

#[test]
fn a_cross_validation_figure_draws_every_run() {
    let runs: Vec<_> = (0..4).map(|k| (format!("seed0/fold{k}"), epochs(10 + k), Some(8))).collect();
    let image = render(&curves::cv_figure("cv", &runs), "cv");
    // Each run a faint line (45 % opaque) of its own colour in both panels.
    for color in &COLORS[..4] {
        for (x0, x1) in [(0, 420), (420, 840)] {
            let n = count_near(&image, on_white(rgb(color), 0.45), x0, x1, 20);
            assert!(n > 40, "{color} in {x0}..{x1}: {n}");
        }
    }
}

/// Of the rows holding pixels near `color` (within 40) in the columns `x0..x1`: how many, and
/// the most such pixels in one.
fn rows_and_widest(image: &(usize, usize, Vec<u8>), color: [u8; 3], x0: usize, x1: usize) -> (usize, usize) {
    let (w, h, px) = image;
    let widths: Vec<usize> = (0..*h).map(|y| (x0..x1).filter(|&x| near(&px[(y * w + x) * 4..], color, 40)).count()).collect();
    (widths.iter().filter(|&&n| n > 0).count(), widths.into_iter().max().unwrap_or(0))
}

#[test]
fn a_legend_marks_a_series_of_dots_with_a_dot() {
    let runs: Vec<_> = (0..4).map(|k| (format!("seed0/fold{k}"), epochs(12), Some(8))).collect();
    let image = render(&curves::cv_figure("cv", &runs), "legend");
    // The accuracy panel's one entry, "selected epochs" (the runs are faint, unlisted): left of
    // its text at x = 56 + 8 + 16, clear of the selected epochs' dots (x ≈ 260).
    let (rows, widest) = rows_and_widest(&image, rgb(COLORS[6]), 56, 80);
    assert!(rows >= 3 && (3..=7).contains(&widest), "a dot, not a 12 px bar: {rows} rows, {widest} px at most");
    // A line's entry stays a bar: the run figure's learning rate, in its third panel.
    let image = render(&curves::run_figure("run", &epochs(30), None), "legend-line");
    let (_, widest) = rows_and_widest(&image, rgb(COLORS[6]), 840 + 56, 840 + 80);
    assert!(widest >= 11, "a bar: {widest} px");
}

#[test]
fn the_confusion_matrix_shades_each_cell_by_its_share_of_the_true_class() {
    let names: Vec<String> = ["cotton", "denim", "silk"].map(String::from).to_vec();
    let labels = [0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2];
    let answers = [0, 0, 0, 0, 1, 1, 2, 2, 2, 2, 2, 2];
    let m = confusion::matrix(&labels, &answers, 3);
    assert_eq!(m, vec![vec![4, 0, 0], vec![0, 2, 2], vec![0, 0, 4]]);
    let text = confusion::text(&m, &names);
    assert!(text.lines().nth(3).unwrap().contains(" 1  denim") && text.lines().nth(3).unwrap().ends_with("0 2 2"), "{text}");
    let image = render(&confusion::svg(&m, &names, "fold 4"), "confusion");
    let (w, _, px) = &image;
    // The cells: 48 px squares from (x0, y0); the label room is the longest name's.
    let room = 12.0 + 6.5 * 6.0;
    let (x0, y0) = (room + 24.0, room + 48.0);
    let at = |r: usize, c: usize| {
        // A cell's corner, clear of its count's digits.
        let (x, y) = ((x0 + c as f64 * 48.0 + 6.0) as usize, (y0 + r as f64 * 48.0 + 6.0) as usize);
        let p = &px[(y * w + x) * 4..(y * w + x) * 4 + 3];
        [p[0], p[1], p[2]]
    };
    assert_eq!(at(0, 0), rgb("#08306b"), "a whole row answered right: the deepest blue");
    assert_eq!(at(0, 1), [255, 255, 255], "never answered: white");
    let half = at(1, 1);
    assert!(half[0] > 100 && half[0] < 160 && half == at(1, 2), "half the row: half the shade, {half:?}");
    // A title longer than the grid is wide widens the picture: its ink clear of both edges.
    let title = "runs/a-long-name/seed0/fold0: fold 4, 56 touches, accuracy 0.8393";
    let (w, _, px) = render(&confusion::svg(&m, &names, title), "confusion-title");
    let inked: Vec<usize> = (0..w * 24).filter(|&i| px[i * 4 + 3] > 200 && px[i * 4] < 128).map(|i| i % w).collect();
    let (left, right) = (inked.iter().min().copied().unwrap_or(0), inked.iter().max().copied().unwrap_or(w));
    assert!(!inked.is_empty() && left >= 4 && right + 4 < w, "the title's ink spans x = {left}..={right} of {w}");
}

/// Four touches of four tokens under a rule of top probability ≥ 0.8 with two answers agreeing:
/// touch 1 is stopped after two tokens with a wrong answer the rest of it corrects, touch 2 never.
#[test]
fn the_anytime_picture_shows_accuracy_so_far_and_the_rule_s_wrong_stops() {
    let prefixes = crate::anytime::Prefixes {
        top: vec![vec![0.5, 0.9, 0.9, 0.9], vec![0.9, 0.9, 0.6, 0.7], vec![0.3, 0.5, 0.6, 0.7], vec![0.9, 0.85, 0.9, 0.9]],
        class: vec![vec![0, 0, 0, 0], vec![2, 2, 1, 1], vec![1, 2, 2, 2], vec![3, 3, 3, 3]],
        labels: vec![0, 1, 2, 3],
        tokens: 4,
    };
    let rule = pvt3_format::StopRule { top_probability: 0.8, agreeing: 2 };
    let [accuracy, ended] = anytime::panels(&prefixes, rule);
    let points = |panel: &super::chart::Panel, k: usize| panel.series[k].points.clone();
    assert_eq!(points(&accuracy, 0), vec![(25.0, 0.5), (50.0, 0.75), (75.0, 1.0), (100.0, 1.0)]);
    // Stopped after 2, 2, 4 and 2 tokens: 62.5 % of the touch on average, three of four right.
    assert_eq!(points(&accuracy, 1), vec![(62.5, 0.75)]);
    assert_eq!(accuracy.marker.as_ref().map(|m| m.0), Some(62.5));
    assert_eq!(points(&ended, 0), vec![(25.0, 0.0), (50.0, 0.75), (75.0, 0.75), (100.0, 1.0)]);
    assert_eq!(points(&ended, 1), vec![(25.0, 0.0), (50.0, 0.5), (75.0, 0.5), (100.0, 0.75)]);
    let image = render(&anytime::svg("anytime", &prefixes, rule), "anytime");
    assert_eq!((image.0, image.1), (840, 330), "two panels");
    assert!(count(&image, rgb(COLORS[0]), 0, 420) > 150, "accuracy so far");
    assert!(count(&image, rgb(COLORS[1]), 0, 420) > 10, "the rule's dot");
    for color in [COLORS[6], COLORS[2]] {
        assert!(count(&image, rgb(color), 420, 840) > 150, "touches ended: {color}");
    }
}
