//! A touch as the robot recorded it, brought to how the model reads touches. A model trained on
//! touches read by distance travelled (`pvt3 import --per-distance`) or scaled to one pressing
//! force (`--per-force`) says so in its file ([`Reading`]); the robot knows the speed and the force
//! it commands, hands them over with its frames, and gets the frames the model reads. The
//! trainer's import calls the same function, so a robot reads a touch as the training did.

use crate::resample::{span_mean, span_reads_up_to};
use crate::Reading;

/// Why a touch cannot be read as a model reads touches (the runtime reports each as its own
/// error, with these words).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ReadError {
    /// The touch does not fit the reading: its layout, or a speed or force the reading needs.
    #[error("reading the touch: {0}")]
    Touch(String),
    /// A value that is a NaN or an infinity.
    #[error("input value {index} is {value}: only finite values can be classified")]
    NonFinite {
        /// Where it is in the input.
        index: usize,
        /// The value.
        value: f32,
    },
    /// A frame of another length than the model's.
    #[error("a frame has {got} values; expected {expected} (height × width × channels)")]
    FrameLength {
        /// The frame's values.
        got: usize,
        /// The model's frame's values.
        expected: usize,
    },
}

type Result<T> = std::result::Result<T, ReadError>;

/// How much faster or slower than it was recorded a touch is read by distance, at most: a touch
/// read 1000 times slower is 1000 times as many frames, each read frame 1000 times faster
/// averages 1000 recorded ones.
pub const MAX_SPEED_RATIO: f64 = 1000.0;

/// What the robot knows of one touch: its sliding speed (in the units the training's speeds had,
/// its sign the direction) and its pressing force.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Touch {
    /// The sliding speed; `None`: not known.
    pub speed: Option<f64>,
    /// The pressing force; `None`: not known.
    pub force: Option<f64>,
}

/// Brings one touch, `rows` rows (height × width × channels) of its frames back to back, each row
/// as long as the touch, to how `reading` reads touches: resampled to the frames it would have at
/// `reading.speed` (`n · |speed| / reading.speed` of them, at least one), then its readings times
/// `reading.force / force`. A reading that needs the speed or the force refuses a touch without it.
/// It is the touch pushed through a [`TouchReader`] frame by frame, so that a robot's stream and
/// a whole touch are read alike, bit for bit.
pub fn read_touch(frames: &[f32], rows: usize, reading: &Reading, touch: Touch) -> Result<Vec<f32>> {
    if rows == 0 || frames.is_empty() || !frames.len().is_multiple_of(rows) {
        return Err(ReadError::Touch(format!("{} values are not {rows} rows of one or more frames", frames.len())));
    }
    if let Some(index) = frames.iter().position(|v| !v.is_finite()) {
        return Err(ReadError::NonFinite { index, value: frames[index] });
    }
    let n = frames.len() / rows;
    let mut reader = TouchReader::new(rows, reading, touch)?;
    let (mut read, mut frame) = (Vec::new(), vec![0.0; rows]);
    for t in 0..n {
        frame.iter_mut().enumerate().for_each(|(r, v)| *v = frames[r * n + t]);
        reader.push(&frame, &mut read)?;
    }
    reader.finish(&mut read);
    // Frame after frame, back to the sample layout: row after row.
    Ok((0..rows).flat_map(|r| read.iter().skip(r).step_by(rows).copied()).collect())
}

/// A touch read as [`read_touch`] reads it, frame by frame as the robot records it: a frame read
/// by distance is given out as soon as the recorded frames it spans (and the one after, which
/// the straight line between frames reads) have arrived, and the frames after the last recorded
/// one when the touch ends ([`TouchReader::finish`]). A session made for a touch (the runtime's
/// `Classifier::session_for`) reads its frames through one.
#[derive(Clone, Debug)]
pub struct TouchReader {
    /// Values in one frame.
    frame_len: usize,
    /// Reading by distance: the touch's speed and the reading's.
    speeds: Option<(f64, f64)>,
    /// Reading at one force: the factor of every value.
    scale: Option<f32>,
    /// The touch recorded so far, one row of frames per value of a frame.
    rows: Vec<Vec<f32>>,
    /// Frames given out so far.
    read: usize,
}

impl TouchReader {
    /// A reader of frames of `frame_len` values, recorded at `touch`, read as `reading` reads
    /// touches; refused where the reading needs a speed or a force `touch` does not give.
    pub fn new(frame_len: usize, reading: &Reading, touch: Touch) -> Result<Self> {
        let refuse = |reason: String| Err(ReadError::Touch(reason));
        let speeds = match reading.speed {
            None => None,
            Some(to) => match touch.speed.filter(|v| v.is_finite() && *v != 0.0) {
                // Each frame read averages about `to / speed` recorded ones, and a recorded frame
                // gives `speed / to` read ones: past a bound, no touch could be read in time.
                Some(speed) if !(1.0 / MAX_SPEED_RATIO..=MAX_SPEED_RATIO).contains(&(speed.abs() / to)) => {
                    return refuse(format!(
                        "a touch at speed {speed} read as at speed {to}: {} times as fast, where a touch is read at 1/{MAX_SPEED_RATIO} to {MAX_SPEED_RATIO} times its speed",
                        speed.abs() / to
                    ))
                }
                Some(speed) => Some((speed.abs(), to)),
                None => {
                    return refuse(format!(
                        "the model reads touches by distance, as at speed {to}: give the touch's speed (finite, not 0), not {:?}",
                        touch.speed
                    ))
                }
            },
        };
        let scale = match reading.force {
            None => None,
            Some(to) => match touch.force.filter(|v| v.is_finite() && *v > 0.0) {
                Some(force) => Some((to / force) as f32),
                None => {
                    return refuse(format!(
                        "the model reads touches scaled to force {to}: give the touch's force (above 0), not {:?}",
                        touch.force
                    ))
                }
            },
        };
        Ok(Self { frame_len, speeds, scale, rows: vec![Vec::new(); frame_len], read: 0 })
    }

    /// Takes the next recorded frame and appends the frames it completes to `out` (each
    /// `frame_len` values); returns how many.
    pub fn push(&mut self, frame: &[f32], out: &mut Vec<f32>) -> Result<usize> {
        if frame.len() != self.frame_len {
            return Err(ReadError::FrameLength { got: frame.len(), expected: self.frame_len });
        }
        if let Some((index, value)) = frame.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(ReadError::NonFinite { index, value: *value });
        }
        let Some((speed, to)) = self.speeds else {
            out.extend(frame.iter().map(|v| self.scaled(*v)));
            return Ok(1);
        };
        self.rows.iter_mut().zip(frame).for_each(|(row, v)| row.push(*v));
        let step = to / speed;
        let before = self.read;
        while span_reads_up_to(self.read as f64 * step, step) < self.recorded() {
            self.give_out(step, out);
        }
        Ok(self.read - before)
    }

    /// Ends the touch: appends the frames read after its last recorded one (its frames held
    /// beyond its end), up to `n · |speed| / reading.speed` in all (at least one); returns how
    /// many. The reader is then ready for the next touch.
    pub fn finish(&mut self, out: &mut Vec<f32>) -> usize {
        let n = self.recorded();
        let mut added = 0;
        if let (Some((speed, to)), true) = (self.speeds, n > 0) {
            let len = ((n as f64 * speed / to).round() as usize).max(1);
            added = len.saturating_sub(self.read);
            (0..added).for_each(|_| self.give_out(to / speed, out));
        }
        self.reset();
        added
    }

    /// Forgets the touch in progress.
    pub fn reset(&mut self) {
        self.rows.iter_mut().for_each(Vec::clear);
        self.read = 0;
    }

    fn recorded(&self) -> usize {
        self.rows.first().map_or(0, Vec::len)
    }

    /// Appends the next frame read by distance, `step` recorded frames a frame read, from the
    /// frames recorded so far.
    fn give_out(&mut self, step: f64, out: &mut Vec<f32>) {
        let (last, from) = (self.recorded() - 1, self.read as f64 * step);
        for row in &self.rows {
            out.push(self.scaled(span_mean(|j| row[j], last, from, step)));
        }
        self.read += 1;
    }

    /// A value read at the reading's force.
    fn scaled(&self, v: f32) -> f32 {
        self.scale.map_or(v, |k| v * k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resample::resample_into;

    #[test]
    fn a_touch_is_resampled_by_its_speed_and_scaled_by_its_force() {
        // Two rows of 6 frames at speed -50, read as at 150 (2 frames) and force 300 → 150.
        let frames = [1.0, 3.0, 2.0, 6.0, 4.0, 0.0, 10.0, 10.0, 10.0, 10.0, 10.0, 10.0];
        let reading = Reading { speed: Some(150.0), force: Some(150.0) };
        let out = read_touch(&frames, 2, &reading, Touch { speed: Some(-50.0), force: Some(300.0) }).unwrap();
        let mut rows = [0.0; 4];
        resample_into(&frames[..6], 0.0, 3.0, &mut rows[..2]);
        resample_into(&frames[6..], 0.0, 3.0, &mut rows[2..]);
        assert_eq!(out, rows.map(|v| v * 0.5));
        // Neither part: the frames as they are.
        assert_eq!(read_touch(&frames, 2, &Reading::default(), Touch::default()).unwrap(), frames);
    }

    #[test]
    fn a_stream_is_read_as_the_whole_touch_and_each_frame_as_soon_as_its_span_is_recorded() {
        let (n, to) = (53, 150.0);
        let touch: Vec<Vec<f32>> = (0..3).map(|r| (0..n).map(|t| ((t * 7 + r * 13) % 17) as f32 * 0.37 - r as f32).collect()).collect();
        for speed in [150.0, 37.0, -10.0, 149.9, 400.0, -73.3] {
            let reading = Reading { speed: Some(to), force: Some(120.0) };
            let mut reader = TouchReader::new(3, &reading, Touch { speed: Some(speed), force: Some(240.0) }).unwrap();
            let step = to / f64::abs(speed);
            let len = ((n as f64 * f64::abs(speed) / to).round() as usize).max(1);
            let (mut read, mut given) = (Vec::new(), 0);
            for t in 0..n {
                let frame: Vec<f32> = touch.iter().map(|row| row[t]).collect();
                given += reader.push(&frame, &mut read).unwrap();
                assert_eq!(given * 3, read.len(), "push counts the frames it gives out");
                // A frame read is given out at most two recorded frames after the end of its span.
                let due = (0..len).filter(|&k| (k + 1) as f64 * step + 2.0 <= (t + 1) as f64).count();
                assert!(read.len() / 3 >= due, "speed {speed}: {} frames given after {} recorded, {due} due", read.len() / 3, t + 1);
            }
            let streamed = read.len() / 3;
            assert_eq!(reader.finish(&mut read) + streamed, len, "speed {speed}");
            for (r, row) in touch.iter().enumerate() {
                let mut whole = vec![0.0; len];
                resample_into(row, 0.0, step, &mut whole);
                let got: Vec<f32> = read.iter().skip(r).step_by(3).copied().collect();
                assert_eq!(got, whole.iter().map(|v| v * 0.5).collect::<Vec<f32>>(), "speed {speed}, row {r}, bit for bit");
            }
            let flat: Vec<f32> = touch.concat();
            let whole = read_touch(&flat, 3, &reading, Touch { speed: Some(speed), force: Some(240.0) }).unwrap();
            let rows: Vec<f32> = (0..3).flat_map(|r| read.iter().skip(r).step_by(3).copied().collect::<Vec<_>>()).collect();
            assert_eq!(whole, rows);
        }
    }

    fn speed_reading() -> Reading {
        Reading { speed: Some(150.0), force: None }
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
        // A reading that would take no end of time or memory: refused, naming the bound.
        for speed in [1e300, 1e-300, 150.0 * 1001.0] {
            let why = msg(&speed_reading(), Touch { speed: Some(speed), force: None });
            assert!(why.contains("where a touch is read at 1/1000 to 1000 times its speed"), "{speed}: {why}");
        }
        assert!(read_touch(&frames, 2, &speed_reading(), Touch { speed: Some(150.0 * 999.0), force: None }).is_ok());
        assert!(read_touch(&frames, 3, &force, Touch { speed: None, force: Some(1.0) }).unwrap_err().to_string().contains("not 3 rows"));
        let mut bad = frames;
        bad[5] = f32::INFINITY;
        assert!(matches!(read_touch(&bad, 2, &force, Touch { speed: None, force: Some(1.0) }), Err(ReadError::NonFinite { index: 5, .. })));
    }
}
