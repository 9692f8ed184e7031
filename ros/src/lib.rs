//! pvt3 on a ROS 2 robot: a node, in pure Rust, that joins a ROS 2 graph over rmw_zenoh (a zenoh
//! router on the robot, the key expressions, liveliness tokens and attachments rmw_zenoh_cpp
//! writes), subscribes to a tactile sensor's topic, decodes each message with `pvt3_messages`
//! (as `pvt3 import` decodes a bag), classifies the touch with the runtime's session and
//! publishes the answer as `vision_msgs/msg/Classification`.
//!
//! [`interfaces`] holds the message types it speaks and their type hashes; [`graph`] names its
//! entities as rmw_zenoh does; [`args`] reads a ROS command line; [`touch`] follows a touch
//! through the runtime, free of any transport; [`outgoing`] writes the answers; [`node`] joins
//! the graph and serves.

#![warn(missing_docs)]

pub mod args;
pub mod graph;
pub mod interfaces;
pub mod node;
pub mod outgoing;
pub mod touch;
