"""The rest of a ROS 2 graph around pvt3-ros, written with libraries no one here wrote, for
ros/tests/node.rs: eclipse-zenoh as the graph's router (tcp/127.0.0.1:PORT, no multicast, no
scouting) and as a sensor driver and a listener; rosbags serialises and reads the messages and
computes the type hashes the keys carry.

    python tests/ros_peer.py PORT TOUCHES.npy KIND [HOSTILE]

It prints `ready` once the router listens, waits for pvt3-ros's subscription to `/frames`
(its liveliness token), then publishes each touch of TOUCHES.npy ([touches,] height, width,
[channels,] frames), frame by frame, on /frames: KIND `image` as sensor_msgs/msg/Image (rgb8, or
mono8 for one channel), `array` as std_msgs/msg/Float32MultiArray (the grid row-major, its
layout's two dimensions), each with rmw_zenoh's attachment naming its publisher (blocking, never dropping, when the link
is busy: the test's driver loses no frame) (the GID of its
liveliness token, by python-xxhash). With HOSTILE, first a burst of messages the node must
refuse and survive: a wrong size, an unknown encoding, cut CDR, a type it does not read; then a
publisher that leaves half way through a touch (its token undeclared); and within each touch,
a second publisher's frame and a frame stamped before the one before it. It prints each
answer read from /classification (vision_msgs/msg/Classification) as a JSON line, and each
/touch_status as one too, and exits once every touch is answered (or after 60 s).
"""

import json
import sys
import time

import numpy as np
import xxhash
import zenoh
from zenoh.ext import Int64, z_serialize
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

STORE = get_typestore(Stores.ROS2_JAZZY)
STORE.register(get_types_from_msg("string class_id\nfloat64 score\n", "vision_msgs/msg/ObjectHypothesis"))
STORE.register(
    get_types_from_msg("std_msgs/Header header\nvision_msgs/ObjectHypothesis[] results\n", "vision_msgs/msg/Classification")
)
T = STORE.types


def key(topic, msgtype):
    """rmw_zenoh's key expression of a topic in domain 0."""
    package, _, name = msgtype.split("/")
    return f"0/{topic}/{package}::msg::dds_::{name}_/{STORE.hash_rihs01(msgtype)}"


def stamp(ns):
    return T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)


def image(frame, ns, encoding=None):
    """An Image of an 8-bit [H, W, C] frame."""
    h, w = frame.shape[:2]
    channels = frame.shape[2] if frame.ndim == 3 else 1
    encoding = encoding or ("rgb8" if channels == 3 else "mono8")
    header = T["std_msgs/msg/Header"](stamp=stamp(ns), frame_id="sensor")
    message = T["sensor_msgs/msg/Image"](
        header=header, height=h, width=w, encoding=encoding, is_bigendian=0, step=w * channels, data=frame.reshape(-1)
    )
    return STORE.serialize_cdr(message, "sensor_msgs/msg/Image")


def array(frame):
    """A Float32MultiArray of a [rows, cols] frame."""
    dims = [T["std_msgs/msg/MultiArrayDimension"](label=l, size=s, stride=st) for l, s, st in (("rows", frame.shape[0], frame.size), ("cols", frame.shape[1], frame.shape[1]))]
    layout = T["std_msgs/msg/MultiArrayLayout"](dim=dims, data_offset=0)
    message = T["std_msgs/msg/Float32MultiArray"](layout=layout, data=frame.reshape(-1).astype(np.float32))
    return STORE.serialize_cdr(message, "std_msgs/msg/Float32MultiArray")


class Publisher:
    """A publisher as rmw_zenoh declares one: its liveliness token, and its GID (the token's
    XXH3-128, low half first) in each message's attachment."""

    def __init__(self, session, n, msgtype):
        package, _, name = msgtype.split("/")
        qos = "::,10:,:,:,,"
        self.token_key = f"@ros2_lv/0/{session.zid()}/0/{n}/MP/%/%/driver{n}/%frames/{package}::msg::dds_::{name}_/{STORE.hash_rihs01(msgtype)}/{qos}"
        self.token = session.liveliness().declare_token(self.token_key)
        digest = xxhash.xxh3_128_intdigest(self.token_key.encode())
        self.gid = (digest & (2**64 - 1)).to_bytes(8, "little") + (digest >> 64).to_bytes(8, "little")
        self.session, self.key, self.sequence = session, key("frames", msgtype), 0

    def put(self, payload):
        self.sequence += 1
        attachment = z_serialize((Int64(self.sequence), Int64(time.time_ns()), self.gid))
        self.session.put(self.key, bytes(payload), attachment=attachment, congestion_control=zenoh.CongestionControl.BLOCK)


def hostile(session, first):
    """Messages the node must refuse, each said on /rosout, the node serving on."""
    image_key = key("frames", "sensor_msgs/msg/Image")
    good = image(first, 1)
    small = image(first[: first.shape[0] // 2], 1)
    odd = image(first, 1, encoding="yuv422")
    flags = STORE.serialize_cdr(T["std_msgs/msg/String"](data="x"), "std_msgs/msg/String")
    for payload, where in ((small, image_key), (odd, image_key), (good[: len(good) // 2], image_key), (good[:3], image_key), (flags, key("frames", "std_msgs/msg/String"))):
        session.put(where, bytes(payload), congestion_control=zenoh.CongestionControl.BLOCK)


def router(port):
    """A zenoh session that is the graph's router, on 127.0.0.1:PORT alone: no multicast, no gossip."""
    config = zenoh.Config()
    config.insert_json5("mode", json.dumps("router"))
    config.insert_json5("listen/endpoints", json.dumps([f"tcp/127.0.0.1:{port}"]))
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("scouting/gossip/enabled", "false")
    return zenoh.open(config)


def main(port, touches_file, kind, hostile_first=False):
    touches = np.load(touches_file)
    if touches.ndim == (5 if kind == "image" else 4) - 1:
        touches = touches[None]
    session = router(port)
    answers, statuses, logs = [], [], []

    def on_answer(sample):
        m = STORE.deserialize_cdr(bytes(sample.payload.to_bytes()), "vision_msgs/msg/Classification")
        answers.append(dict(stamp=m.header.stamp.sec * 10**9 + m.header.stamp.nanosec, classes=[r.class_id for r in m.results], probabilities=[r.score for r in m.results]))

    def on_status(sample):
        m = STORE.deserialize_cdr(bytes(sample.payload.to_bytes()), "diagnostic_msgs/msg/DiagnosticStatus")
        statuses.append({v.key: v.value for v in m.values})

    def on_log(sample):
        logs.append(STORE.deserialize_cdr(bytes(sample.payload.to_bytes()), "rcl_interfaces/msg/Log").msg)

    subscribers = [
        session.declare_subscriber(key("classification", "vision_msgs/msg/Classification"), on_answer),
        session.declare_subscriber(key("touch_status", "diagnostic_msgs/msg/DiagnosticStatus"), on_status),
        session.declare_subscriber(key("rosout", "rcl_interfaces/msg/Log"), on_log),
    ]
    print("ready", flush=True)
    deadline = time.time() + 60
    while time.time() < deadline:
        tokens = [str(r.ok.key_expr) for r in session.liveliness().get("@ros2_lv/0/**") if r.ok]
        if any("/MS/" in t and "/%frames/" in t for t in tokens) and any("/MP/" in t and "/%classification/" in t for t in tokens):
            break
        time.sleep(0.05)
    print(json.dumps(dict(tokens=sorted(tokens))), flush=True)
    time.sleep(0.3)
    msgtype = "sensor_msgs/msg/Image" if kind == "image" else "std_msgs/msg/Float32MultiArray"
    driver, second = Publisher(session, 1, msgtype), Publisher(session, 2, msgtype)
    ns = 1_700_000_000_000_000_000

    def message(frame, ns):
        return image(np.ascontiguousarray(frame), ns) if kind == "image" else array(np.ascontiguousarray(frame))

    if hostile_first:
        hostile(session, np.ascontiguousarray(np.moveaxis(touches[0], -1, 0)[0]))
        # A publisher that leaves half way through a touch: the node drops the touch.
        leaving = Publisher(session, 3, msgtype)
        for frame in np.moveaxis(touches[0], -1, 0)[: touches.shape[-1] // 2]:
            ns += 40_000_000
            leaving.put(message(frame, ns))
        time.sleep(0.2)
        leaving.token.undeclare()
        time.sleep(0.3)
    for touch in touches:
        for f, frame in enumerate(np.moveaxis(touch, -1, 0)):
            ns += 40_000_000
            driver.put(message(frame, ns))
            if hostile_first and f == 3:
                second.put(message(frame, ns))  # a second publisher on the topic
                driver.put(message(frame, ns - 80_000_000))  # stamped before the frame before it
            time.sleep(0.002)
    while time.time() < deadline and len(answers) < len(touches):
        time.sleep(0.05)
    time.sleep(0.2)
    for a in answers:
        print(json.dumps(a))
    for s in statuses:
        print(json.dumps(dict(status=s)))
    for line in logs:
        print(json.dumps(dict(log=line)))
    for s in subscribers:
        s.undeclare()
    session.close()


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2], sys.argv[3], len(sys.argv) > 4)
