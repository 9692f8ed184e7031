//! Which frames of a camera's recording a touch takes ([`FrameSpan::take`]): a count of them
//! spread evenly over the whole recording, or over the span in which the gel moves (where the
//! PhysiCLeAR authors cut their videos, found by a rule of its own: its gel moves by a grey level
//! or two a frame). `pvt3 import` takes its touches' frames so, and a robot that records a whole
//! touch before it classifies can take its frames alike.

use crate::Picture;

/// Which frames of a recording a touch takes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum FrameSpan {
    /// Evenly over the whole recording.
    Whole,
    /// Evenly over the span in which the gel moves ([`Motion`]), widened to the frames asked
    /// where it is shorter; the whole recording where nothing moves.
    #[default]
    Moving,
}

/// The frames a touch takes of a recording ([`FrameSpan::take`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Taken {
    /// The first frame of the span they are spread over.
    pub first: usize,
    /// The last frame of that span.
    pub last: usize,
    /// The recording's frames taken, in order (a short recording's repeated).
    pub frames: Vec<usize>,
}

impl FrameSpan {
    /// The `count` frames a touch takes of `recorded` (one or more frames): spread evenly over
    /// this span of it.
    pub fn take(self, recorded: &[Picture], count: usize) -> Taken {
        let mut motion = Motion::new(self);
        recorded.iter().for_each(|frame| motion.push(frame));
        motion.take(count)
    }
}

/// A recording's frames seen one at a time, for [`FrameSpan::take`] of a recording too long to
/// hold: what the span needs of each frame (for the moving span, its change from the one before)
/// in the memory of one frame.
pub struct Motion {
    span: FrameSpan,
    frames: usize,
    /// The last frame, grey, for the moving span.
    previous: Option<Picture>,
    /// Each frame's change from the one before (the mean absolute difference of their grey levels).
    change: Vec<f32>,
}

impl Motion {
    /// Nothing seen yet, for the frames of `span`.
    pub fn new(span: FrameSpan) -> Self {
        Self { span, frames: 0, previous: None, change: Vec::new() }
    }

    /// The recording's next frame.
    pub fn push(&mut self, frame: &Picture) {
        self.frames += 1;
        if self.span == FrameSpan::Moving {
            let grey = frame.grey();
            if let Some(previous) = &self.previous {
                let sum = previous.data.iter().zip(&grey.data).map(|(a, b)| f32::from(a.abs_diff(*b))).sum::<f32>();
                self.change.push(sum / previous.data.len() as f32);
            }
            self.previous = Some(grey);
        }
    }

    /// Frames seen.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The `count` frames a touch takes of the frames seen (one or more).
    pub fn take(&self, count: usize) -> Taken {
        let (first, last) = match self.span {
            FrameSpan::Whole => (0, self.frames - 1),
            FrameSpan::Moving => widened(moving_span(&self.change), count, self.frames),
        };
        Taken { first, last, frames: evenly(first, last, count) }
    }
}

/// How far between a recording's stillest and busiest frame a frame must change to count as
/// moving: GelSight's gel moves by a grey level or two a frame, its codec's key frames jump.
pub const MOVING_FRACTION: f32 = 0.25;
/// Frames over which each frame's change is smoothed (a median: a key frame's jump is one frame).
pub const SMOOTHING: usize = 5;
/// Still frames within a moving span that do not end it.
pub const PAUSE: usize = 5;

/// `count` frame indices spread evenly over `start..=end` (each the middle of its share).
fn evenly(start: usize, end: usize, count: usize) -> Vec<usize> {
    let len = end + 1 - start;
    (0..count).map(|k| start + (2 * k + 1) * len / (2 * count)).collect()
}

/// The span in which the gel moves, of a recording whose frames change by `change` (frame
/// `i + 1`'s is `change[i]`, [`Motion`]): each change smoothed by a median over [`SMOOTHING`]
/// frames; a frame moves where that exceeds [`MOVING_FRACTION`] of the way from the recording's
/// stillest to its busiest frame; the span is the longest run of moving frames, pauses of up to
/// [`PAUSE`] frames bridged. `None` for a recording that never changes.
fn moving_span(change: &[f32]) -> Option<(usize, usize)> {
    let smooth: Vec<f32> = (0..change.len())
        .map(|i| {
            let mut near = change[i.saturating_sub(SMOOTHING / 2)..(i + SMOOTHING / 2 + 1).min(change.len())].to_vec();
            near.sort_by(f32::total_cmp);
            near[(near.len() - 1) / 2]
        })
        .collect();
    let (still, busy) = smooth.iter().fold((f32::MAX, 0f32), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
    if smooth.is_empty() || busy <= still {
        return None;
    }
    let threshold = still + MOVING_FRACTION * (busy - still);
    // Runs of moving frames (frame i + 1 is change i's), pauses of up to PAUSE frames bridged.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for i in (0..smooth.len()).filter(|&i| smooth[i] > threshold).map(|i| i + 1) {
        match runs.last_mut() {
            Some((_, end)) if i - *end <= PAUSE + 1 => *end = i,
            _ => runs.push((i, i)),
        }
    }
    runs.into_iter().max_by_key(|(start, end)| (end - start, std::cmp::Reverse(*start)))
}

/// `span` widened about its middle to `frames` frames within `0..len` where it is shorter; the
/// whole recording where nothing moves.
fn widened(span: Option<(usize, usize)>, frames: usize, len: usize) -> (usize, usize) {
    let Some((start, end)) = span else { return (0, len - 1) };
    if end + 1 - start >= frames {
        return (start, end);
    }
    let width = frames.min(len);
    let start = (start + end).div_ceil(2).saturating_sub(width / 2).min(len - width);
    (start, start + width - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_spread_evenly_and_a_short_moving_span_is_widened() {
        assert_eq!(evenly(0, 11, 4), [1, 4, 7, 10]);
        assert_eq!(evenly(4, 9, 6), [4, 5, 6, 7, 8, 9]);
        assert_eq!(widened(Some((4, 9)), 4, 12), (4, 9));
        assert_eq!(widened(Some((5, 6)), 4, 12), (4, 7));
        assert_eq!(widened(Some((0, 1)), 5, 12), (0, 4));
        assert_eq!(widened(Some((10, 11)), 5, 12), (7, 11));
        assert_eq!(widened(None, 5, 12), (0, 11));
        let still: Vec<Picture> = (0..6).map(|_| Picture { height: 2, width: 3, channels: 3, data: vec![9; 18] }).collect();
        assert_eq!(FrameSpan::Moving.take(&still, 4), Taken { first: 0, last: 5, frames: vec![0, 2, 3, 5] });
    }
}
