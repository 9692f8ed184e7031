//! A small builder for ONNX graphs: constants become initializers, every node gets a fresh
//! output name, attributes are built by helpers.

use pvt3_format::onnx::{AttributeProto, DataType, NodeProto, Op, TensorProto};

/// Constants up to this size are shared between the nodes that use the same value.
const SHARED_BYTES: usize = 1024;

#[derive(Default)]
pub struct Graph {
    pub nodes: Vec<NodeProto>,
    pub initializers: Vec<TensorProto>,
    count: usize,
}

impl Graph {
    fn fresh(&mut self, hint: &str) -> String {
        self.count += 1;
        format!("{hint}_{}", self.count)
    }

    /// A constant; a small one (a scalar, a shape, an index list) equal to one written before is
    /// that one, so `eps`, `one`, `[-1]`… appear once in the file.
    fn initializer(&mut self, hint: &str, dims: &[usize], data_type: DataType, raw_data: Vec<u8>) -> String {
        let dims: Vec<i64> = dims.iter().map(|d| *d as i64).collect();
        if raw_data.len() <= SHARED_BYTES {
            let same = |t: &&TensorProto| t.raw_data == raw_data && t.dims == dims && t.data_type == data_type as i32;
            if let Some(t) = self.initializers.iter().find(same) {
                return t.name.clone();
            }
        }
        let name = self.fresh(hint);
        self.initializers.push(TensorProto { name: name.clone(), dims, data_type: data_type as i32, raw_data, ..Default::default() });
        name
    }

    pub fn f32s(&mut self, hint: &str, dims: &[usize], data: Vec<f32>) -> String {
        debug_assert_eq!(dims.iter().product::<usize>(), data.len(), "{hint}");
        self.initializer(hint, dims, DataType::Float, data.iter().flat_map(|v| v.to_le_bytes()).collect())
    }

    pub fn i64s(&mut self, hint: &str, dims: &[usize], data: Vec<i64>) -> String {
        self.initializer(hint, dims, DataType::Int64, data.iter().flat_map(|v| v.to_le_bytes()).collect())
    }

    /// A node with one output, named after `hint` unless `output` is given.
    pub fn node(&mut self, op: Op, inputs: &[&str], attribute: Vec<AttributeProto>, output: Option<&str>) -> String {
        let out = output.map_or_else(|| self.fresh(&op.name().to_lowercase()), str::to_string);
        self.nodes.push(NodeProto {
            op_type: op.name().into(),
            name: format!("{op}_{}", self.nodes.len()),
            input: inputs.iter().map(|s| s.to_string()).collect(),
            output: vec![out.clone()],
            attribute,
            ..Default::default()
        });
        out
    }

    pub fn op(&mut self, op: Op, inputs: &[&str]) -> String {
        self.node(op, inputs, vec![], None)
    }
}
