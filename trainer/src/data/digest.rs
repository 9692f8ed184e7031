//! A data set's identity and the split it records: the digest of its touches as read, the
//! [`TrainedOn`] a run writes into its provenance, and the checks every reload makes against it.

use sha2::{Digest, Sha256};

use super::split::short;
use super::{Dataset, TrainedOn};

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
            format!("sha256:{}", hex(&sha.finalize()))
        })
    }

    /// The split this data set gives, as a run records it; with `every_touch` (a final model's,
    /// which every touch trains), each touch's own digest too.
    pub fn trained_on(&self, every_touch: bool) -> TrainedOn {
        TrainedOn {
            digest: self.digest().to_string(),
            fold_seed: self.fold_seed,
            folds: self.folds.iter().map(|f| char::from_digit(*f as u32, 10).expect("a fold below 10")).collect(),
            touches: if every_touch { (0..self.len()).map(|i| self.touch_digest(i)).collect() } else { Vec::new() },
        }
    }

    /// Touch `i`'s own digest: the first 64 bits of the SHA-256 of its frame's layout, its length
    /// and its values as read (as f32), whatever file holds it and whatever other touches pad it
    /// to; its label is not in it, so a touch relabelled is still the touch.
    pub fn touch_digest(&self, i: usize) -> String {
        let (frame, frames) = self.sample_shape.split_at(self.sample_shape.len() - 1);
        let mut sha = Sha256::new();
        sha.update(frame.iter().chain([&self.lengths[i]]).flat_map(|d| (*d as u64).to_le_bytes()).collect::<Vec<u8>>());
        // The touch's own frames, not the padding after its end.
        for row in self.sample(i).chunks(frames[0]) {
            sha.update(row[..self.lengths[i]].iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>());
        }
        hex(&sha.finalize()[..8])
    }

    /// Takes the folds a run recorded, refusing touches that are not the ones it trained on.
    pub fn take_split(&mut self, recorded: &TrainedOn) -> crate::Result<()> {
        let refuse = |reason: String| crate::Error::data(&self.path, reason);
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
        match recorded.differs(&self.trained_on(false)) {
            Some(why) => Err(crate::Error::data(&self.path, format!("{whose} trained on another split: {why}"))),
            None => Ok(()),
        }
    }
}

/// `bytes` as lower-case hex digits, two a byte.
fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
