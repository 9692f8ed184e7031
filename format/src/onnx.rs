//! The part of ONNX's protobuf schema (`onnx.proto`, opset 17) that `pvt3 export` writes and the
//! runtime reads, as prost messages, and [`Op`], the operators a pvt3 file may hold. The exporter
//! builds these messages and the runtime decodes them: one definition, so that a field or an
//! operator cannot be written without being read. Fields left out here (sparse tensors,
//! functions, training information) are skipped by the decoder and never written.

/// `ModelProto`: the file.
#[derive(Clone, PartialEq, prost::Message)]
pub struct ModelProto {
    /// The ONNX IR version the file is written in.
    #[prost(int64, tag = "1")]
    pub ir_version: i64,
    /// The operator sets the graph uses (the default domain's opset 17).
    #[prost(message, repeated, tag = "8")]
    pub opset_import: Vec<OperatorSetIdProto>,
    /// What wrote the file (`pvt3`).
    #[prost(string, tag = "2")]
    pub producer_name: String,
    /// The version of what wrote it.
    #[prost(string, tag = "3")]
    pub producer_version: String,
    /// The computation.
    #[prost(message, optional, tag = "7")]
    pub graph: Option<GraphProto>,
    /// The `pvt3.` metadata ([`crate::keys`]), the digest last.
    #[prost(message, repeated, tag = "14")]
    pub metadata_props: Vec<StringStringEntryProto>,
}

/// `OperatorSetIdProto`: an operator set the graph uses.
#[derive(Clone, PartialEq, prost::Message)]
pub struct OperatorSetIdProto {
    /// The operator set's domain (`""`: ONNX's default).
    #[prost(string, tag = "1")]
    pub domain: String,
    /// The operator set's version.
    #[prost(int64, tag = "2")]
    pub version: i64,
}

/// One metadata property.
#[derive(Clone, PartialEq, prost::Message)]
pub struct StringStringEntryProto {
    /// The property's key.
    #[prost(string, tag = "1")]
    pub key: String,
    /// The property's value.
    #[prost(string, tag = "2")]
    pub value: String,
}

/// `GraphProto`: the graph, its nodes, constants, inputs and outputs.
#[derive(Clone, PartialEq, prost::Message)]
pub struct GraphProto {
    /// The nodes, in an order where each reads only what nodes before it wrote.
    #[prost(message, repeated, tag = "1")]
    pub node: Vec<NodeProto>,
    /// The graph's name.
    #[prost(string, tag = "2")]
    pub name: String,
    /// The constants: weights and the shapes and indices nodes read.
    #[prost(message, repeated, tag = "5")]
    pub initializer: Vec<TensorProto>,
    /// The graph's inputs (pvt3's: [`crate::INPUT`]).
    #[prost(message, repeated, tag = "11")]
    pub input: Vec<ValueInfoProto>,
    /// The graph's outputs (pvt3's: [`crate::LOGITS`], [`crate::PROBABILITIES`]).
    #[prost(message, repeated, tag = "12")]
    pub output: Vec<ValueInfoProto>,
}

/// `NodeProto`: one operator applied to named tensors.
#[derive(Clone, PartialEq, prost::Message)]
pub struct NodeProto {
    /// The tensors the node reads, by name.
    #[prost(string, repeated, tag = "1")]
    pub input: Vec<String>,
    /// The tensors the node writes, by name.
    #[prost(string, repeated, tag = "2")]
    pub output: Vec<String>,
    /// The node's name, unique in the graph.
    #[prost(string, tag = "3")]
    pub name: String,
    /// An [`Op`]'s name.
    #[prost(string, tag = "4")]
    pub op_type: String,
    /// The operator's attributes.
    #[prost(message, repeated, tag = "5")]
    pub attribute: Vec<AttributeProto>,
    /// The operator's domain (`""`: ONNX's default).
    #[prost(string, tag = "7")]
    pub domain: String,
}

/// `AttributeProto.AttributeType`: the kinds of attribute the exporter writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(i32)]
pub enum AttributeType {
    /// A float (`f`).
    Float = 1,
    /// An integer (`i`).
    Int = 2,
    /// Integers (`ints`).
    Ints = 7,
}

/// `AttributeProto`: one attribute of a node (float, integer or integers).
#[derive(Clone, PartialEq, prost::Message)]
pub struct AttributeProto {
    /// The attribute's name.
    #[prost(string, tag = "1")]
    pub name: String,
    /// An [`AttributeType`].
    #[prost(int32, tag = "20")]
    pub r#type: i32,
    /// The value of a float attribute.
    #[prost(float, tag = "2")]
    pub f: f32,
    /// The value of an integer attribute.
    #[prost(int64, tag = "3")]
    pub i: i64,
    /// The values of an attribute of integers.
    #[prost(int64, repeated, tag = "8")]
    pub ints: Vec<i64>,
}

/// An integer attribute.
pub fn int(name: &str, v: i64) -> AttributeProto {
    AttributeProto { name: name.into(), r#type: AttributeType::Int as i32, i: v, ..Default::default() }
}

/// An attribute of integers.
pub fn ints(name: &str, v: &[i64]) -> AttributeProto {
    AttributeProto { name: name.into(), r#type: AttributeType::Ints as i32, ints: v.to_vec(), ..Default::default() }
}

/// A float attribute.
pub fn float(name: &str, v: f32) -> AttributeProto {
    AttributeProto { name: name.into(), r#type: AttributeType::Float as i32, f: v, ..Default::default() }
}

/// `TensorProto.DataType`: the element types the exporter writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(i32)]
pub enum DataType {
    /// 32-bit float.
    Float = 1,
    /// 64-bit integer.
    Int64 = 7,
}

/// `TensorProto`: a constant tensor (weights, shapes, indices).
#[derive(Clone, PartialEq, prost::Message)]
pub struct TensorProto {
    /// The tensor's shape.
    #[prost(int64, repeated, tag = "1")]
    pub dims: Vec<i64>,
    /// A [`DataType`].
    #[prost(int32, tag = "2")]
    pub data_type: i32,
    /// Float values, when not in `raw_data`.
    #[prost(float, repeated, tag = "4")]
    pub float_data: Vec<f32>,
    /// Integer values, when not in `raw_data`.
    #[prost(int64, repeated, tag = "7")]
    pub int64_data: Vec<i64>,
    /// The tensor's name, by which nodes read it.
    #[prost(string, tag = "8")]
    pub name: String,
    /// The values as little-endian bytes (how the exporter writes weights).
    #[prost(bytes = "vec", tag = "9")]
    pub raw_data: Vec<u8>,
}

/// A graph input or output: its name and a float tensor type.
#[derive(Clone, PartialEq, prost::Message)]
pub struct ValueInfoProto {
    /// The tensor's name.
    #[prost(string, tag = "1")]
    pub name: String,
    /// Its type: element type and shape.
    #[prost(message, optional, tag = "2")]
    pub r#type: Option<TypeProto>,
}

/// `TypeProto`: a value's type.
#[derive(Clone, PartialEq, prost::Message)]
pub struct TypeProto {
    /// A tensor's type (the only kind pvt3 writes).
    #[prost(message, optional, tag = "1")]
    pub tensor_type: Option<TensorTypeProto>,
}

/// `TypeProto.Tensor`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct TensorTypeProto {
    /// A [`DataType`].
    #[prost(int32, tag = "1")]
    pub elem_type: i32,
    /// The tensor's shape, fixed or named sizes.
    #[prost(message, optional, tag = "2")]
    pub shape: Option<TensorShapeProto>,
}

/// `TensorShapeProto`: a tensor's shape.
#[derive(Clone, PartialEq, prost::Message)]
pub struct TensorShapeProto {
    /// Each axis's size.
    #[prost(message, repeated, tag = "1")]
    pub dim: Vec<Dimension>,
}

/// `TensorShapeProto.Dimension`: a fixed size or a named one (the batch).
#[derive(Clone, PartialEq, prost::Message)]
pub struct Dimension {
    /// A fixed or a named size.
    #[prost(oneof = "DimensionValue", tags = "1, 2")]
    pub value: Option<DimensionValue>,
}

/// `TensorShapeProto.Dimension.value`: a fixed or a named size.
#[derive(Clone, PartialEq, prost::Oneof)]
pub enum DimensionValue {
    /// A fixed size.
    #[prost(int64, tag = "1")]
    DimValue(i64),
    /// A named size, given at run time (the batch).
    #[prost(string, tag = "2")]
    DimParam(String),
}

impl ModelProto {
    /// Signs the model: the integrity digest of everything else ([`crate::digest`]) as its last
    /// metadata property, in place of any earlier one. What the exporter does last, and what a
    /// test does after changing a file on purpose.
    pub fn sign(&mut self) {
        use prost::Message;
        self.metadata_props.retain(|e| e.key != crate::keys::DIGEST);
        let digest = crate::digest(&self.encode_to_vec()).expect("prost writes well-formed messages");
        self.metadata_props.push(StringStringEntryProto { key: crate::keys::DIGEST.into(), value: digest });
    }
}

impl NodeProto {
    /// Attribute `name`, if the node has it.
    pub fn attribute(&self, name: &str) -> Option<&AttributeProto> {
        self.attribute.iter().find(|a| a.name == name)
    }

    /// Whether the node has attribute `name`, of any type.
    pub fn has(&self, name: &str) -> bool {
        self.attribute(name).is_some()
    }

    /// Integer attribute `name`, or `default` when absent.
    pub fn int(&self, name: &str, default: i64) -> i64 {
        self.attribute(name).map_or(default, |a| a.i)
    }

    /// Float attribute `name`, or `default` when absent.
    pub fn float(&self, name: &str, default: f32) -> f32 {
        self.attribute(name).map_or(default, |a| a.f)
    }

    /// Integers attribute `name`, if the node has it.
    pub fn ints(&self, name: &str) -> Option<&[i64]> {
        self.attribute(name).map(|a| a.ints.as_slice())
    }

    /// The node's operator, if pvt3 writes it.
    pub fn op(&self) -> Option<Op> {
        Op::from_name(&self.op_type)
    }
}

macro_rules! ops {
    ($($(#[$doc:meta])* $op:ident = $name:literal,)*) => {
        /// The ONNX operators (opset 17, default domain) a pvt3 file holds: the exporter writes
        /// nothing else and the runtime wires each of them, matching this enum exhaustively.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Op {
            $(#[doc = concat!("ONNX's `", $name, "`.")] $(#[$doc])* $op,)*
        }

        impl Op {
            /// Every operator, in the enum's order.
            pub const ALL: &'static [Op] = &[$(Op::$op,)*];

            /// The operator's ONNX name (`NodeProto.op_type`).
            pub fn name(self) -> &'static str {
                match self {
                    $(Op::$op => $name,)*
                }
            }

            /// The operator named `name` (`NodeProto.op_type`), if pvt3 writes it.
            pub fn from_name(name: &str) -> Option<Self> {
                match name {
                    $($name => Some(Op::$op),)*
                    _ => None,
                }
            }
        }
    };
}

ops! {
    Add = "Add",
    Concat = "Concat",
    /// The spectral head's transform (a forward, two-sided transform of a real signal).
    Dft = "DFT",
    Div = "Div",
    Erf = "Erf",
    Exp = "Exp",
    Expand = "Expand",
    Gather = "Gather",
    Identity = "Identity",
    LayerNormalization = "LayerNormalization",
    Log = "Log",
    MatMul = "MatMul",
    Max = "Max",
    Mul = "Mul",
    ReduceMean = "ReduceMean",
    ReduceSum = "ReduceSum",
    Reshape = "Reshape",
    Shape = "Shape",
    Slice = "Slice",
    Softmax = "Softmax",
    Sqrt = "Sqrt",
    Sub = "Sub",
    Transpose = "Transpose",
}

impl std::fmt::Display for Op {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use prost::Message;

    #[test]
    fn every_operator_reads_back_by_its_name() {
        assert_eq!(Op::ALL.len(), 23);
        for op in Op::ALL {
            assert_eq!(Op::from_name(op.name()), Some(*op));
        }
        assert_eq!(Op::from_name("Conv"), None);
    }

    #[test]
    fn a_model_round_trips_through_its_bytes() {
        let node = NodeProto {
            input: vec!["x".into()],
            output: vec!["y".into()],
            name: "Softmax_0".into(),
            op_type: Op::Softmax.name().into(),
            attribute: vec![int("axis", -1), ints("perm", &[1, 0]), float("epsilon", 1e-5)],
            domain: String::new(),
        };
        let dim = |v| Dimension { value: Some(v) };
        let info = ValueInfoProto {
            name: "x".into(),
            r#type: Some(TypeProto {
                tensor_type: Some(TensorTypeProto {
                    elem_type: DataType::Float as i32,
                    shape: Some(TensorShapeProto {
                        dim: vec![dim(DimensionValue::DimParam("batch".into())), dim(DimensionValue::DimValue(3))],
                    }),
                }),
            }),
        };
        let model = ModelProto {
            ir_version: 8,
            opset_import: vec![OperatorSetIdProto { domain: String::new(), version: 17 }],
            producer_name: "pvt3".into(),
            producer_version: "0".into(),
            graph: Some(GraphProto {
                node: vec![node],
                name: "g".into(),
                initializer: vec![TensorProto {
                    dims: vec![2],
                    data_type: DataType::Int64 as i32,
                    int64_data: vec![4, 5],
                    ..Default::default()
                }],
                input: vec![info.clone()],
                output: vec![info],
            }),
            metadata_props: vec![StringStringEntryProto { key: "k".into(), value: "v".into() }],
        };
        let back = ModelProto::decode(&model.encode_to_vec()[..]).unwrap();
        assert_eq!(back, model);
        let node = &back.graph.unwrap().node[0];
        assert_eq!(
            (node.op(), node.int("axis", 0), node.ints("perm"), node.float("epsilon", 0.0)),
            (Some(Op::Softmax), -1, Some(&[1, 0][..]), 1e-5)
        );
        assert!(!node.has("keepdims"));
    }
}
