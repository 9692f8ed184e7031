//! A robot's copy of the model can be damaged: flipped bits in flash, a truncated transfer, a
//! block written over another. Every such mutant of the real golden model is refused at load as
//! corrupted, none is classified, and none panics.

mod support;

use std::panic::{catch_unwind, AssertUnwindSafe};

use pvt3_runtime::{Classifier, Error};
use support::{golden, golden_vectors, Draw};

/// Mutants of `good`: bit flips, byte overwrites, truncations, splices over and into the file.
fn mutants(good: &[u8]) -> Vec<(String, Vec<u8>)> {
    let mut draw = Draw(0x2545_f491_4f6c_dd1d);
    let len = good.len();
    let mut out = Vec::new();
    for i in 0..120 {
        let mut m = good.to_vec();
        for _ in 0..1 + i % 3 {
            m[draw.below(len)] ^= 1 << draw.below(8);
        }
        out.push((format!("{} flipped bits", 1 + i % 3), m));
    }
    for _ in 0..40 {
        let mut m = good.to_vec();
        let (at, n) = (draw.below(len), 1 + draw.below(64));
        for b in &mut m[at..(at + n).min(len)] {
            *b = draw.below(256) as u8;
        }
        out.push((format!("{n} random bytes at {at}"), m));
    }
    for _ in 0..60 {
        let keep = draw.below(len);
        out.push((format!("truncated to {keep} bytes"), good[..keep].to_vec()));
    }
    for _ in 0..60 {
        let (from, to, n) = (draw.below(len), draw.below(len), 1 + draw.below(4096));
        let chunk = &good[from..(from + n).min(len)];
        let mut over = good.to_vec();
        let end = (to + chunk.len()).min(len);
        over[to..end].copy_from_slice(&chunk[..end - to]);
        out.push((format!("{} bytes from {from} written over {to}", end - to), over));
        let mut into = good[..to].to_vec();
        into.extend_from_slice(chunk);
        into.extend_from_slice(&good[to..]);
        out.push((format!("{} bytes from {from} inserted at {to}", chunk.len()), into));
    }
    out.retain(|(_, m)| m != good);
    out
}

#[test]
fn every_damaged_copy_of_a_real_model_is_refused_and_none_panics() {
    let good = std::fs::read(golden("model.onnx")).unwrap();
    let (x, _) = golden_vectors();
    let window = &x[..4500];
    Classifier::from_bytes(&good, "intact").unwrap().classify(window).unwrap();
    let mutants = mutants(&good);
    assert!(mutants.len() >= 300, "{} mutants", mutants.len());
    for (what, bytes) in &mutants {
        let outcome = catch_unwind(AssertUnwindSafe(|| Classifier::from_bytes(bytes, "mutant").and_then(|c| c.classify(window))));
        match outcome {
            Err(_) => panic!("{what}: panicked"),
            Ok(Ok(p)) => panic!("{what}: classified as {}", p.label),
            Ok(Err(Error::Corrupted { .. })) => {}
            Ok(Err(e)) => panic!("{what}: refused, but not as corrupted: {e}"),
        }
    }
}

#[test]
fn a_file_without_a_digest_is_refused_with_a_clear_message() {
    let good = std::fs::read(golden("model.onnx")).unwrap();
    // The digest entry is the file's last field (the exporter appends it): field 14, its
    // length, then the key (field 1, its length): four bytes before the key.
    let key = pvt3_format::keys::DIGEST.as_bytes();
    let start = good.windows(key.len()).rposition(|w| w == key).unwrap() - 4;
    assert_eq!(good[start], 14 << 3 | 2, "a metadata entry starts there");
    let unsigned = &good[..start];
    let e = Classifier::from_bytes(unsigned, "old.onnx").err().expect("refused");
    let msg = e.to_string();
    assert!(matches!(e, Error::Corrupted { .. }) && msg.contains("old.onnx") && msg.contains("export it again"), "{msg}");
}
