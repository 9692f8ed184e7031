//! The ROS 2 interfaces the node speaks, by their `.msg` definitions as their packages ship
//! them, and each one's type hash (RIHS01, REP 2011): the SHA-256 of the type's description and
//! of every type it holds, as ROS writes it in JSON. rmw_zenoh puts the hash in every key
//! expression and liveliness token, so a subscriber hears only a publisher of the same type:
//! a wrong hash is silence, not an error. Constants and default values are not part of it.

use sha2::{Digest, Sha256};

/// A message type: its name (`sensor_msgs/msg/Image`) and its definition.
#[derive(Clone, Copy, Debug)]
pub struct Interface {
    /// `package/msg/Type`.
    pub name: &'static str,
    /// The `.msg` text: a field a line (`type name`), constants and comments allowed.
    pub definition: &'static str,
}

/// Every message type the node reads or writes, and those they hold.
pub const INTERFACES: [Interface; 20] = [
    Interface { name: "builtin_interfaces/msg/Time", definition: "int32 sec\nuint32 nanosec\n" },
    Interface { name: "std_msgs/msg/Header", definition: "builtin_interfaces/Time stamp\nstring frame_id\n" },
    Interface {
        name: "sensor_msgs/msg/Image",
        definition: "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n",
    },
    Interface { name: "sensor_msgs/msg/CompressedImage", definition: "std_msgs/Header header\nstring format\nuint8[] data\n" },
    Interface { name: "std_msgs/msg/MultiArrayDimension", definition: "string label\nuint32 size\nuint32 stride\n" },
    Interface { name: "std_msgs/msg/MultiArrayLayout", definition: "MultiArrayDimension[] dim\nuint32 data_offset\n" },
    Interface { name: "std_msgs/msg/Float32MultiArray", definition: "MultiArrayLayout layout\nfloat32[] data\n" },
    Interface { name: "std_msgs/msg/Float64MultiArray", definition: "MultiArrayLayout layout\nfloat64[] data\n" },
    Interface { name: "std_msgs/msg/Int16MultiArray", definition: "MultiArrayLayout layout\nint16[] data\n" },
    Interface { name: "std_msgs/msg/Int32MultiArray", definition: "MultiArrayLayout layout\nint32[] data\n" },
    Interface { name: "std_msgs/msg/UInt16MultiArray", definition: "MultiArrayLayout layout\nuint16[] data\n" },
    Interface { name: "std_msgs/msg/UInt8MultiArray", definition: "MultiArrayLayout layout\nuint8[] data\n" },
    Interface { name: "std_msgs/msg/Bool", definition: "bool data\n" },
    Interface { name: "std_msgs/msg/Empty", definition: "" },
    Interface { name: "vision_msgs/msg/ObjectHypothesis", definition: "string class_id\nfloat64 score\n" },
    Interface { name: "vision_msgs/msg/Classification", definition: "std_msgs/Header header\nObjectHypothesis[] results\n" },
    Interface { name: "diagnostic_msgs/msg/KeyValue", definition: "string key\nstring value\n" },
    Interface {
        name: "diagnostic_msgs/msg/DiagnosticStatus",
        definition: "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\nbyte level\nstring name\nstring message\nstring hardware_id\nKeyValue[] values\n",
    },
    Interface {
        name: "rcl_interfaces/msg/Log",
        definition: "uint8 DEBUG=10\nuint8 INFO=20\nuint8 WARN=30\nuint8 ERROR=40\nuint8 FATAL=50\nbuiltin_interfaces/Time stamp\nuint8 level\nstring name\nstring msg\nstring file\nstring function\nuint32 line\n",
    },
    Interface { name: "std_msgs/msg/String", definition: "string data\n" },
];

/// Why a type has no hash here: a type it names is not defined, or a line is not a field.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct InterfaceError(pub String);

/// The interface named `name`.
pub fn interface(name: &str) -> Result<&'static Interface, InterfaceError> {
    INTERFACES.iter().find(|i| i.name == name).ok_or_else(|| InterfaceError(format!("no definition of {name}")))
}

/// The name DDS and rmw_zenoh give a type: `sensor_msgs::msg::dds_::Image_`.
pub fn dds_name(name: &str) -> String {
    let mut parts: Vec<&str> = name.split('/').collect();
    let last = parts.pop().unwrap_or_default();
    format!("{}::dds_::{last}_", parts.join("::"))
}

/// A field of a definition: its name and the type_description_interfaces/FieldType of its type.
struct Field {
    name: String,
    type_id: u8,
    capacity: u64,
    string_capacity: u64,
    nested: String,
}

/// The primitive types' ids (type_description_interfaces/msg/FieldType).
const PRIMITIVES: [(&str, u8); 16] = [
    ("int8", 2),
    ("uint8", 3),
    ("int16", 4),
    ("uint16", 5),
    ("int32", 6),
    ("uint32", 7),
    ("int64", 8),
    ("uint64", 9),
    ("float32", 10),
    ("float64", 11),
    ("char", 13),
    ("bool", 15),
    ("byte", 16),
    ("string", 17),
    ("wstring", 18),
    ("bounded_string", 21),
];

/// The fields of `interface`, its nested types named in full (`std_msgs/msg/Header`).
fn fields(interface: &Interface) -> Result<Vec<Field>, InterfaceError> {
    let package = interface.name.split('/').next().unwrap_or_default();
    let mut out = Vec::new();
    for line in interface.definition.lines() {
        let line = line.split('#').next().unwrap_or_default().trim();
        let mut words = line.split_whitespace();
        let (Some(kind), Some(name)) = (words.next(), words.next()) else {
            if line.is_empty() {
                continue;
            }
            return Err(InterfaceError(format!("{}: `{line}` is not a field", interface.name)));
        };
        if name.contains('=') || words.next().is_some_and(|w| w.starts_with('=')) {
            continue; // a constant
        }
        out.push(field(package, kind, name)?);
    }
    if out.is_empty() {
        // As rosidl does for a message without fields.
        out.push(Field {
            name: "structure_needs_at_least_one_member".into(),
            type_id: 3,
            capacity: 0,
            string_capacity: 0,
            nested: String::new(),
        });
    }
    Ok(out)
}

/// A field `name` of type `kind` (`uint8[]`, `string<=8`, `Header`, `std_msgs/Header[4]`) in a
/// type of `package`.
fn field(package: &str, kind: &str, name: &str) -> Result<Field, InterfaceError> {
    let bad = || InterfaceError(format!("`{kind} {name}`: not a type"));
    let (base, offset, capacity) = match kind.split_once('[') {
        None => (kind, 0, 0),
        Some((base, rest)) => {
            let inside = rest.strip_suffix(']').ok_or_else(bad)?;
            match inside.strip_prefix("<=") {
                _ if inside.is_empty() => (base, 144, 0),
                Some(n) => (base, 96, n.parse().map_err(|_| bad())?),
                None => (base, 48, inside.parse().map_err(|_| bad())?),
            }
        }
    };
    let (base, string_capacity) = match base.split_once("<=") {
        Some(("string", n)) => ("bounded_string", n.parse().map_err(|_| bad())?),
        _ => (base, 0),
    };
    let (type_id, nested) = match PRIMITIVES.iter().find(|(p, _)| *p == base) {
        Some((_, id)) => (*id, String::new()),
        None => {
            let full = match base.split_once('/') {
                Some((pkg, ty)) => format!("{pkg}/msg/{ty}"),
                None => format!("{package}/msg/{base}"),
            };
            (1, full)
        }
    };
    Ok(Field { name: name.to_string(), type_id: type_id + offset, capacity, string_capacity, nested })
}

/// The JSON of one type's description, as ROS hashes it.
fn description_json(name: &str, fields: &[Field]) -> String {
    let fields: Vec<String> = fields
        .iter()
        .map(|f| {
            format!(
                "{{\"name\": \"{}\", \"type\": {{\"type_id\": {}, \"capacity\": {}, \"string_capacity\": {}, \"nested_type_name\": \"{}\"}}}}",
                f.name, f.type_id, f.capacity, f.string_capacity, f.nested
            )
        })
        .collect();
    format!("{{\"type_name\": \"{name}\", \"fields\": [{}]}}", fields.join(", "))
}

/// The type hash of the interface named `name`: `RIHS01_` and 64 hex digits.
pub fn type_hash(name: &str) -> Result<String, InterfaceError> {
    let top = fields(interface(name)?)?;
    // Every type it holds, at any depth, by name.
    let mut referenced = std::collections::BTreeMap::new();
    let mut pending: Vec<String> = top.iter().filter(|f| !f.nested.is_empty()).map(|f| f.nested.clone()).collect();
    while let Some(nested) = pending.pop() {
        if nested == name || referenced.contains_key(&nested) {
            continue;
        }
        let its = fields(interface(&nested)?)?;
        pending.extend(its.iter().filter(|f| !f.nested.is_empty()).map(|f| f.nested.clone()));
        referenced.insert(nested.clone(), description_json(&nested, &its));
    }
    let referenced: Vec<String> = referenced.into_values().collect();
    let json = format!(
        "{{\"type_description\": {}, \"referenced_type_descriptions\": [{}]}}",
        description_json(name, &top),
        referenced.join(", ")
    );
    let digest = Sha256::digest(json.as_bytes());
    Ok(format!("RIHS01_{}", digest.iter().map(|b| format!("{b:02x}")).collect::<String>()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hash_of_std_msgs_string_is_the_one_ros_publishes() {
        // rmw_zenoh's design document gives this key expression for a std_msgs/String topic.
        assert_eq!(type_hash("std_msgs/msg/String").unwrap(), "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18");
        assert_eq!(dds_name("std_msgs/msg/String"), "std_msgs::msg::dds_::String_");
    }

    #[test]
    fn every_interface_hashes_and_field_types_parse() {
        for i in INTERFACES {
            assert!(type_hash(i.name).unwrap().starts_with("RIHS01_"), "{}", i.name);
        }
        let f = field("sensor_msgs", "string<=8[<=3]", "x").unwrap();
        assert_eq!((f.type_id, f.capacity, f.string_capacity), (21 + 96, 3, 8));
        let f = field("sensor_msgs", "Header[4]", "x").unwrap();
        assert_eq!((f.type_id, f.capacity, f.nested.as_str()), (49, 4, "sensor_msgs/msg/Header"));
        assert!(type_hash("geometry_msgs/msg/Pose").unwrap_err().0.contains("no definition"));
    }
}
