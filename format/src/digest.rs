//! The integrity digest: SHA-256 over every top-level field of the encoded `ModelProto` (graph,
//! weights, opsets, every metadata entry) except the digest's own metadata entry, in file order.
//! The exporter hashes the file it is about to write and adds the entry; the runtime finds the
//! entry by walking the protobuf's top-level fields, hashes the rest, and compares. A flipped,
//! truncated or spliced byte anywhere changes the hash, the entry, or the framing, so a damaged
//! file is refused before a parser or tract reads it. Walking is done here by hand, with every
//! length checked, so arbitrary bytes give an [`Integrity`] error and never a panic.

use sha2::{Digest, Sha256};

use crate::keys::DIGEST;

/// Why a file's content is not what was exported.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Integrity {
    /// Not a protobuf message: what is wrong with its bytes.
    #[error("its bytes are not a well-formed protobuf message ({0}): truncated or corrupted")]
    Malformed(&'static str),
    /// No digest: a file from before the digest, or damaged.
    #[error("it has no `{DIGEST}` entry: exported by a pvt3 older than the digest, or damaged; export it again")]
    Missing,
    /// More than one digest.
    #[error("it has more than one `{DIGEST}` entry")]
    Repeated,
    #[error("its content hashes to {computed}, not to the {claimed} it was exported with: the file was altered or corrupted")]
    /// The content does not hash to the digest it holds.
    Mismatch {
        /// The digest the file holds.
        claimed: String,
        /// The digest of its content.
        computed: String,
    },
}

/// `ModelProto.metadata_props`.
const METADATA_PROPS: u64 = 14;
/// `StringStringEntryProto.key` and `.value`.
const KEY: u64 = 1;
const VALUE: u64 = 2;
const PREFIX: &str = "sha256:";

/// One field of a message: its number, its payload if length-delimited, and its whole bytes
/// (tag included).
struct Field<'a> {
    number: u64,
    payload: Option<&'a [u8]>,
    bytes: &'a [u8],
}

fn varint(bytes: &[u8], at: &mut usize) -> Result<u64, Integrity> {
    let mut value = 0u64;
    for shift in (0..64).step_by(7) {
        let b = *bytes.get(*at).ok_or(Integrity::Malformed("a number runs past the end"))?;
        *at += 1;
        value |= u64::from(b & 0x7f) << shift;
        if b & 0x80 == 0 {
            return Ok(value);
        }
    }
    Err(Integrity::Malformed("a number longer than ten bytes"))
}

/// The top-level fields of the message `bytes`, in order.
fn fields(bytes: &[u8]) -> Result<Vec<Field<'_>>, Integrity> {
    let mut out = Vec::new();
    let mut at = 0;
    while at < bytes.len() {
        let start = at;
        let tag = varint(bytes, &mut at)?;
        let (number, wire) = (tag >> 3, tag & 7);
        if number == 0 {
            return Err(Integrity::Malformed("a field numbered 0"));
        }
        let mut payload = None;
        let len = match wire {
            0 => varint(bytes, &mut at).map(|_| 0)?,
            1 => 8,
            5 => 4,
            2 => {
                let len = varint(bytes, &mut at)?;
                usize::try_from(len).map_err(|_| Integrity::Malformed("a length beyond memory"))?
            }
            _ => return Err(Integrity::Malformed("an unknown wire type")),
        };
        let end = at.checked_add(len).filter(|e| *e <= bytes.len()).ok_or(Integrity::Malformed("a field runs past the end"))?;
        if wire == 2 {
            payload = Some(&bytes[at..end]);
        }
        at = end;
        out.push(Field { number, payload, bytes: &bytes[start..end] });
    }
    Ok(out)
}

/// The value of a metadata entry whose key is the digest's, if `field` is one.
fn digest_entry<'a>(field: &Field<'a>) -> Result<Option<&'a [u8]>, Integrity> {
    let Some(payload) = field.payload.filter(|_| field.number == METADATA_PROPS) else { return Ok(None) };
    let entry = fields(payload)?;
    let string = |n: u64| entry.iter().rev().find(|f| f.number == n).and_then(|f| f.payload);
    Ok((string(KEY) == Some(DIGEST.as_bytes())).then(|| string(VALUE).unwrap_or_default()))
}

/// The hash of `fields` other than the digest entry, and the digest entries' values.
fn hash(bytes: &[u8]) -> Result<(String, Vec<&[u8]>), Integrity> {
    let mut sha = Sha256::new();
    let mut claimed = Vec::new();
    for field in fields(bytes)? {
        match digest_entry(&field)? {
            Some(value) => claimed.push(value),
            None => sha.update(field.bytes),
        }
    }
    let hex: String = sha.finalize().iter().map(|b| format!("{b:02x}")).collect();
    Ok((format!("{PREFIX}{hex}"), claimed))
}

/// The digest of an encoded `ModelProto` (its digest entry, if any, left out): the value the
/// exporter writes under [`DIGEST`].
pub fn digest(model: &[u8]) -> Result<String, Integrity> {
    Ok(hash(model)?.0)
}

/// Checks that an encoded `ModelProto` carries one digest entry and that it matches the rest.
pub fn verify(model: &[u8]) -> Result<(), Integrity> {
    let (computed, claimed) = hash(model)?;
    match claimed[..] {
        [] => Err(Integrity::Missing),
        [value] if value == computed.as_bytes() => Ok(()),
        [value] => Err(Integrity::Mismatch { claimed: String::from_utf8_lossy(value).into_owned(), computed }),
        _ => Err(Integrity::Repeated),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn len_delimited(number: u64, payload: &[u8]) -> Vec<u8> {
        let mut out = vec![(number << 3 | 2) as u8, payload.len() as u8];
        out.extend_from_slice(payload);
        out
    }

    fn entry(key: &str, value: &str) -> Vec<u8> {
        len_delimited(METADATA_PROPS, &[len_delimited(KEY, key.as_bytes()), len_delimited(VALUE, value.as_bytes())].concat())
    }

    /// A small message: a varint field, a graph-like field, a metadata entry.
    fn model() -> Vec<u8> {
        [vec![1 << 3, 8], len_delimited(7, b"graph and weights"), entry("pvt3.classes", "[\"a\"]")].concat()
    }

    fn signed() -> Vec<u8> {
        let m = model();
        [m.clone(), entry(DIGEST, &digest(&m).unwrap())].concat()
    }

    #[test]
    fn a_signed_model_verifies_wherever_its_entry_stands() {
        assert_eq!(verify(&signed()), Ok(()));
        let m = model();
        let front = [entry(DIGEST, &digest(&m).unwrap()), m.clone()].concat();
        assert_eq!(verify(&front), Ok(()));
        assert!(digest(&m).unwrap().starts_with("sha256:") && digest(&m).unwrap().len() == 7 + 64);
        assert_eq!(digest(&signed()).unwrap(), digest(&model()).unwrap(), "the entry is left out of its own hash");
    }

    #[test]
    fn every_flip_and_truncation_is_refused_without_panicking() {
        let good = signed();
        let mut refused = 0;
        for at in 0..good.len() {
            for bit in 0..8 {
                let mut bad = good.clone();
                bad[at] ^= 1 << bit;
                assert!(verify(&bad).is_err(), "flip of bit {bit} at byte {at} verified");
                refused += 1;
            }
            assert!(verify(&good[..at]).is_err(), "truncation to {at} bytes verified");
        }
        assert_eq!(refused, good.len() * 8);
    }

    #[test]
    fn missing_repeated_and_malformed_are_told_apart() {
        assert_eq!(verify(&model()), Err(Integrity::Missing));
        let twice = [signed(), entry(DIGEST, "sha256:00")].concat();
        assert_eq!(verify(&twice), Err(Integrity::Repeated));
        assert!(matches!(verify(&[0x0b, 1, 2]), Err(Integrity::Malformed(_))), "wire type 3");
        assert!(matches!(verify(&[0x3a, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x01]), Err(Integrity::Malformed(_))));
        assert!(matches!(verify(&[0x3a, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x7f]), Err(Integrity::Malformed(_))));
        let other = [model(), entry(DIGEST, "sha256:0000")].concat();
        assert!(matches!(verify(&other), Err(Integrity::Mismatch { .. })));
    }
}
