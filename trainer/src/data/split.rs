//! A run's split as a recorded fact: which touches train, validate and test, and of which data.
//! A run writes [`TrainedOn`] into its provenance; every reload (eval, prune, the pooled stopping
//! rule, distillation, resume) takes the folds from there and refuses data that are not the
//! touches the run trained on, so that no test touch is ever read as a training or validation one.

use sha2::{Digest, Sha256};

use super::{Dataset, TEST_FOLD};

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
    /// [`Dataset::digest`] of the touches.
    pub digest: String,
    /// The seed that drew the folds (stratified, or around the held-out levels); `None`: the
    /// file's own `fold` array.
    pub fold_seed: Option<u64>,
    /// Touch `i`'s fold is the `i`-th digit.
    pub folds: String,
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
fn short(digest: &str) -> &str {
    &digest[..digest.len().min("sha256:".len() + 12)]
}

impl Dataset {
    /// SHA-256 of the touches as read (their layout, lengths, labels and every value as f32),
    /// whatever file or dtype holds them; computed once.
    pub fn digest(&self) -> &str {
        self.digest.get_or_init(|| {
            let mut sha = Sha256::new();
            let words = |v: &[usize]| v.iter().flat_map(|d| (*d as u64).to_le_bytes()).collect::<Vec<u8>>();
            sha.update(words(&self.sample_shape));
            sha.update(words(&self.lengths));
            sha.update(self.labels.iter().flat_map(|l| l.to_le_bytes()).collect::<Vec<u8>>());
            for i in 0..self.len() {
                for chunk in self.sample(i).chunks(1 << 16) {
                    sha.update(chunk.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>());
                }
            }
            let hex: String = sha.finalize().iter().map(|b| format!("{b:02x}")).collect();
            format!("sha256:{hex}")
        })
    }

    /// The split this data set gives, as a run records it.
    pub fn trained_on(&self) -> TrainedOn {
        TrainedOn {
            digest: self.digest().to_string(),
            fold_seed: self.fold_seed,
            folds: self.folds.iter().map(|f| char::from_digit(*f as u32, 10).expect("a fold below 10")).collect(),
        }
    }

    /// Takes the folds a run recorded, refusing touches that are not the ones it trained on.
    pub fn take_split(&mut self, recorded: &TrainedOn) -> crate::Result<()> {
        let refuse = |reason: String| super::data_error(&self.path, reason);
        if self.digest() != recorded.digest {
            return Err(refuse(format!(
                "not the data the run trained on: its touches hash to {}, the run's to {}",
                short(self.digest()),
                short(&recorded.digest)
            )));
        }
        let folds = recorded.fold_numbers().filter(|f| f.len() == self.len());
        self.folds = folds.ok_or_else(|| refuse(format!("the run's record of its folds is damaged: {:?}", recorded.folds)))?;
        self.fold_seed = recorded.fold_seed;
        Ok(())
    }

    /// Refuses when this data set's split is not `recorded` (a run's), naming what differs;
    /// `whose` names the run or option whose split is meant.
    pub fn check_split(&self, recorded: &TrainedOn, whose: &str) -> crate::Result<()> {
        match recorded.differs(&self.trained_on()) {
            Some(why) => Err(super::data_error(&self.path, format!("{whose} trained on another split: {why}"))),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(digest: &str, seed: Option<u64>, folds: &str) -> TrainedOn {
        TrainedOn { digest: digest.into(), fold_seed: seed, folds: folds.into() }
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
