//! The part of ONNX's protobuf schema that `pvt3 export` writes and the runtime reads, decoded
//! with prost. Fields left out here (docs, shapes, opsets) are skipped by the decoder. The
//! runtime needs no ONNX operator registry, which is most of a full ONNX loader's size
//! (docs/deploy.md): [`crate::wire`] builds tract's own operators from these nodes directly.

use tract_core::prelude::*;

#[derive(Clone, PartialEq, prost::Message)]
pub(crate) struct Model {
    #[prost(message, optional, tag = "7")]
    pub graph: Option<Graph>,
    #[prost(message, repeated, tag = "14")]
    pub metadata_props: Vec<Entry>,
}

#[derive(Clone, PartialEq, prost::Message)]
pub(crate) struct Entry {
    #[prost(string, tag = "1")]
    pub key: String,
    #[prost(string, tag = "2")]
    pub value: String,
}

#[derive(Clone, PartialEq, prost::Message)]
pub(crate) struct Graph {
    #[prost(message, repeated, tag = "1")]
    pub node: Vec<Node>,
    #[prost(message, repeated, tag = "5")]
    pub initializer: Vec<TensorProto>,
}

#[derive(Clone, PartialEq, prost::Message)]
pub(crate) struct Node {
    #[prost(string, repeated, tag = "1")]
    pub input: Vec<String>,
    #[prost(string, repeated, tag = "2")]
    pub output: Vec<String>,
    #[prost(string, tag = "3")]
    pub name: String,
    #[prost(string, tag = "4")]
    pub op_type: String,
    #[prost(message, repeated, tag = "5")]
    pub attribute: Vec<Attribute>,
    #[prost(string, tag = "7")]
    pub domain: String,
}

#[derive(Clone, PartialEq, prost::Message)]
pub(crate) struct Attribute {
    #[prost(string, tag = "1")]
    pub name: String,
    #[prost(float, tag = "2")]
    pub f: f32,
    #[prost(int64, tag = "3")]
    pub i: i64,
    #[prost(int64, repeated, tag = "8")]
    pub ints: Vec<i64>,
}

#[derive(Clone, PartialEq, prost::Message)]
pub(crate) struct TensorProto {
    #[prost(int64, repeated, tag = "1")]
    pub dims: Vec<i64>,
    #[prost(int32, tag = "2")]
    pub data_type: i32,
    #[prost(float, repeated, tag = "4")]
    pub float_data: Vec<f32>,
    #[prost(int64, repeated, tag = "7")]
    pub int64_data: Vec<i64>,
    #[prost(string, tag = "8")]
    pub name: String,
    #[prost(bytes = "vec", tag = "9")]
    pub raw_data: Vec<u8>,
}

/// ONNX's `TensorProto.DataType` codes the exporter writes.
const FLOAT: i32 = 1;
const INT64: i32 = 7;

impl Model {
    pub(crate) fn decode(bytes: &[u8]) -> Result<Self, String> {
        let model = <Self as prost::Message>::decode(bytes).map_err(|e| e.to_string())?;
        if model.graph.is_none() {
            return Err("the file has no graph".into());
        }
        Ok(model)
    }
}

impl Node {
    fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attribute.iter().find(|a| a.name == name)
    }

    /// Whether the node has attribute `name`, of any type.
    pub(crate) fn has(&self, name: &str) -> bool {
        self.attribute(name).is_some()
    }

    /// Integer attribute `name`, or `default` when absent.
    pub(crate) fn int(&self, name: &str, default: i64) -> i64 {
        self.attribute(name).map_or(default, |a| a.i)
    }

    pub(crate) fn float(&self, name: &str, default: f32) -> f32 {
        self.attribute(name).map_or(default, |a| a.f)
    }

    pub(crate) fn ints(&self, name: &str) -> Option<&[i64]> {
        self.attribute(name).map(|a| a.ints.as_slice())
    }
}

impl TensorProto {
    /// The tensor, from `raw_data` (what the exporter writes) or the typed fields.
    pub(crate) fn to_tensor(&self) -> Result<Tensor, String> {
        let dims: Vec<usize> =
            self.dims.iter().map(|d| usize::try_from(*d)).collect::<Result<_, _>>().map_err(|_| self.bad("a negative dimension"))?;
        let len = dims.iter().try_fold(1usize, |n, d| n.checked_mul(*d)).ok_or_else(|| self.bad("too many values"))?;
        fn values<T: Datum + Copy, const N: usize>(raw: &[u8], typed: &[T], len: usize, from: fn([u8; N]) -> T) -> Option<Vec<T>> {
            let v: Vec<T> =
                if raw.is_empty() { typed.to_vec() } else { raw.chunks_exact(N).map(|c| from(c.try_into().expect("N bytes"))).collect() };
            (v.len() == len && (raw.is_empty() || raw.len() == len * N)).then_some(v)
        }
        let tensor = match self.data_type {
            FLOAT => values(&self.raw_data, &self.float_data, len, f32::from_le_bytes).map(|v| Tensor::from_shape(&dims, &v)),
            INT64 => values(&self.raw_data, &self.int64_data, len, i64::from_le_bytes).map(|v| Tensor::from_shape(&dims, &v)),
            other => return Err(self.bad(&format!("element type {other}, neither float32 nor int64"))),
        };
        tensor.ok_or_else(|| self.bad("a value count that does not fit its dimensions"))?.map_err(|e| self.bad(&e.to_string()))
    }

    fn bad(&self, problem: &str) -> String {
        format!("initializer `{}` has {problem}", self.name)
    }
}
