//! Cutting an ONNX graph at named tensors: the nodes that compute `outputs` from `inputs`, with
//! the initializers they read. This is how the streaming session runs the spatial and the
//! temporal stage of the one exported file separately, without a second file to keep in step.

use std::collections::HashSet;

use tract_onnx::pb::{
    tensor_proto::DataType, tensor_shape_proto::dimension::Value as Dim, tensor_shape_proto::Dimension, type_proto, GraphProto, ModelProto,
    TensorShapeProto, TypeProto, ValueInfoProto,
};

/// A tensor that becomes an input of the cut graph.
pub(crate) struct Seam<'a> {
    pub name: &'a str,
    pub data_type: DataType,
    pub shape: Vec<usize>,
}

fn value_info(seam: &Seam) -> ValueInfoProto {
    let dim = seam.shape.iter().map(|v| Dimension { value: Some(Dim::DimValue(*v as i64)), ..Default::default() });
    ValueInfoProto {
        name: seam.name.into(),
        r#type: Some(TypeProto {
            value: Some(type_proto::Value::TensorType(type_proto::Tensor {
                elem_type: seam.data_type as i32,
                shape: Some(TensorShapeProto { dim: dim.collect() }),
            })),
            ..Default::default()
        }),
        ..Default::default()
    }
}

/// The part of `model` that maps `inputs` to `outputs`; an error names a tensor the cut would
/// still need from outside (a seam the file does not have, or one in the wrong place).
pub(crate) fn cut(model: &ModelProto, inputs: &[Seam], outputs: &[&str]) -> Result<ModelProto, String> {
    let graph = model.graph.as_ref().ok_or("the file has no graph")?;
    for name in inputs.iter().map(|s| s.name).chain(outputs.iter().copied()) {
        if !graph.node.iter().any(|n| n.output.iter().any(|o| o == name)) {
            return Err(format!("no tensor named `{name}` (exported by an older pvt3?)"));
        }
    }
    let seams: HashSet<&str> = inputs.iter().map(|s| s.name).collect();
    let mut needed: HashSet<&str> = outputs.iter().copied().collect();
    let mut keep = vec![false; graph.node.len()];
    // ONNX lists nodes in topological order, so one backward pass finds every producer.
    for (i, node) in graph.node.iter().enumerate().rev() {
        if node.output.iter().any(|o| needed.contains(o.as_str())) && !node.output.iter().any(|o| seams.contains(o.as_str())) {
            keep[i] = true;
            needed.extend(node.input.iter().map(String::as_str).filter(|n| !n.is_empty() && !seams.contains(n)));
        }
    }
    let produced: HashSet<&str> =
        graph.node.iter().zip(&keep).filter(|(_, k)| **k).flat_map(|(n, _)| n.output.iter().map(String::as_str)).collect();
    let initializer: Vec<_> = graph.initializer.iter().filter(|t| needed.contains(t.name.as_str())).cloned().collect();
    let mut missing: Vec<&str> =
        needed.iter().filter(|n| !produced.contains(*n) && !initializer.iter().any(|t| t.name == **n)).copied().collect();
    if !missing.is_empty() {
        missing.sort();
        return Err(format!("the cut still needs {}", missing.join(", ")));
    }
    let output = outputs
        .iter()
        .map(|o| {
            graph
                .output
                .iter()
                .find(|v| v.name == *o)
                .cloned()
                .unwrap_or_else(|| ValueInfoProto { name: o.to_string(), ..Default::default() })
        })
        .collect();
    let graph = GraphProto {
        name: format!("{}:{}", graph.name, outputs.join("+")),
        node: graph.node.iter().zip(&keep).filter(|(_, k)| **k).map(|(n, _)| n.clone()).collect(),
        initializer,
        input: inputs.iter().map(value_info).collect(),
        output,
        ..Default::default()
    };
    Ok(ModelProto { graph: Some(graph), ..model.clone() })
}
