//! How a recording's frame times stray from a steady clock: counted for every touch read from a
//! ROS 2 bag (its `header.stamp`s, or its receive times where the message has no header), a
//! camera's or a taxel array's, and reported per touch by `pvt3 import`.

/// How a recording's frame times (a bag's `header.stamp`s, or its receive times) stray from a
/// steady clock: what a robot's driver dropped, repeated or sent out of order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Timing {
    /// Intervals longer than 1.5 times the median: frames dropped.
    pub gaps: usize,
    /// Frames stamped as the one before.
    pub repeated: usize,
    /// Frames stamped before the one before.
    pub out_of_order: usize,
}

impl Timing {
    /// The timing of frames taken at `times` (nanoseconds), in the order they came.
    pub fn of(times: &[i64]) -> Self {
        let steps: Vec<i64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        let mut rising: Vec<i64> = steps.iter().copied().filter(|s| *s > 0).collect();
        rising.sort_unstable();
        let median = rising.get(rising.len() / 2).copied().unwrap_or(0);
        Self {
            gaps: steps.iter().filter(|s| median > 0 && **s * 2 > median * 3).count(),
            repeated: steps.iter().filter(|s| **s == 0).count(),
            out_of_order: steps.iter().filter(|s| **s < 0).count(),
        }
    }

    /// Whether any frame strayed.
    pub fn strays(&self) -> bool {
        *self != Self::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_s_times_count_its_gaps_repeats_and_reorderings() {
        let steady: Vec<i64> = (0..10).map(|k| k * 40).collect();
        assert_eq!(Timing::of(&steady), Timing::default());
        assert!(!Timing::of(&steady).strays());
        // 0, 40, 80, [dropped 120], 160, 160 (repeated), 200, 190 (back), 240
        let stray = [0, 40, 80, 160, 160, 200, 190, 240];
        assert_eq!(Timing::of(&stray), Timing { gaps: 1, repeated: 1, out_of_order: 1 });
        assert_eq!(Timing::of(&[5]), Timing::default(), "one frame: nothing to stray");
    }
}
