//! Reading the exporter's ONNX: the messages are `pvt3_format::onnx` (prost, shared with the
//! exporter, so a field cannot be written without being read), decoded here, and an initializer
//! becomes a tract tensor. Fields the messages leave out are skipped by the decoder. The runtime
//! needs no ONNX operator registry, which is most of a full ONNX loader's size
//! (docs/deploy.md): [`crate::wire`] builds tract's own operators from these nodes directly.

use prost::Message;
use pvt3_format::onnx::{DataType, ModelProto, TensorProto};
use pvt3_format::Budget;
use tract_core::prelude::*;

/// The model in `bytes`, which must have a graph.
pub(crate) fn decode(bytes: &[u8]) -> Result<ModelProto, String> {
    let model = ModelProto::decode(bytes).map_err(|e| e.to_string())?;
    if model.graph.is_none() {
        return Err("the file has no graph".into());
    }
    Ok(model)
}

/// The initializer `t` as a tensor, from `raw_data` (what the exporter writes) or the typed
/// fields, its size checked against `budget` first ([`TensorProto::checked_shape`]).
pub(crate) fn to_tensor(t: &TensorProto, budget: Budget) -> Result<Tensor, String> {
    let dims = t.checked_shape(budget).map_err(|e| e.to_string())?;
    fn values<T: Datum + Copy, const N: usize>(raw: &[u8], typed: &[T], from: fn([u8; N]) -> T) -> Vec<T> {
        if raw.is_empty() {
            typed.to_vec()
        } else {
            raw.chunks_exact(N).map(|c| from(c.try_into().expect("N bytes"))).collect()
        }
    }
    let tensor = if t.data_type == DataType::Float as i32 {
        Tensor::from_shape(&dims, &values(&t.raw_data, &t.float_data, f32::from_le_bytes))
    } else {
        Tensor::from_shape(&dims, &values(&t.raw_data, &t.int64_data, i64::from_le_bytes))
    };
    tensor.map_err(|e| format!("initializer `{}`: {e}", t.name))
}
