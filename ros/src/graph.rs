//! The names rmw_zenoh gives a ROS 2 graph: a topic's key expression
//! (`<domain>/<topic>/<DDS type>/<type hash>`), which carries its messages, and each entity's
//! liveliness token (`@ros2_lv/<domain>/<session>/<node id>/<id>/<NN|MP|MS>/<enclave>/<namespace>/
//! <node>[/<topic>/<type>/<hash>/<QoS>]`, `/` written `%`), by which `ros2 node list` and
//! `ros2 topic list` find it. An entity's GID is the XXH3-128 of its token.

use crate::interfaces::{dds_name, type_hash, InterfaceError};

/// A node: its domain, namespace (`/` at the root), name and enclave (`/`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Node {
    /// `ROS_DOMAIN_ID`.
    pub domain: u32,
    /// `/`, or `/robot/left_hand`.
    pub namespace: String,
    /// `pvt3`.
    pub name: String,
    /// `/`.
    pub enclave: String,
}

/// The quality of service an endpoint declares, as far as rmw_zenoh's token records it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Qos {
    /// Best effort rather than reliable (ROS's sensor-data profile).
    pub best_effort: bool,
    /// Messages kept (`KEEP_LAST`).
    pub depth: usize,
}

impl Qos {
    /// rmw_zenoh's own default (reliable, 42 kept), which its token leaves unwritten.
    const DEFAULT_DEPTH: usize = 42;

    /// The QoS part of a token, each setting written only where it is not rmw_zenoh's default:
    /// `reliability:durability:history,depth:deadline:lifespan:liveliness`.
    fn key(self) -> String {
        let reliability = if self.best_effort { "2" } else { "" };
        let depth = if self.depth == Self::DEFAULT_DEPTH { String::new() } else { self.depth.to_string() };
        format!("{reliability}::,{depth}:,:,:,,")
    }
}

/// A topic: its fully qualified name, its type and the QoS of the endpoint on it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Topic {
    /// `/digit/image_raw`.
    pub name: String,
    /// `sensor_msgs/msg/Image`.
    pub type_name: String,
    /// `RIHS01_…`.
    pub hash: String,
    /// The endpoint's QoS.
    pub qos: Qos,
}

impl Topic {
    /// The topic `name` (fully qualified) of type `type_name`, with its type hash.
    pub fn new(name: &str, type_name: &str, qos: Qos) -> Result<Self, InterfaceError> {
        Ok(Self { name: name.to_string(), type_name: type_name.to_string(), hash: type_hash(type_name)?, qos })
    }

    /// The key expression its messages are put on, in `domain`.
    pub fn key_expr(&self, domain: u32) -> String {
        format!("{domain}/{}/{}/{}", self.name.trim_matches('/'), dds_name(&self.type_name), self.hash)
    }
}

/// What an entity of the graph is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A node (`NN`).
    Node,
    /// A publisher (`MP`).
    Publisher,
    /// A subscription (`MS`).
    Subscription,
}

/// An entity's liveliness token and its GID.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entity {
    /// The token's key expression.
    pub token: String,
    /// The XXH3-128 of the token, low half first (each half little-endian).
    pub gid: [u8; 16],
}

/// `/` written `%` (an empty name too), as a token's parts are.
fn mangle(name: &str) -> String {
    if name.is_empty() {
        return "%".into();
    }
    name.replace('/', "%")
}

impl Entity {
    /// The entity `id` of kind `kind` of `node` (itself number `node_id`) in the zenoh session
    /// `session` (its id in hex), on `topic` unless it is the node.
    pub fn new(session: &str, node_id: usize, id: usize, kind: Kind, node: &Node, topic: Option<&Topic>) -> Self {
        let kind = match kind {
            Kind::Node => "NN",
            Kind::Publisher => "MP",
            Kind::Subscription => "MS",
        };
        let (enclave, namespace, name) = (mangle(&node.enclave), mangle(&node.namespace), mangle(&node.name));
        let mut token = format!("@ros2_lv/{}/{session}/{node_id}/{id}/{kind}/{enclave}/{namespace}/{name}", node.domain);
        if let Some(t) = topic {
            token += &format!("/{}/{}/{}/{}", mangle(&t.name), mangle(&dds_name(&t.type_name)), mangle(&t.hash), t.qos.key());
        }
        Self { gid: gid(&token), token }
    }
}

/// The GID of the entity whose liveliness token is `token`: its XXH3-128, low half first (each
/// half little-endian), as rmw_zenoh derives it.
pub fn gid(token: &str) -> [u8; 16] {
    let hash = xxhash_rust::xxh3::xxh3_128(token.as_bytes());
    let mut gid = [0; 16];
    gid[..8].copy_from_slice(&(hash as u64).to_le_bytes());
    gid[8..].copy_from_slice(&((hash >> 64) as u64).to_le_bytes());
    gid
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_and_tokens_are_written_as_rmw_zenoh_writes_them() {
        let topic = Topic::new("/chatter", "std_msgs/msg/String", Qos { best_effort: false, depth: 10 }).unwrap();
        let hash = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18";
        assert_eq!(topic.key_expr(0), format!("0/chatter/std_msgs::msg::dds_::String_/{hash}"));
        let node = Node { domain: 0, namespace: "/".into(), name: "talker".into(), enclave: "/".into() };
        let session = "aac3178e146ba6f1fc6e6a4085e77f21";
        assert_eq!(Entity::new(session, 0, 0, Kind::Node, &node, None).token, format!("@ros2_lv/0/{session}/0/0/NN/%/%/talker"));
        let publisher = Entity::new(session, 0, 10, Kind::Publisher, &node, Some(&topic));
        assert_eq!(
            publisher.token,
            format!("@ros2_lv/0/{session}/0/10/MP/%/%/talker/%chatter/std_msgs::msg::dds_::String_/{hash}/::,10:,:,:,,")
        );
        let sensor = Qos { best_effort: true, depth: 42 };
        assert_eq!(sensor.key(), "2::,:,:,:,,");
        assert_ne!(publisher.gid, Entity::new(session, 0, 11, Kind::Publisher, &node, Some(&topic)).gid);
    }
}
