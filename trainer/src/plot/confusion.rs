//! The confusion matrix of an evaluation: rows the true class, columns the answer, as text and
//! as a shaded SVG grid with the class names on both axes.

use std::fmt::Write;

use super::escape;

/// `counts[true][answered]` over `classes` classes.
pub fn matrix(labels: &[u32], predictions: &[u32], classes: usize) -> Vec<Vec<usize>> {
    let mut m = vec![vec![0; classes]; classes];
    for (l, p) in labels.iter().zip(predictions) {
        m[*l as usize][*p as usize] += 1;
    }
    m
}

/// A fixed-width table: a row per true class, a column per answer (numbered as the rows).
pub fn text(m: &[Vec<usize>], names: &[String]) -> String {
    let width = m.iter().flatten().max().map_or(1, |v| v.to_string().len()).max(m.len().to_string().len()) + 1;
    let name_width = names.iter().map(|n| n.chars().count()).max().unwrap_or(0).max(10);
    let mut s = format!("{:<w$}    answered →\n{:<w$}", "true ↓", "", w = name_width + 4);
    for k in 0..m.len() {
        let _ = write!(s, "{:>width$}", k);
    }
    s.push('\n');
    for (k, row) in m.iter().enumerate() {
        let _ = write!(s, "{:>2}  {:<name_width$}", k, names[k]);
        for v in row {
            let _ = write!(s, "{:>width$}", v);
        }
        s.push('\n');
    }
    s
}

/// The matrix as an SVG grid, each cell shaded by its share of its row (its true class).
pub fn svg(m: &[Vec<usize>], names: &[String], title: &str) -> String {
    let n = m.len().max(1);
    let cell = (480.0 / n as f64).clamp(14.0, 48.0);
    let label_room = 12.0 + 6.5 * names.iter().map(|s| s.chars().count()).max().unwrap_or(1) as f64;
    let (x0, y0) = (label_room + 24.0, label_room + 48.0);
    let (grid_width, height) = (x0 + cell * n as f64 + 20.0, y0 + cell * n as f64 + 20.0);
    // Wide enough for the title (14 px type, about 8 px a character), the grid centred below it.
    let width = grid_width.max(8.0 * title.chars().count() as f64 + 24.0);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(s, r#"<text x="{}" y="18" text-anchor="middle" font-size="14">{}</text>"#, width / 2.0, escape(title));
    let _ = writeln!(s, r#"<g transform="translate({} 0)">"#, (width - grid_width) / 2.0);
    let _ = writeln!(s, r#"<text x="{}" y="36" text-anchor="middle">answered</text>"#, x0 + cell * n as f64 / 2.0);
    let _ = writeln!(
        s,
        r#"<text x="12" y="{}" text-anchor="middle" transform="rotate(-90 12 {0})">true class</text>"#,
        y0 + cell * n as f64 / 2.0
    );
    for (k, name) in names.iter().enumerate() {
        let c = k as f64 * cell + cell / 2.0;
        let _ =
            writeln!(s, r#"<text x="{}" y="{}" text-anchor="end" dominant-baseline="middle">{}</text>"#, x0 - 4.0, y0 + c, escape(name));
        let (tx, ty) = (x0 + c, y0 - 4.0);
        let _ = writeln!(s, r#"<text x="{tx}" y="{ty}" transform="rotate(-60 {tx} {ty})">{}</text>"#, escape(name));
    }
    for (r, row) in m.iter().enumerate() {
        let total = row.iter().sum::<usize>().max(1) as f64;
        for (c, &v) in row.iter().enumerate() {
            let share = v as f64 / total;
            // White to deep blue (#08306b) by share.
            let mix = |full: f64| (255.0 + (full - 255.0) * share).round() as u8;
            let fill = format!("#{:02x}{:02x}{:02x}", mix(8.0), mix(48.0), mix(107.0));
            let (x, y) = (x0 + c as f64 * cell, y0 + r as f64 * cell);
            let _ = writeln!(s, r##"<rect x="{x:.1}" y="{y:.1}" width="{cell:.1}" height="{cell:.1}" fill="{fill}" stroke="#ccc"/>"##);
            if v > 0 && cell >= 18.0 {
                let ink = if share > 0.5 { "white" } else { "black" };
                let _ = writeln!(
                    s,
                    r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" dominant-baseline="middle" fill="{ink}">{v}</text>"#,
                    x + cell / 2.0,
                    y + cell / 2.0
                );
            }
        }
    }
    s.push_str("</g>\n</svg>\n");
    s
}
