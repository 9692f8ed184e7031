"""The RIHS01 type hash (REP 2011) of each ROS 2 message type named on the command line, as
rosbags computes it from its own copy of the ROS 2 Jazzy definitions: the oracle for the hashes
pvt3-ros puts in its key expressions and liveliness tokens (ros/tests/interfaces.rs).
vision_msgs is no part of rosbags' store: its two types are defined here as vision_msgs 4.x
ships them.

    python tests/ros_type_hashes.py TYPE...     # prints `TYPE HASH` a line
"""

import sys

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

VISION_MSGS = {
    "vision_msgs/msg/ObjectHypothesis": "string class_id\nfloat64 score\n",
    "vision_msgs/msg/Classification": "std_msgs/Header header\nvision_msgs/ObjectHypothesis[] results\n",
}


def main(names):
    store = get_typestore(Stores.ROS2_JAZZY)
    for name, text in VISION_MSGS.items():
        store.register(get_types_from_msg(text, name))
    for name in names:
        print(name, store.hash_rihs01(name))


if __name__ == "__main__":
    main(sys.argv[1:])
