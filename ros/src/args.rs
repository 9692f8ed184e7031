//! The command line as ROS users write it: `pvt3-ros --ros-args -r frames:=/digit/image_raw -p
//! model:=felt.onnx`. `-r FROM:=TO` remaps a topic (a relative name, or one resolved in the
//! node's namespace) and `__node:=`, `__ns:=` rename the node or move it; `-p NAME:=VALUE` sets
//! a parameter ([`PARAMETERS`]); `ROS_DOMAIN_ID` picks the domain.

use crate::graph::Node;

/// Every parameter, its default and what it does, for `--help` and for refusing a misspelt one.
pub const PARAMETERS: [(&str, &str, &str); 6] = [
    ("model", "", "the pvt3 file (.onnx) to classify with; required"),
    (
        "touch",
        "frames",
        "how touches are cut: `frames` (each window a touch), `contact` (the contact topic's true to false) or `moving` (a camera's recording, taken over the span in which the gel moves)",
    ),
    ("recording", "300", "touch:=moving: the frames a recording holds; it ends there, or when the contact topic says false"),
    ("early_stop", "true", "answer as soon as the file's stopping rule decides, before the window is full"),
    ("frame_id", "", "the header.frame_id of the answers"),
    ("router", "tcp/localhost:7447", "the zenoh router of the ROS 2 graph (rmw_zenoh's `ros2 run rmw_zenoh_cpp rmw_zenohd`)"),
];

/// The node's topics: (its name before remapping, its type, what it carries). The frames' type
/// is the one its publisher declares (any type pvt3 reads; the node's own token names `Image`
/// for a camera's file and `Float32MultiArray` for a taxel array's).
pub const TOPICS: [(&str, &str, &str); 6] = [
    ("frames", "sensor_msgs/msg/Image, CompressedImage or std_msgs/msg/*MultiArray", "in: the sensor's frames"),
    ("contact", "std_msgs/msg/Bool", "in: true when the sensor touches, false when it lets go (touch:=contact, touch:=moving)"),
    ("reset", "std_msgs/msg/Empty", "in: ends the touch at once, unanswered"),
    ("classification", "vision_msgs/msg/Classification", "out: each touch's answer, one hypothesis a class, stamped with its last frame"),
    (
        "touch_status",
        "diagnostic_msgs/msg/DiagnosticStatus",
        "out: how it was reached: frames read, early stop, what ended it, compute time",
    ),
    ("/rosout", "rcl_interfaces/msg/Log", "out: frames refused and why"),
];

/// What the command line says.
#[derive(Clone, Debug, PartialEq)]
pub struct Args {
    /// The node's name and place.
    pub node: Node,
    /// Each parameter's value, defaults filled in.
    pub parameters: Vec<(String, String)>,
    /// `FROM:=TO` remappings of topics.
    pub remaps: Vec<(String, String)>,
}

/// Why a command line is refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ArgsError(pub String);

impl Args {
    /// Reads `args` (without the program's name) and `domain` (`ROS_DOMAIN_ID`, if set).
    pub fn parse(args: &[String], domain: Option<&str>) -> Result<Self, ArgsError> {
        let domain = match domain {
            Some(d) if !d.is_empty() => d.parse().map_err(|_| ArgsError(format!("ROS_DOMAIN_ID `{d}` is not a number from 0 to 232")))?,
            _ => 0,
        };
        let mut node = Node { domain, namespace: "/".into(), name: "pvt3".into(), enclave: "/".into() };
        let mut parameters: Vec<(String, String)> = PARAMETERS.iter().map(|(n, d, _)| (n.to_string(), d.to_string())).collect();
        let mut remaps = Vec::new();
        let mut ros = false;
        let mut words = args.iter();
        while let Some(word) = words.next() {
            match word.as_str() {
                "--ros-args" => ros = true,
                "--" => ros = false,
                "-r" | "--remap" | "-p" | "--param" if ros => {
                    let rule = words.next().ok_or_else(|| ArgsError(format!("{word} needs NAME:=VALUE")))?;
                    let (from, to) = rule.split_once(":=").ok_or_else(|| ArgsError(format!("{word} {rule}: expected NAME:=VALUE")))?;
                    if word.starts_with("-p") || word == "--param" {
                        let slot = parameters.iter_mut().find(|(n, _)| n == from).ok_or_else(|| {
                            let known: Vec<&str> = PARAMETERS.iter().map(|p| p.0).collect();
                            ArgsError(format!("-p {from}: no such parameter; pvt3-ros has {}", known.join(", ")))
                        })?;
                        slot.1 = to.to_string();
                    } else {
                        match from {
                            "__node" | "__name" => node.name = to.to_string(),
                            "__ns" => node.namespace = format!("/{}", to.trim_matches('/')),
                            _ => remaps.push((from.to_string(), to.to_string())),
                        }
                    }
                }
                other => {
                    return Err(ArgsError(format!("`{other}`: pvt3-ros takes --ros-args -r FROM:=TO and -p NAME:=VALUE (see --help)")))
                }
            }
        }
        Ok(Self { node, parameters, remaps })
    }

    /// The value of parameter `name`.
    pub fn parameter(&self, name: &str) -> &str {
        self.parameters.iter().find(|(n, _)| n == name).map_or("", |(_, v)| v.as_str())
    }

    /// The fully qualified name of the node's topic `name`: resolved in its namespace (`~/` in
    /// its own), then remapped where a rule names it or its resolved name.
    pub fn topic(&self, name: &str) -> String {
        let resolved = self.resolve(name);
        match self.remaps.iter().find(|(from, _)| *from == name || self.resolve(from) == resolved) {
            Some((_, to)) => self.resolve(to),
            None => resolved,
        }
    }

    fn resolve(&self, name: &str) -> String {
        let ns = self.node.namespace.trim_end_matches('/');
        if name.starts_with('/') {
            name.to_string()
        } else if let Some(private) = name.strip_prefix("~/") {
            format!("{ns}/{}/{private}", self.node.name)
        } else {
            format!("{ns}/{name}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(line: &str) -> Result<Args, ArgsError> {
        Args::parse(&line.split_whitespace().map(String::from).collect::<Vec<_>>(), None)
    }

    #[test]
    fn remaps_and_parameters_as_ros_users_write_them() {
        let a =
            parse("--ros-args -r __ns:=/hand -r __node:=skin -r frames:=/digit/image_raw -p model:=felt.onnx -p touch:=contact").unwrap();
        assert_eq!((a.node.namespace.as_str(), a.node.name.as_str()), ("/hand", "skin"));
        assert_eq!(a.topic("frames"), "/digit/image_raw");
        assert_eq!(a.topic("classification"), "/hand/classification");
        assert_eq!(a.topic("~/x"), "/hand/skin/x");
        assert_eq!(a.topic("/rosout"), "/rosout");
        assert_eq!((a.parameter("model"), a.parameter("touch"), a.parameter("early_stop")), ("felt.onnx", "contact", "true"));
        let a = parse("--ros-args -r /hand/contact:=gripper/touching -r __ns:=/hand").unwrap();
        assert_eq!(a.topic("contact"), "/hand/gripper/touching");
    }

    #[test]
    fn the_guide_lists_every_parameter_with_its_default() {
        let guide = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/guide/ros.md")).unwrap();
        for (name, default, _) in PARAMETERS {
            let shown = if default.is_empty() { "(".to_string() } else { format!("`{default}`") };
            assert!(guide.contains(&format!("| `{name}` | {shown}")), "docs/guide/ros.md: no row for `{name}`");
        }
    }

    #[test]
    fn what_it_cannot_read_is_refused_by_name() {
        assert!(parse("--ros-args -p modle:=x").unwrap_err().0.contains("-p modle: no such parameter; pvt3-ros has model,"));
        assert!(parse("--ros-args -r frames").unwrap_err().0.contains("expected NAME:=VALUE"));
        assert!(parse("model.onnx").unwrap_err().0.contains("`model.onnx`: pvt3-ros takes --ros-args"));
        assert!(Args::parse(&[], Some("x")).unwrap_err().0.contains("ROS_DOMAIN_ID `x`"));
    }
}
