//! A run's split as a recorded fact: which touches train, validate and test, and of which data.
//! A run writes [`TrainedOn`] into its provenance; every reload (eval, prune, the pooled stopping
//! rule, distillation, resume) takes the folds from there and refuses data that are not the
//! touches the run trained on, so that no test touch is ever read as a training or validation one.

use pvt3_models::Rng;

/// The fold that holds the test set in the published protocol.
pub const TEST_FOLD: usize = 4;
/// Folds 0..FOLDS (the test fold included).
pub const FOLDS: usize = 5;

/// Which samples train, validate and test.
#[derive(Clone, Debug, PartialEq)]
pub struct Split {
    pub train: Vec<usize>,
    pub val: Vec<usize>,
    pub test: Vec<usize>,
}

/// What a run trained on: the data set's digest, where its folds came from, and every touch's
/// fold, one digit a touch ([`TEST_FOLD`] tests, the run's validation fold validates, the others
/// train).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrainedOn {
    /// `Dataset::digest` of the touches.
    pub digest: String,
    /// The seed that drew the folds (stratified, or around the held-out levels); `None`: the
    /// file's own `fold` array.
    pub fold_seed: Option<u64>,
    /// Touch `i`'s fold is the `i`-th digit.
    pub folds: String,
    /// A final model's (which every touch trains): each touch's own digest
    /// (`Dataset::touch_digest`), so that no touch that trained it is taken for a test touch,
    /// alone or in another file. Empty for a run whose test fold is its test.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub touches: Vec<String>,
}

impl TrainedOn {
    /// The folds as numbers, or `None` when the record is not one digit 0..=4 a touch.
    pub fn fold_numbers(&self) -> Option<Vec<usize>> {
        self.folds.chars().map(|c| c.to_digit(10).map(|d| d as usize).filter(|d| *d <= TEST_FOLD)).collect()
    }

    /// Why `given` is not this split, in words, or `None` when it is.
    pub fn differs(&self, given: &TrainedOn) -> Option<String> {
        if self.digest != given.digest {
            return Some(format!(
                "its touches are not the ones the run trained on (they hash to {}, the run's to {})",
                short(&given.digest),
                short(&self.digest)
            ));
        }
        if self.fold_seed != given.fold_seed {
            return Some(format!("the run's folds {}, these {}", drawn(self.fold_seed), drawn(given.fold_seed)));
        }
        let moved = self.folds.chars().zip(given.folds.chars()).filter(|(a, b)| a != b).count();
        (moved > 0).then(|| format!("touches in other folds than the run's: {moved} of {}", self.folds.len()))
    }
}

/// How folds were drawn, in words.
fn drawn(seed: Option<u64>) -> String {
    match seed {
        Some(s) => format!("were drawn with seed {s}"),
        None => "are the file's fold array".into(),
    }
}

/// The first 12 hex digits of a digest, enough to tell two apart in a message.
pub(super) fn short(digest: &str) -> &str {
    &digest[..digest.len().min("sha256:".len() + 12)]
}

/// Deals each class's samples, shuffled by `seed`, round-robin into folds 0..folds_count.
pub(super) fn stratified_folds(labels: &[u32], folds_count: usize, seed: u64) -> Vec<usize> {
    let mut rng = Rng::new(seed);
    let mut folds = vec![0; labels.len()];
    let classes = labels.iter().max().map_or(0, |m| *m + 1);
    for c in 0..classes {
        let mut members: Vec<usize> = (0..labels.len()).filter(|&i| labels[i] == c).collect();
        rng.shuffle(&mut members);
        for (k, i) in members.into_iter().enumerate() {
            folds[i] = k % folds_count;
        }
    }
    folds
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(digest: &str, seed: Option<u64>, folds: &str) -> TrainedOn {
        TrainedOn { digest: digest.into(), fold_seed: seed, folds: folds.into(), touches: Vec::new() }
    }

    #[test]
    fn a_split_names_what_differs() {
        let run = record("sha256:aaaa", Some(1), "01234");
        assert_eq!(run.differs(&run.clone()), None);
        let other_data = run.differs(&record("sha256:bbbb", Some(1), "01234")).unwrap();
        assert!(other_data.contains("not the ones the run trained on"), "{other_data}");
        let other_seed = run.differs(&record("sha256:aaaa", Some(0), "01234")).unwrap();
        assert!(other_seed.contains("drawn with seed 1, these were drawn with seed 0"), "{other_seed}");
        let from_file = run.differs(&record("sha256:aaaa", None, "01234")).unwrap();
        assert!(from_file.contains("the file's fold array"), "{from_file}");
        assert_eq!(run.differs(&record("sha256:aaaa", Some(1), "01244")).unwrap(), "touches in other folds than the run's: 1 of 5");
        assert_eq!(record("d", None, "0149").fold_numbers(), None, "a fold beyond the test fold is damage");
    }
}
