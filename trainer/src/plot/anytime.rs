//! What part of a touch gives (`pvt3 eval --anytime`): accuracy from the start of each touch,
//! and where the stopping rule ends touches, rightly or not, so that a stop's cost can be seen.

use pvt3_format::StopRule;

use super::chart::{figure, Panel, Series, COLORS};
use crate::anytime::Prefixes;

/// The picture of [`panels`] under `title`.
pub fn svg(title: &str, prefixes: &Prefixes, rule: StopRule) -> String {
    figure(title, &panels(prefixes, rule))
}

/// Left: accuracy from the first tokens against the share of the touch read, and the rule's
/// accuracy at the share it reads on average (marked). Right: the share of touches the rule has
/// ended by each share of the touch (a touch it never stops ends with its last frame), and of
/// those with the right answer; the gap between the two is the rule's wrong stops.
pub fn panels(prefixes: &Prefixes, rule: StopRule) -> [Panel; 2] {
    let tokens = prefixes.tokens;
    let read = |k: usize| 100.0 * k as f64 / tokens as f64;
    let stopping = prefixes.stop_by(rule);
    let mean = 100.0 * stopping.mean_share;
    let marker = Some((mean, format!("the rule reads {mean:.0} % on average")));
    let x_label = "share of the touch read (%)".to_string();
    let accuracy = Panel {
        title: "accuracy from the start of the touch".into(),
        x_label: x_label.clone(),
        series: vec![
            Series::line("answer so far", COLORS[0], (1..=tokens).map(|k| (read(k), prefixes.accuracy_at(k))).collect()),
            Series { dots: true, ..Series::line("stopped by the rule", COLORS[1], vec![(mean, stopping.accuracy)]) },
        ],
        y_range: Some((0.0, 1.0)),
        marker: marker.clone(),
        legend_low: true,
    };
    let stops = prefixes.stops(rule);
    let ended_by = |right_only: bool| -> Vec<(f64, f64)> {
        let n = stops.len().max(1) as f64;
        (1..=tokens).map(|k| (read(k), stops.iter().filter(|&&(at, right)| at <= k && (right || !right_only)).count() as f64 / n)).collect()
    };
    let ended = Panel {
        title: "touches the rule has ended".into(),
        x_label,
        series: vec![Series::line("ended", COLORS[6], ended_by(false)), Series::line("ended, answer right", COLORS[2], ended_by(true))],
        y_range: Some((0.0, 1.0)),
        marker,
        ..Panel::default()
    };
    [accuracy, ended]
}
