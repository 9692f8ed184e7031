//! Line charts: panels side by side, each with axes, ticks, a legend, its series and an optional
//! marked x (the selected epoch).

use std::fmt::Write;

use super::escape;

/// One line (or, with `dots`, points) of a panel.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub color: &'static str,
    pub points: Vec<(f64, f64)>,
    pub dots: bool,
    /// Thin and without a legend entry: one of many runs.
    pub faint: bool,
}

impl Series {
    pub fn line(name: &str, color: &'static str, points: Vec<(f64, f64)>) -> Self {
        Self { name: name.into(), color, points, dots: false, faint: false }
    }
}

#[derive(Clone, Debug, Default)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub series: Vec<Series>,
    /// The y axis's range; by default the data's, with a margin.
    pub y_range: Option<(f64, f64)>,
    /// A vertical line at this x, labelled.
    pub marker: Option<(f64, String)>,
    /// Where the legend goes: top left, or bottom right for curves that rise to the top.
    pub legend_low: bool,
}

/// Colours that stay apart for people with the common colour-vision deficiencies (Okabe & Ito).
pub const COLORS: [&str; 7] = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"];

const PANEL_W: f64 = 420.0;
const PANEL_H: f64 = 300.0;
const MARGIN: (f64, f64, f64, f64) = (56.0, 16.0, 36.0, 44.0); // left, right, top, bottom

/// About five round ticks (1, 2 or 5 × 10^k apart) covering `lo..hi`.
pub fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return vec![lo];
    }
    let raw = (hi - lo) / 5.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * magnitude).find(|s| *s >= raw).unwrap_or(10.0 * magnitude);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

fn label(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e5) {
        format!("{v:.0e}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The range of a panel's y values, with a margin; `(0, 1)` if it has none.
fn data_range(panel: &Panel) -> (f64, f64) {
    let ys = panel.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)).filter(|y| y.is_finite());
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| (lo.min(y), hi.max(y)));
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(hi.abs() * 1e-3).max(1e-12);
    (lo - pad, hi + pad)
}

/// The panels side by side under `title`, as an SVG document.
pub fn figure(title: &str, panels: &[Panel]) -> String {
    let width = PANEL_W * panels.len().max(1) as f64;
    let height = PANEL_H + 30.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(s, r#"<text x="{}" y="20" text-anchor="middle" font-size="14">{}</text>"#, width / 2.0, escape(title));
    for (k, panel) in panels.iter().enumerate() {
        draw_panel(&mut s, panel, k as f64 * PANEL_W, 30.0);
    }
    s.push_str("</svg>\n");
    s
}

/// Where a panel draws its data: the plot area's edges (`x0..x1`, `y0..y1`, in the picture's
/// units) and the ranges of x and y they show.
struct Area {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    x_range: (f64, f64),
    y_range: (f64, f64),
}

impl Area {
    /// The plot area of `panel` at (`ox`, `oy`): within its margins, over its data's x range
    /// and its y range (given, or the data's).
    fn of(panel: &Panel, ox: f64, oy: f64) -> Self {
        let (left, right, top, bottom) = MARGIN;
        let xs = panel.series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
        let (xlo, xhi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
        let x_range = if xlo.is_finite() { (xlo, if xhi > xlo { xhi } else { xlo + 1.0 }) } else { (0.0, 1.0) };
        let y_range = panel.y_range.unwrap_or_else(|| data_range(panel));
        Self { x0: ox + left, x1: ox + PANEL_W - right, y0: oy + top, y1: oy + PANEL_H - bottom, x_range, y_range }
    }

    /// Where `x` is drawn.
    fn px(&self, x: f64) -> f64 {
        let (lo, hi) = self.x_range;
        self.x0 + (x - lo) / (hi - lo) * (self.x1 - self.x0)
    }

    /// Where `y` is drawn, held within the area.
    fn py(&self, y: f64) -> f64 {
        let (lo, hi) = self.y_range;
        self.y1 - (y.clamp(lo, hi) - lo) / (hi - lo) * (self.y1 - self.y0)
    }
}

fn draw_panel(s: &mut String, panel: &Panel, ox: f64, oy: f64) {
    let area = Area::of(panel, ox, oy);
    draw_axes(s, panel, &area, oy);
    let marker = panel.marker.as_ref().map(|(x, text)| (area.px(*x), text.as_str()));
    if let Some((x, _)) = marker {
        let (y0, y1) = (area.y0, area.y1);
        let _ = writeln!(s, r##"<line x1="{x:.1}" y1="{y0}" x2="{x:.1}" y2="{y1}" stroke="#777" stroke-dasharray="4 3"/>"##);
    }
    for series in &panel.series {
        draw_series(s, series, &area);
    }
    draw_legend(s, panel, &area, marker);
}

/// The panel's title (at `oy`), its y grid and ticks, its x ticks, its frame and the x axis's
/// label.
fn draw_axes(s: &mut String, panel: &Panel, area: &Area, oy: f64) {
    let Area { x0, x1, y0, y1, x_range: (xlo, xhi), y_range: (ylo, yhi) } = *area;
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle" font-size="12">{}</text>"#,
        (x0 + x1) / 2.0,
        oy + 16.0,
        escape(&panel.title)
    );
    for t in ticks(ylo, yhi) {
        let y = area.py(t);
        let _ = writeln!(s, r##"<line x1="{x0}" y1="{y:.1}" x2="{x1}" y2="{y:.1}" stroke="#e4e4e4"/>"##);
        let _ = writeln!(s, r#"<text x="{}" y="{:.1}" text-anchor="end">{}</text>"#, x0 - 4.0, y + 4.0, label(t));
    }
    for t in ticks(xlo, xhi).into_iter().filter(|t| t.fract() == 0.0 || xhi - xlo < 5.0) {
        let x = area.px(t);
        let _ = writeln!(s, r#"<line x1="{x:.1}" y1="{y1}" x2="{x:.1}" y2="{}" stroke="black"/>"#, y1 + 4.0);
        let _ = writeln!(s, r#"<text x="{x:.1}" y="{}" text-anchor="middle">{}</text>"#, y1 + 16.0, label(t));
    }
    let _ = writeln!(s, r#"<rect x="{x0}" y="{y0}" width="{}" height="{}" fill="none" stroke="black"/>"#, x1 - x0, y1 - y0);
    let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#, (x0 + x1) / 2.0, y1 + 32.0, escape(&panel.x_label));
}

/// A series' finite points: dots, or a line (thin and pale for a faint one).
fn draw_series(s: &mut String, series: &Series, area: &Area) {
    let points: Vec<String> =
        series.points.iter().filter(|p| p.1.is_finite()).map(|&(x, y)| format!("{:.1},{:.1}", area.px(x), area.py(y))).collect();
    if series.dots {
        for p in &points {
            let (x, y) = p.split_once(',').expect("x,y");
            let _ = writeln!(s, r#"<circle cx="{x}" cy="{y}" r="2.5" fill="{}"/>"#, series.color);
        }
    } else if !points.is_empty() {
        let (width, opacity) = if series.faint { (1.0, 0.45) } else { (1.8, 1.0) };
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="{width}" stroke-opacity="{opacity}"/>"#,
            points.join(" "),
            series.color
        );
    }
}

/// The marker's label (at the drawn x of `marker`) and the legend of the series that are not
/// faint, each where the panel leaves room for it.
fn draw_legend(s: &mut String, panel: &Panel, area: &Area, marker: Option<(f64, &str)>) {
    let Area { x0, x1, y0, y1, .. } = *area;
    let legend: Vec<&Series> = panel.series.iter().filter(|s| !s.faint).collect();
    let longest = legend.iter().map(|s| s.name.chars().count()).max().unwrap_or(0);
    let (w, h) = (16.0 + 6.5 * longest as f64 + 8.0, 14.0 * legend.len() as f64 + 4.0);
    if let Some((x, text)) = marker {
        // The label over the curves, haloed in white, on the side with room: left of a line in the
        // right half; at the top, or above a low legend (where curves rise to the top).
        let (tx, anchor) = if x > (x0 + x1) / 2.0 { (x - 3.0, "end") } else { (x + 3.0, "start") };
        let ty = if panel.legend_low { y1 - h - 8.0 } else { y0 + 12.0 };
        let _ = writeln!(
            s,
            r##"<text x="{tx:.1}" y="{ty}" text-anchor="{anchor}" fill="#555" stroke="white" stroke-width="3" paint-order="stroke">{}</text>"##,
            escape(text)
        );
    }
    let (lx, ly0) = match panel.legend_low {
        true => (x1 - w, y1 - h + 8.0),
        false => (x0 + 8.0, y0 + 14.0 + if panel.marker.is_some() { 10.0 } else { 0.0 }),
    };
    if !legend.is_empty() {
        // A pale ground, so that the entries stay legible over the curves they name.
        let _ = writeln!(s, r#"<rect x="{}" y="{}" width="{w}" height="{h}" fill="white" fill-opacity="0.85"/>"#, lx - 4.0, ly0 - 12.0);
    }
    for (k, series) in legend.iter().enumerate() {
        let ly = ly0 + 14.0 * k as f64;
        let _ = writeln!(s, "{}", legend_mark(series, lx, ly));
        let _ = writeln!(s, r#"<text x="{}" y="{ly}">{}</text>"#, lx + 16.0, escape(&series.name));
    }
}

/// A legend entry's mark at (`x`, `y`), the baseline of its text: the series' own mark, a dot for
/// a series of points and a short bar for a line.
fn legend_mark(series: &Series, x: f64, y: f64) -> String {
    if series.dots {
        format!(r#"<circle cx="{}" cy="{}" r="2.5" fill="{}"/>"#, x + 6.0, y - 3.5, series.color)
    } else {
        format!(r#"<rect x="{x}" y="{}" width="12" height="3" fill="{}"/>"#, y - 4.0, series.color)
    }
}
