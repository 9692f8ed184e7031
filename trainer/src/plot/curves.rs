//! Training curves: one run's losses (and a joint run's encodings' distance), accuracies and
//! learning rate per epoch with the selected epoch marked, and a cross-validation's runs together.

use std::path::Path;

use super::chart::{figure, Panel, Series, COLORS};
use crate::metrics::{self, EpochMetrics};
use crate::run_dir::Run;
use crate::Result;

fn points(m: &[EpochMetrics], value: impl Fn(&EpochMetrics) -> Option<f64>) -> Vec<(f64, f64)> {
    m.iter().filter_map(|e| value(e).map(|v| (e.epoch as f64, v))).collect()
}

/// One run: losses, accuracies (test where it was measured) and the learning rate, the epoch
/// validation selected marked.
pub fn run_figure(title: &str, m: &[EpochMetrics], selected: Option<usize>) -> String {
    let marker = selected.map(|e| (e as f64, format!("selected: epoch {e}")));
    let mut losses = vec![
        Series::line("training", COLORS[0], points(m, |e| Some(e.train_loss))),
        Series::line("validation", COLORS[1], points(m, |e| Some(e.val_loss))),
    ];
    // A joint run's: how far its encodings are from the other sensor's.
    let apart = points(m, |e| e.encodings_apart);
    if !apart.is_empty() {
        losses.push(Series::line("encodings apart (joint)", COLORS[3], apart));
    }
    let loss =
        Panel { title: "loss".into(), x_label: "epoch".into(), series: losses, y_range: None, marker: marker.clone(), ..Panel::default() };
    let accuracy = Panel {
        title: "accuracy".into(),
        x_label: "epoch".into(),
        series: vec![
            Series::line("training", COLORS[0], points(m, |e| Some(e.train_accuracy))),
            Series::line("validation", COLORS[1], points(m, |e| Some(e.val_accuracy))),
            Series { dots: true, ..Series::line("test (at improvements)", COLORS[2], points(m, |e| e.test_accuracy)) },
        ],
        y_range: Some((0.0, 1.0)),
        marker: marker.clone(),
        ..Panel::default()
    };
    let lr = Panel {
        title: "learning rate".into(),
        x_label: "epoch".into(),
        series: vec![Series::line("at the epoch's last step", COLORS[6], points(m, |e| Some(e.lr)))],
        y_range: None,
        marker,
        ..Panel::default()
    };
    figure(title, &[loss, accuracy, lr])
}

/// The epoch the `model/` checkpoint of the run in `dir` holds, once it has one.
pub fn selected_epoch(dir: &Path) -> Option<usize> {
    crate::checkpoint::load_meta(&Run(dir).model()).ok().map(|(_, meta)| meta.provenance.epoch)
}

/// Writes the training curves of the run in `dir` ([`run_figure`] of its `metrics.jsonl`), the
/// `selected` epoch marked (a training run's best so far, or [`selected_epoch`]); the path
/// written.
pub fn write_run(dir: &Path, selected: Option<usize>) -> Result<std::path::PathBuf> {
    let m = metrics::read(&Run(dir).metrics())?;
    let title = format!("{} · {} epochs", dir.display(), m.len());
    let path = Run(dir).curves();
    super::write(&path, &run_figure(&title, &m, selected))?;
    Ok(path)
}

/// A cross-validation: every run's validation accuracy and training loss per epoch, each
/// selected epoch a dot.
pub fn cv_figure(title: &str, runs: &[(String, Vec<EpochMetrics>, Option<usize>)]) -> String {
    let mut accuracy =
        Panel { title: "validation accuracy".into(), x_label: "epoch".into(), y_range: Some((0.0, 1.0)), ..Panel::default() };
    let mut loss = Panel { title: "training loss".into(), x_label: "epoch".into(), ..Panel::default() };
    let mut selected = Vec::new();
    for (k, (name, m, chosen)) in runs.iter().enumerate() {
        let color = COLORS[k % (COLORS.len() - 1)];
        accuracy.series.push(Series { faint: true, ..Series::line(name, color, points(m, |e| Some(e.val_accuracy))) });
        loss.series.push(Series { faint: true, ..Series::line(name, color, points(m, |e| Some(e.train_loss))) });
        if let Some(e) = chosen.and_then(|c| m.iter().find(|e| e.epoch == c)) {
            selected.push((e.epoch as f64, e.val_accuracy));
        }
    }
    accuracy.series.push(Series { dots: true, ..Series::line("selected epochs", COLORS[6], selected) });
    figure(title, &[accuracy, loss])
}

/// Writes the figure of the cross-validation in `out` from its runs `dirs` (each `seed*/fold*`);
/// the path written.
pub fn write_cv(out: &Path, dirs: &[std::path::PathBuf], title: &str, figure: &str) -> Result<std::path::PathBuf> {
    let mut runs = Vec::new();
    for dir in dirs {
        let name = dir.strip_prefix(out).unwrap_or(dir).display().to_string();
        runs.push((name, metrics::read(&Run(dir).metrics())?, selected_epoch(dir)));
    }
    let path = out.join(figure);
    super::write(&path, &cv_figure(title, &runs))?;
    Ok(path)
}
