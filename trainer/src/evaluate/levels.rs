//! Accuracy at each recorded level of a touch's conditions (a speed, a force): where a model
//! misses when some ways of touching were held out of its training, as `pvt3 eval` prints it
//! beside the classes (docs/robustness.md reads the held-out rows so).

use std::collections::HashSet;

use crate::data::Condition;

/// The touches answered at one level of a condition, and how many of them right.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Level {
    pub level: String,
    pub touches: usize,
    pub right: usize,
}

impl Level {
    pub fn accuracy(&self) -> f64 {
        self.right as f64 / self.touches.max(1) as f64
    }
}

/// Each level of `condition` among the answered touches, in the condition's order: answer `k` is
/// `predictions[k]` to the data set's touch `touches[k]`, whose label is `labels[k]`. A touch
/// answered more than once (by several runs of a cross-validation) counts each time.
pub fn by_level(condition: &Condition, touches: &[usize], labels: &[u32], predictions: &[u32]) -> Vec<Level> {
    let answered: HashSet<usize> = touches.iter().copied().collect();
    condition
        .distinct_among(|i| answered.contains(&i))
        .into_iter()
        .map(|level| {
            let at: Vec<usize> = (0..touches.len()).filter(|&k| condition.levels[touches[k]] == level).collect();
            let right = at.iter().filter(|&&k| labels[k] == predictions[k]).count();
            Level { level: level.to_string(), touches: at.len(), right }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_answered_level_counts_its_touches_and_right_answers_in_numeric_order() {
        let speed = Condition { name: "speed".into(), levels: ["10", "-20", "10", "150", "-20"].map(String::from).to_vec() };
        // Touches 0, 1, 2 and 4 answered (touch 2 twice, by two runs); 150 mm/s never.
        let touches = [0, 1, 2, 4, 2];
        let labels = [0, 1, 0, 1, 0];
        let predictions = [0, 0, 1, 1, 0];
        let levels = by_level(&speed, &touches, &labels, &predictions);
        let expect = |level: &str, touches, right| Level { level: level.into(), touches, right };
        assert_eq!(levels, vec![expect("-20", 2, 1), expect("10", 3, 2)]);
        assert_eq!(levels[1].accuracy(), 2.0 / 3.0);
    }
}
