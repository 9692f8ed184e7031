//! Every interface's type hash equals the one rosbags computes from its own definitions
//! (tests/ros_type_hashes.py): a wrong hash would leave the node unheard by every ROS 2 node.

#[path = "../../tests/support/onnx_check.rs"]
#[allow(dead_code)] // the other end-to-end tests use the rest of it
mod onnx_check;
#[path = "../../tests/support/workspace.rs"]
mod workspace;

use pvt3_ros::interfaces::{type_hash, INTERFACES};

#[test]
fn every_type_hash_is_rosbags_own() {
    let names: Vec<&str> = INTERFACES.iter().map(|i| i.name).collect();
    let said = onnx_check::run_script("tests/ros_type_hashes.py", &names);
    let theirs: Vec<(&str, &str)> = said.lines().filter_map(|l| l.split_once(' ')).collect();
    assert_eq!(theirs.len(), names.len(), "{said}");
    for (name, hash) in theirs {
        assert_eq!(type_hash(name).unwrap(), hash, "{name}");
    }
}
