//! A touch as the robot recorded it, brought to how the model reads touches. A model trained on
//! touches read by distance travelled (`pvt3 import --per-distance`) or scaled to one pressing
//! force (`--per-force`) says so in its file ([`Reading`]); the robot knows the speed and the force
//! it commands, hands them over with its frames, and gets the frames the model reads. The
//! trainer's import calls the same function, so a robot reads a touch as the training did.

use crate::resample::resample;
use crate::{Error, Result};

pub use pvt3_format::Reading;

/// What the robot knows of one touch: its sliding speed (in the units the training's speeds had,
/// its sign the direction) and its pressing force.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Touch {
    pub speed: Option<f64>,
    pub force: Option<f64>,
}

/// Brings one touch, `rows` rows (height × width × channels) of its frames back to back, each row
/// as long as the touch, to how `reading` reads touches: resampled to the frames it would have at
/// `reading.speed` (`n · |speed| / reading.speed` of them, at least one), then its readings times
/// `reading.force / force`. A reading that needs the speed or the force refuses a touch without it.
pub fn read_touch(frames: &[f32], rows: usize, reading: &Reading, touch: Touch) -> Result<Vec<f32>> {
    let refuse = |reason: String| Err(Error::Touch(reason));
    if rows == 0 || frames.is_empty() || !frames.len().is_multiple_of(rows) {
        return refuse(format!("{} values are not {rows} rows of one or more frames", frames.len()));
    }
    if let Some(index) = frames.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite { index, value: frames[index] });
    }
    let n = frames.len() / rows;
    let mut out = frames.to_vec();
    if let Some(to) = reading.speed {
        let Some(speed) = touch.speed.filter(|v| v.is_finite() && *v != 0.0) else {
            return refuse(format!(
                "the model reads touches by distance, as at speed {to}: give the touch's speed (finite, not 0), not {:?}",
                touch.speed
            ));
        };
        let len = ((n as f64 * speed.abs() / to).round() as usize).max(1);
        out = out.chunks(n).flat_map(|row| resample(row, len)).collect();
    }
    if let Some(to) = reading.force {
        let Some(force) = touch.force.filter(|v| v.is_finite() && *v > 0.0) else {
            return refuse(format!(
                "the model reads touches scaled to force {to}: give the touch's force (above 0), not {:?}",
                touch.force
            ));
        };
        let k = (to / force) as f32;
        out.iter_mut().for_each(|v| *v *= k);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_touch_is_resampled_by_its_speed_and_scaled_by_its_force() {
        // Two rows of 6 frames at speed -50, read as at 150 (2 frames) and force 300 → 150.
        let frames = [1.0, 3.0, 2.0, 6.0, 4.0, 0.0, 10.0, 10.0, 10.0, 10.0, 10.0, 10.0];
        let reading = Reading { speed: Some(150.0), force: Some(150.0) };
        let out = read_touch(&frames, 2, &reading, Touch { speed: Some(-50.0), force: Some(300.0) }).unwrap();
        let rows: Vec<f32> = resample(&frames[..6], 2).into_iter().chain(resample(&frames[6..], 2)).map(|v| v * 0.5).collect();
        assert_eq!(out, rows);
        // Neither part: the frames as they are.
        assert_eq!(read_touch(&frames, 2, &Reading::default(), Touch::default()).unwrap(), frames);
    }

    #[test]
    fn what_the_reading_needs_is_asked_for() {
        let frames = [1.0; 8];
        let speed = Reading { speed: Some(150.0), force: None };
        let force = Reading { speed: None, force: Some(150.0) };
        let msg = |r: &Reading, t: Touch| read_touch(&frames, 2, r, t).unwrap_err().to_string();
        assert!(msg(&speed, Touch::default()).contains("give the touch's speed"));
        assert!(msg(&speed, Touch { speed: Some(0.0), force: None }).contains("give the touch's speed"));
        assert!(msg(&force, Touch { speed: Some(10.0), force: Some(-1.0) }).contains("give the touch's force"));
        assert!(msg(&force, Touch { speed: None, force: Some(f64::NAN) }).contains("give the touch's force"));
        assert!(read_touch(&frames, 3, &force, Touch { speed: None, force: Some(1.0) }).unwrap_err().to_string().contains("not 3 rows"));
        let mut bad = frames;
        bad[5] = f32::INFINITY;
        assert!(matches!(read_touch(&bad, 2, &force, Touch { speed: None, force: Some(1.0) }), Err(Error::NonFinite { index: 5, .. })));
    }
}
