//! Reading the exporter's ONNX: the messages are `pvt3_format::onnx` (prost, shared with the
//! exporter, so a field cannot be written without being read), decoded here, and an initializer
//! becomes a tract tensor. Fields the messages leave out are skipped by the decoder. The runtime
//! needs no ONNX operator registry, which is most of a full ONNX loader's size
//! (docs/deploy.md): [`crate::wire`] builds tract's own operators from these nodes directly.

use prost::Message;
use pvt3_format::onnx::{DataType, ModelProto, TensorProto};
use tract_core::prelude::*;

/// The model in `bytes`, which must have a graph.
pub(crate) fn decode(bytes: &[u8]) -> Result<ModelProto, String> {
    let model = ModelProto::decode(bytes).map_err(|e| e.to_string())?;
    if model.graph.is_none() {
        return Err("the file has no graph".into());
    }
    Ok(model)
}

/// The initializer `t` as a tensor, from `raw_data` (what the exporter writes) or the typed fields.
pub(crate) fn to_tensor(t: &TensorProto) -> Result<Tensor, String> {
    let bad = |problem: &str| format!("initializer `{}` has {problem}", t.name);
    let dims: Vec<usize> = t.dims.iter().map(|d| usize::try_from(*d)).collect::<Result<_, _>>().map_err(|_| bad("a negative dimension"))?;
    let len = dims.iter().try_fold(1usize, |n, d| n.checked_mul(*d)).ok_or_else(|| bad("too many values"))?;
    fn values<T: Datum + Copy, const N: usize>(raw: &[u8], typed: &[T], len: usize, from: fn([u8; N]) -> T) -> Option<Vec<T>> {
        let v: Vec<T> =
            if raw.is_empty() { typed.to_vec() } else { raw.chunks_exact(N).map(|c| from(c.try_into().expect("N bytes"))).collect() };
        (v.len() == len && (raw.is_empty() || raw.len() == len * N)).then_some(v)
    }
    let tensor = match t.data_type {
        x if x == DataType::Float as i32 => {
            values(&t.raw_data, &t.float_data, len, f32::from_le_bytes).map(|v| Tensor::from_shape(&dims, &v))
        }
        x if x == DataType::Int64 as i32 => {
            values(&t.raw_data, &t.int64_data, len, i64::from_le_bytes).map(|v| Tensor::from_shape(&dims, &v))
        }
        other => return Err(bad(&format!("element type {other}, neither float32 nor int64"))),
    };
    tensor.ok_or_else(|| bad("a value count that does not fit its dimensions"))?.map_err(|e| bad(&e.to_string()))
}
