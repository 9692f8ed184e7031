"""What `pvt3 import` of a long ROS 2 bag costs beside a video of the same frames: a set of
2 classes x 5 touches of 320 x 240 RGB frames, one touch 10,000 frames long, the others 50,
written as bags of both storages (rosbags' rosbag2 writer, MCAP and SQLite, topic /camera,
sensor_msgs/msg/Image rgb8) and as lossless videos (FFmpeg's FFV1); each set imported in
alternating rounds, the wall time and the peak resident memory of each import measured
(/usr/bin/time). The three sets must import equal, byte for byte. Prints a markdown table for
docs/benchmarks.md.

    target/onnx-venv/bin/python bench/bag_import.py [PVT3] [ROUNDS]

PVT3 defaults to target/release/pvt3; the venv is the one the tests make (rosbags, numpy).
"""

import subprocess
import sys
from pathlib import Path
from statistics import median

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

H, W = 240, 320
LONG, SHORT = 10_000, 50
OUT = Path("target/bag-bench")
STORE = get_typestore(Stores.ROS2_JAZZY)
IMAGE = "sensor_msgs/msg/Image"


def frame(klass, touch, f, frames):
    """A level of its class, and while the gel moves (the middle half) a square sliding across."""
    image = np.full((H, W, 3), (40 * klass + 10 * touch) % 200, np.uint8)
    image[..., 1] += np.arange(W, dtype=np.uint8)[None, :] // 4
    if frames // 4 <= f < 3 * frames // 4:
        x = (f - frames // 4) * (W - 40) // (frames // 2)
        image[100:140, x : x + 40] = (250, 30, 90)
    return image


def touches():
    for klass in range(2):
        for touch in range(5):
            yield klass, touch, LONG if (klass, touch) == (0, 0) else SHORT


def write_bag(path, klass, touch, frames, storage):
    types = STORE.types
    with Writer(path, version=9 if storage == StoragePlugin.MCAP else 8, storage_plugin=storage) as writer:
        connection = writer.add_connection("/camera", IMAGE, typestore=STORE)
        for f in range(frames):
            ns = 1_700_000_000_000_000_000 + f * 16_666_667
            stamp = types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
            header = types["std_msgs/msg/Header"](stamp=stamp, frame_id="camera")
            data = frame(klass, touch, f, frames).ravel()
            message = types[IMAGE](header=header, height=H, width=W, encoding="rgb8", is_bigendian=0, step=3 * W, data=data)
            writer.write(connection, ns, STORE.serialize_cdr(message, IMAGE))


def write_video(path, klass, touch, frames):
    ffmpeg = subprocess.Popen(
        ["ffmpeg", "-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{W}x{H}", "-r", "60", "-i", "pipe:0"]
        + ["-c:v", "ffv1", "-pix_fmt", "bgr0", str(path)],
        stdin=subprocess.PIPE,
    )
    for f in range(frames):
        ffmpeg.stdin.write(frame(klass, touch, f, frames).tobytes())
    ffmpeg.stdin.close()
    assert ffmpeg.wait() == 0, path


KINDS = {"bags": "ROS 2 bags (MCAP)", "sqlite": "ROS 2 bags (SQLite)", "videos": "videos (FFV1)"}


def write_set(kind):
    """The set of `kind`, written once (a file `ready-KIND` says it is whole)."""
    ready = OUT / f"ready-{kind}"
    if ready.exists():
        return
    for klass, touch, frames in touches():
        folder = OUT / kind / f"class_{klass}"
        folder.mkdir(parents=True, exist_ok=True)
        if kind == "videos":
            write_video(folder / f"touch_{touch}.mkv", klass, touch, frames)
        else:
            storage = StoragePlugin.MCAP if kind == "bags" else StoragePlugin.SQLITE3
            write_bag(folder / f"touch_{touch}", klass, touch, frames, storage)
    ready.write_text("")


def timed(pvt3, kind):
    args = [pvt3, "import", str(OUT / kind), "--out", str(OUT / f"{kind}.npz")]
    if kind != "videos":
        args += ["--topic", "/camera"]
    run = subprocess.run(["/usr/bin/time", "-f", "%e %M"] + args, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    seconds, kib = run.stderr.strip().splitlines()[-1].split()
    return float(seconds), int(kib) / 1024


def main(pvt3="target/release/pvt3", rounds="3"):
    for kind in KINDS:
        write_set(kind)
    size = {kind: sum(p.stat().st_size for p in (OUT / kind).rglob("*") if p.is_file()) for kind in KINDS}
    results = {kind: [] for kind in KINDS}
    for _ in range(int(rounds)):
        for kind in results:
            results[kind].append(timed(pvt3, kind))
    sets = {kind: np.load(OUT / f"{kind}.npz") for kind in KINDS}
    for kind in ("bags", "sqlite"):
        assert np.array_equal(sets[kind]["x"], sets["videos"]["x"]), f"the {kind}' frames differ from the videos'"
    print(f"| touches as | on disk | import, median of {rounds} (range) | peak memory, median |")
    print("|---|---:|---|---:|")
    for kind, runs in results.items():
        times, memory = [r[0] for r in runs], [r[1] for r in runs]
        print(f"| {KINDS[kind]} | {size[kind] / 2**20:,.0f} MiB | {median(times):.1f} s ({min(times):.1f}-{max(times):.1f}) | {median(memory):,.0f} MiB |")


if __name__ == "__main__":
    main(*sys.argv[1:])
