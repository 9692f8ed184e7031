"""What pvt3-ros costs on a ROS 2 graph: a sensor driver publishing a touch's frames at a camera's
rate through a zenoh router on 127.0.0.1 (eclipse-zenoh, messages by rosbags: tests/ros_peer.py's
code), the node pinned to one core. For each touch, the time from the publish of its last frame
to its answer's arrival at the router (the router's own stamp, zenoh's HLC, taken in Rust as the
answer comes in), beside the runtime's own time on that frame (the node's `last_ms`: from the
frame's arrival to the answer); and to the answer's arrival in this process's Python callback,
which waits for the GIL. The answers come in the touches' order, one a touch. Every second, the
node's CPU share and resident memory (/proc). Prints a row of bench/ros_node.sh's table
(docs/benchmarks.md).

    target/onnx-venv/bin/python bench/ros_node.py PVT3_ROS MODEL KIND FPS SECONDS

KIND: `image` (frames of the file's camera, as it gives them) or `array` (the golden iCub
windows). E.g. `bench/ros_node.py target/release/pvt3-ros shipped/physiclear.onnx image 60 600`.
"""

import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import ros_peer  # noqa: E402  the test peer's messages, keys and publisher


def frames_of(model, kind):
    """The frames one touch publishes: the camera's (its recorded size, from the file's header) or the golden windows'."""
    if kind == "array":
        windows = np.load("tests/golden/icub20/input.npy")
        return [np.ascontiguousarray(f) for w in windows for f in np.moveaxis(w, -1, 0)], windows.shape[-1]
    import onnx

    meta = {p.key: p.value for p in onnx.load(model, load_external_data=False).metadata_props}
    h, w, c = json.loads(meta["pvt3.camera"])["recorded"]
    frames = json.loads(meta["pvt3.config"])["frames"]
    rng = np.random.default_rng(0)
    return [rng.integers(0, 256, (h, w, c), dtype=np.uint8) for _ in range(frames)], frames


def sample(pid, clock):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    cpu = (int(fields[11]) + int(fields[12])) / clock
    with open(f"/proc/{pid}/status") as f:
        rss = next(int(line.split()[1]) for line in f if line.startswith("VmRSS")) / 1024
    return cpu, rss


def percentile(values, q):
    return float(np.percentile(values, q)) if values else float("nan")


def main(binary, model, kind, fps, seconds):
    fps, seconds = float(fps), float(seconds)
    # The node has core 0 to itself: the driver, the router and the listener (this process) run on
    # the others, so that the node's figures are its own.
    others = os.sched_getaffinity(0) - {0}
    if others:
        os.sched_setaffinity(0, others)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    session = ros_peer.router(port)
    routed, arrived, last_ms = [], [], []
    store = ros_peer.STORE

    def on_answer(sample):
        arrived.append(time.time_ns())
        routed.append(sample.timestamp.get_time_as_ntp64().as_nanos())

    def on_status(sample):
        m = store.deserialize_cdr(bytes(sample.payload.to_bytes()), "diagnostic_msgs/msg/DiagnosticStatus")
        last_ms.append(float({v.key: v.value for v in m.values}["last_ms"]))

    subscribers = [
        session.declare_subscriber(ros_peer.key("classification", "vision_msgs/msg/Classification"), on_answer),
        session.declare_subscriber(ros_peer.key("touch_status", "diagnostic_msgs/msg/DiagnosticStatus"), on_status),
    ]
    args = ["taskset", "-c", "0", binary, "--ros-args", "-p", f"model:={model}", "-p", f"router:=tcp/127.0.0.1:{port}", "-p", "early_stop:=false"]
    node = subprocess.Popen(args, stderr=subprocess.DEVNULL)
    msgtype = "sensor_msgs/msg/Image" if kind == "image" else "std_msgs/msg/Float32MultiArray"
    driver = ros_peer.Publisher(session, 1, msgtype)
    frames, window = frames_of(model, kind)
    deadline = time.time() + 30
    while time.time() < deadline and not any("/MS/" in str(r.ok.key_expr) and "%frames" in str(r.ok.key_expr) for r in session.liveliness().get("@ros2_lv/0/**") if r.ok):
        time.sleep(0.05)
    time.sleep(0.5)
    published, usage, clock = [], [], os.sysconf("SC_CLK_TCK")
    stop = threading.Event()

    def sampler():
        while not stop.wait(1.0):
            usage.append((time.perf_counter(), *sample(node.pid, clock)))

    threading.Thread(target=sampler, daemon=True).start()
    start, n, ns = time.perf_counter(), 0, 1_700_000_000_000_000_000
    while time.perf_counter() - start < seconds:
        frame = frames[n % len(frames)]
        ns += int(1e9 / fps)
        driver.put(ros_peer.image(frame, ns) if kind == "image" else ros_peer.array(frame))
        if (n + 1) % window == 0:
            published.append(time.time_ns())
        n += 1
        time.sleep(max(0.0, start + n / fps - time.perf_counter()))
    time.sleep(1.0)
    stop.set()
    node.terminate()
    node.wait()
    for s in subscribers:
        s.undeclare()
    session.close()
    # Answers come in the touches' order, one a touch: the k-th answers the k-th touch.
    assert len(arrived) == len(published), f"{len(arrived)} answers for {len(published)} touches"
    latencies = [(r - p) / 1e6 for r, p in zip(routed, published)]
    at_listener = [(a - p) / 1e6 for a, p in zip(arrived, published)]
    overhead = [lat - last for lat, last in zip(latencies, last_ms)]
    cpu = [(b[1] - a[1]) / (b[0] - a[0]) for a, b in zip(usage, usage[1:])]
    rss = [u[2] for u in usage]
    # Growth after the first minute (a least-squares line through each second's sample), MiB a minute.
    later = [(t, r) for t, _, r in usage if t - usage[0][0] >= 60]
    growth = 60 * np.polyfit([t for t, _ in later], [r for _, r in later], 1)[0] if len(later) > 2 else float("nan")
    print(
        f"| `{model}` | {fps:g} | {seconds:g} s, {len(latencies)} touches | {percentile(latencies, 50):.2f} / {percentile(latencies, 99):.2f} ms "
        f"| {percentile(last_ms, 50):.2f} / {percentile(last_ms, 99):.2f} ms | {percentile(overhead, 99):.2f} ms "
        f"| {percentile(at_listener, 50):.2f} / {percentile(at_listener, 99):.2f} ms "
        f"| {100 * np.mean(cpu):.1f} % ({100 * max(cpu, default=0):.1f} %) | {rss[0]:.1f} / {rss[-1]:.1f} / {max(rss):.1f} MiB | {growth:+.3f} MiB |"
    )


if __name__ == "__main__":
    main(*sys.argv[1:])
