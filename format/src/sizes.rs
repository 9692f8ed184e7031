//! Sizes before allocation. Every size a file declares (an initializer's dimensions, the
//! window, a camera's recorded frame) is checked here against the bytes the file holds and
//! against [`Budget`], a bound derived from the file's own length, before a reader allocates
//! anything that size. A runtime checks every tensor its plan would compute against the same
//! budget before building it. A file that fails is refused by the name of what declared the
//! size. The digest proves a file is whole, not that it is sane: anyone can damage a graph and
//! sign it again, so these checks are what stands between a hostile file and an allocation
//! that fails, or aborts the process that loads it.

use crate::onnx::{DataType, DimensionValue, GraphProto, TensorProto};
use crate::{keys, Header, INPUT};

/// Values a tensor of one window may have for each byte of the file that asks for it.
/// The shipped files' largest tensor has 0.83 values a byte (the camera's features of every
/// pixel, `[frames, 3, 23, pixels]`), the window 0.04 (docs/deploy.md, "Sizes before allocation").
pub const VALUES_PER_BYTE: usize = 64;

/// A file is counted as at least this long, so a small model may still read a large window.
pub const LEAST_FILE_BYTES: usize = 1 << 20;

/// The most values one tensor may have for one window, for a file of a given length:
/// [`VALUES_PER_BYTE`] for each of its bytes, the file counted as at least
/// [`LEAST_FILE_BYTES`] long (64 Mi values, 256 MiB of float32, for any file up to 1 MiB).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    values: usize,
}

/// A size a file declares that it cannot hold, or that exceeds its [`Budget`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what} {problem}")]
pub struct SizeError {
    /// What declared the size: an initializer, a node or a metadata entry, by name.
    pub what: String,
    /// Why it is refused.
    pub problem: String,
}

impl Budget {
    /// The budget of a file of `bytes` bytes.
    pub fn of_file(bytes: usize) -> Self {
        Self { values: bytes.max(LEAST_FILE_BYTES).saturating_mul(VALUES_PER_BYTE) }
    }

    /// The most values a tensor of one window may have.
    pub fn values(self) -> usize {
        self.values
    }

    /// The values of a tensor of `dims` that holds `windows` windows, if it is within the
    /// budget. Axes of length 0 count as 1 here, so an empty tensor's other axes are bounded as
    /// a full one's (a `[2⁶², 0]` tensor holds nothing, but its strides overflow).
    pub fn admit(self, dims: &[usize], windows: usize) -> Result<usize, String> {
        let limit = self.values.saturating_mul(windows.max(1));
        let span = dims.iter().try_fold(1usize, |n, d| n.checked_mul((*d).max(1)));
        match span {
            Some(span) if span <= limit => Ok(dims.iter().product()),
            _ => Err(format!("of shape {dims:?}: more than the {limit} values a file of this size may ask for")),
        }
    }
}

/// Bytes per value of an element type the exporter writes, or `None` for any other.
fn value_bytes(data_type: i32) -> Option<usize> {
    match data_type {
        t if t == DataType::Float as i32 => Some(4),
        t if t == DataType::Int64 as i32 => Some(8),
        _ => None,
    }
}

impl TensorProto {
    /// The initializer's shape, once its dimensions are checked: none negative, within
    /// `budget`, and holding exactly the values its data has (`raw_data`'s bytes, or the
    /// typed field's values), of an element type the exporter writes (float32, int64).
    pub fn checked_shape(&self, budget: Budget) -> Result<Vec<usize>, SizeError> {
        let bad = |problem: String| SizeError { what: format!("initializer `{}`", self.name), problem };
        let dims: Vec<usize> = self
            .dims
            .iter()
            .map(|d| usize::try_from(*d))
            .collect::<Result<_, _>>()
            .map_err(|_| bad(format!("has a negative dimension ({:?})", self.dims)))?;
        let values = budget.admit(&dims, 1).map_err(|why| bad(format!("is {why}")))?;
        let size =
            value_bytes(self.data_type).ok_or_else(|| bad(format!("has element type {}, neither float32 nor int64", self.data_type)))?;
        let typed = if size == 4 { self.float_data.len() } else { self.int64_data.len() };
        let held = if self.raw_data.is_empty() { typed } else { self.raw_data.len() / size };
        if held != values || !self.raw_data.len().is_multiple_of(size) || (!self.raw_data.is_empty() && typed != 0) {
            let data =
                if self.raw_data.is_empty() { format!("{typed} typed values") } else { format!("{} bytes of data", self.raw_data.len()) };
            return Err(bad(format!("has dimensions {dims:?} ({values} values of {size} bytes) but {data}")));
        }
        Ok(dims)
    }
}

/// Checks every size a file declares before a reader allocates anything that size, and gives
/// the file's [`Budget`], which the runtime holds each tensor of its plans to:
/// - every initializer's ([`TensorProto::checked_shape`]);
/// - the window (`pvt3.config`) and a camera's recorded frame (`pvt3.camera`), each within the
///   budget;
/// - the graph's input, declared as the window under a batch axis, in float32.
///
/// `graph` is the file's graph, `header` its metadata as [`Header::parse`] read it and
/// `file_len` its length in bytes.
pub fn check_sizes(graph: &GraphProto, header: &Header, file_len: usize) -> Result<Budget, SizeError> {
    let budget = Budget::of_file(file_len);
    for t in &graph.initializer {
        t.checked_shape(budget)?;
    }
    let metadata = |key: &str, problem: String| SizeError { what: format!("metadata `{key}`"), problem };
    let window = header.sample_shape();
    budget.admit(&window, 1).map_err(|why| metadata(keys::CONFIG, format!("declares a window {why}")))?;
    if let Some(camera) = header.camera {
        budget.admit(&camera.recorded, 1).map_err(|why| metadata(keys::CAMERA, format!("declares recorded frames {why}")))?;
    }
    let declared = graph.input.iter().find(|i| i.name == INPUT);
    if let Some(input) = declared {
        let tensor = input.r#type.as_ref().and_then(|t| t.tensor_type.as_ref());
        let dims: Option<Vec<Option<i64>>> = tensor.and_then(|t| t.shape.as_ref()).map(|s| {
            s.dim
                .iter()
                .map(|d| match d.value {
                    Some(DimensionValue::DimValue(v)) => Some(v),
                    _ => None,
                })
                .collect()
        });
        let expected: Vec<Option<i64>> = std::iter::once(None).chain(window.iter().map(|d| Some(*d as i64))).collect();
        let float = tensor.is_some_and(|t| t.elem_type == DataType::Float as i32);
        if !float || dims.as_ref() != Some(&expected) {
            let window: Vec<String> = window.iter().map(|d| d.to_string()).collect();
            let problem = format!("is not float32 [batch, {}], the metadata's window", window.join(", "));
            return Err(SizeError { what: format!("graph input `{INPUT}`"), problem });
        }
    }
    Ok(budget)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn floats(name: &str, dims: &[i64], values: usize) -> TensorProto {
        TensorProto {
            dims: dims.to_vec(),
            data_type: DataType::Float as i32,
            name: name.into(),
            raw_data: vec![0; values * 4],
            ..Default::default()
        }
    }

    #[test]
    fn the_budget_grows_with_the_file_from_a_floor() {
        assert_eq!(Budget::of_file(0).values(), 64 << 20);
        assert_eq!(Budget::of_file(2 << 20).values(), 128 << 20);
        assert_eq!(Budget::of_file(usize::MAX).values(), usize::MAX, "saturates, never overflows");
        let b = Budget::of_file(1000);
        assert_eq!(b.admit(&[8, 1 << 20], 1), Ok(8 << 20));
        assert!(b.admit(&[65, 1 << 20], 1).is_err());
        assert_eq!(b.admit(&[65, 1 << 20], 2), Ok(65 << 20), "two windows, twice the values");
        assert_eq!(b.admit(&[0, 5], 1), Ok(0));
        let err = b.admit(&[1 << 62, 0], 1).unwrap_err();
        assert!(err.contains("[4611686018427387904, 0]"), "an empty tensor's axes are bounded: {err}");
        assert!(b.admit(&[usize::MAX, usize::MAX], 1).is_err(), "a product that overflows");
    }

    #[test]
    fn an_initializer_holds_what_its_dimensions_say() {
        let b = Budget::of_file(1 << 20);
        assert_eq!(floats("w", &[2, 3], 6).checked_shape(b), Ok(vec![2, 3]));
        let refused = [
            (floats("w", &[2, 3], 5), "has dimensions [2, 3] (6 values of 4 bytes) but 20 bytes of data"),
            (floats("w", &[2, -3], 6), "has a negative dimension ([2, -3])"),
            (floats("w", &[1 << 40, 0], 0), "is of shape [1099511627776, 0]: more than the 67108864 values"),
            (TensorProto { data_type: 11, ..floats("w", &[1], 1) }, "has element type 11, neither float32 nor int64"),
            (TensorProto { float_data: vec![1.0], ..floats("w", &[1], 1) }, "but 4 bytes of data"),
            (TensorProto { raw_data: vec![0; 7], ..floats("w", &[2], 0) }, "but 7 bytes of data"),
            (TensorProto { raw_data: vec![], int64_data: vec![1, 2], data_type: 7, ..floats("w", &[3], 0) }, "but 2 typed values"),
        ];
        for (t, why) in refused {
            let err = t.checked_shape(b).unwrap_err();
            assert!(err.to_string().starts_with("initializer `w` ") && err.to_string().contains(why), "{err}");
        }
    }
}
