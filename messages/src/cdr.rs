//! CDR (OMG's Common Data Representation, XCDR1), as ROS 2 serialises a message: a 4-byte
//! encapsulation header saying the byte order, then each field in order, aligned to its own size
//! (up to 8 bytes) from the end of the header; a string is its length (with its terminating NUL)
//! and its bytes, a sequence its length and its elements. [`Reader`] reads either byte order;
//! [`Writer`] writes little-endian, as ROS 2 does on every platform it runs on.

use crate::{DecodeError, Result};

/// A cursor over one message's CDR bytes.
pub struct Reader<'a> {
    bytes: &'a [u8],
    /// The next byte, counted from the end of the encapsulation header.
    at: usize,
    little: bool,
}

/// A value of a fixed size read from CDR.
pub trait Primitive: Sized + Copy {
    /// Its size in bytes, which is also its alignment.
    const SIZE: usize;
    /// The value from its bytes in the message's order.
    fn from_bytes(bytes: &[u8], little: bool) -> Self;
    /// Its bytes, little-endian, appended to `out`.
    fn to_le(self, out: &mut Vec<u8>);
}

macro_rules! primitive {
    ($($t:ty),*) => {$(
        impl Primitive for $t {
            const SIZE: usize = std::mem::size_of::<$t>();
            fn from_bytes(bytes: &[u8], little: bool) -> Self {
                let b = bytes.try_into().expect("SIZE bytes");
                if little { <$t>::from_le_bytes(b) } else { <$t>::from_be_bytes(b) }
            }
            fn to_le(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
        }
    )*};
}
primitive!(u8, i8, u16, i16, u32, i32, u64, i64, f32, f64);

impl<'a> Reader<'a> {
    /// A reader of `message`, after its encapsulation header: plain CDR, little- or big-endian
    /// (`00 01` or `00 00`, then two bytes of options).
    pub fn new(message: &'a [u8]) -> Result<Self> {
        let little = match message.get(..4) {
            Some([0, 1, _, _]) => true,
            Some([0, 0, _, _]) => false,
            Some(h) => return Err(DecodeError(format!("an encapsulation header {h:02x?}, not plain CDR (00 00 or 00 01)"))),
            None => return Err(DecodeError(format!("{} bytes, too short for a CDR message", message.len()))),
        };
        Ok(Self { bytes: &message[4..], at: 0, little })
    }

    /// The next `n` bytes, after padding to `align`; `what` names the field in an error.
    fn take(&mut self, n: usize, align: usize, what: &str) -> Result<&'a [u8]> {
        let start = self.at.next_multiple_of(align);
        let end = start.checked_add(n).filter(|end| *end <= self.bytes.len());
        let end = end.ok_or_else(|| {
            let left = self.bytes.len().saturating_sub(start);
            DecodeError(format!("truncated: {what} at byte {} needs {n} bytes, {left} are left", start + 4))
        })?;
        self.at = end;
        Ok(&self.bytes[start..end])
    }

    /// A value of type `T`.
    pub fn read<T: Primitive>(&mut self, what: &str) -> Result<T> {
        let little = self.little;
        Ok(T::from_bytes(self.take(T::SIZE, T::SIZE, what)?, little))
    }

    /// A string (UTF-8 is not required of it: a lossy copy).
    pub fn string(&mut self, what: &str) -> Result<String> {
        let len = self.read::<u32>(what)? as usize;
        let bytes = self.take(len, 1, what)?;
        Ok(String::from_utf8_lossy(bytes.strip_suffix(&[0]).unwrap_or(bytes)).into_owned())
    }

    /// A sequence's length: its elements follow.
    pub fn length(&mut self, what: &str) -> Result<usize> {
        Ok(self.read::<u32>(what)? as usize)
    }

    /// A sequence of bytes, borrowed.
    pub fn bytes(&mut self, what: &str) -> Result<&'a [u8]> {
        let len = self.length(what)?;
        self.take(len, 1, what)
    }

    /// A sequence of `T`, each converted to f32 by `to`. Its length is checked against the
    /// bytes left before anything is allocated.
    pub fn values<T: Primitive>(&mut self, what: &str, to: fn(T) -> f32) -> Result<Vec<f32>> {
        let len = self.length(what)?;
        let little = self.little;
        let bytes = self.take(len.saturating_mul(T::SIZE), T::SIZE, what)?;
        Ok(bytes.chunks_exact(T::SIZE).map(|b| to(T::from_bytes(b, little))).collect())
    }
}

/// A message being written: the encapsulation header of little-endian CDR, then each field
/// aligned as [`Reader`] reads it.
pub struct Writer {
    bytes: Vec<u8>,
}

impl Default for Writer {
    fn default() -> Self {
        Self::new()
    }
}

impl Writer {
    /// An empty message.
    pub fn new() -> Self {
        Self { bytes: vec![0, 1, 0, 0] }
    }

    /// Pads to `align` bytes from the end of the header.
    fn align(&mut self, align: usize) {
        let at = (self.bytes.len() - 4).next_multiple_of(align) + 4;
        self.bytes.resize(at, 0);
    }

    /// A value of type `T`.
    pub fn write<T: Primitive>(&mut self, value: T) -> &mut Self {
        self.align(T::SIZE);
        value.to_le(&mut self.bytes);
        self
    }

    /// A string: its length with its terminating NUL, its bytes, the NUL.
    pub fn string(&mut self, text: &str) -> &mut Self {
        self.write((text.len() + 1) as u32);
        self.bytes.extend_from_slice(text.as_bytes());
        self.bytes.push(0);
        self
    }

    /// A sequence's length, its elements to follow.
    pub fn length(&mut self, len: usize) -> &mut Self {
        self.write(len as u32)
    }

    /// The message's bytes.
    pub fn finish(self) -> Vec<u8> {
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_aligned_from_the_end_of_the_header() {
        // u8 1, (pad 3) u32 7, string "ab", (pad 1) u16 0x0102, (pad 6, to 24) f64 1.5
        let mut m = vec![0, 1, 0, 0, 1, 0, 0, 0, 7, 0, 0, 0, 3, 0, 0, 0, b'a', b'b', 0, 0, 2, 1, 0, 0, 0, 0, 0, 0];
        m.extend_from_slice(&1.5f64.to_le_bytes());
        let mut r = Reader::new(&m).unwrap();
        assert_eq!(r.read::<u8>("a").unwrap(), 1);
        assert_eq!(r.read::<u32>("b").unwrap(), 7);
        assert_eq!(r.string("c").unwrap(), "ab");
        assert_eq!(r.read::<u16>("d").unwrap(), 0x0102);
        assert_eq!(r.read::<f64>("e").unwrap(), 1.5);
        let err = r.read::<u8>("f").unwrap_err().0;
        assert_eq!(err, "truncated: f at byte 36 needs 1 bytes, 0 are left");
    }

    #[test]
    fn what_the_writer_writes_the_reader_reads() {
        let mut w = Writer::new();
        w.write(1u8).write(7u32).string("ab").write(0x0102u16).write(1.5f64).length(2).write(-3i16).write(4i16);
        let m = w.finish();
        let mut r = Reader::new(&m).unwrap();
        assert_eq!((r.read::<u8>("a").unwrap(), r.read::<u32>("b").unwrap()), (1, 7));
        assert_eq!((r.string("c").unwrap(), r.read::<u16>("d").unwrap(), r.read::<f64>("e").unwrap()), ("ab".into(), 0x0102, 1.5));
        assert_eq!(r.values::<i16>("f", f32::from).unwrap(), [-3.0, 4.0]);
        assert_eq!(m.len(), 36 + 4 + 2 * 2, "aligned as the reader's test lays its fields out, then the sequence");
    }

    #[test]
    fn big_endian_and_foreign_headers() {
        let m = [0, 0, 0, 0, 0, 0, 1, 2];
        assert_eq!(Reader::new(&m).unwrap().read::<u32>("x").unwrap(), 0x0102);
        assert!(Reader::new(&[0, 3, 0, 0]).err().unwrap().0.contains("not plain CDR"));
        assert!(Reader::new(&[0, 1]).err().unwrap().0.contains("too short"));
    }

    #[test]
    fn a_sequence_longer_than_its_bytes_is_refused_before_allocation() {
        let m = [0, 1, 0, 0, 0xff, 0xff, 0xff, 0xff, 1, 2];
        let err = Reader::new(&m).unwrap().values::<f32>("data", |v| v).unwrap_err().0;
        assert!(err.contains("data at byte 8 needs 17179869180 bytes, 2 are left"), "{err}");
    }
}
