"""Camera and taxel-array touches written as ROS 2 bags by libraries no one here wrote, beside the
same frames as image or CSV files, for tests/bags.rs: `pvt3 import` must read both alike, byte
for byte.

    python tests/bag_writer.py OUT

OUT/frames/CASE/CLASS/TOUCH/NNN.png (or .jpg): each touch's frames as a frame folder.
OUT/bags/WRITER/CASE/CLASS/TOUCH: the same frames as a bag, on topic /camera, stamped
33 ms apart from the touch's start (the bag's receive times 1 ms later). The writers:
rosbags' rosbag2 writer with MCAP (a bag directory, metadata.yaml and its .mcap) and with
SQLite (its .db3), and mcap-ros2-support's writer (a lone .mcap file, zstd or lz4 chunks).
The cases: sensor_msgs/msg/Image in every encoding pvt3 reads (bgr8 with rows padded past
their pixels, mono16 in both byte orders) and CompressedImage in PNG and JPEG (encoded by
FFmpeg from the PNG frames).
OUT/csv/ARRAY/CLASS/touchN.csv and OUT/bags/WRITER/ARRAY/CLASS/touchN: a taxel array's touch
(3 x 4 taxels, 6 to 10 frames) as a CSV file (columns data[0] to data[11]) and as a bag of
std_msgs/msg/*MultiArray on topic /taxels, unstamped (a multi-array has no header), received
33 ms apart: every element type pvt3 reads, the 3 x 4 layout given as two dimensions (the
int16 case's data after an offset of two values) or, for float64, none. OUT/long/run holds the rgb8 case's touches one after another in one
bag (rosbags, MCAP), touch i received from i seconds after its first message on, and
OUT/long/labels.csv cuts them out again (path,class,start,end).
"""

import struct
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path

import numpy as np
from mcap.writer import CompressionType
from mcap_ros2.writer import Writer as McapRos2Writer
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

H, W, FRAMES = 8, 10, 6
CLASSES, TOUCHES = ("felt", "wood"), 5
TOPIC, ARRAY_TOPIC = "/camera", "/taxels"
ROWS, COLS = 3, 4
STORE = get_typestore(Stores.ROS2_JAZZY)

TIME_DEF = "int32 sec\nuint32 nanosec\n"
HEADER_DEF = "builtin_interfaces/Time stamp\nstring frame_id\n"
SEPARATOR = "=" * 80 + "\n"
DEPENDENCIES = f"{SEPARATOR}MSG: std_msgs/Header\n{HEADER_DEF}{SEPARATOR}MSG: builtin_interfaces/Time\n{TIME_DEF}"
DEFINITIONS = {
    "sensor_msgs/msg/Image": "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
    "uint8 is_bigendian\nuint32 step\nuint8[] data\n" + DEPENDENCIES,
    "sensor_msgs/msg/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data\n" + DEPENDENCIES,
}
LAYOUT_DEF = (
    f"{SEPARATOR}MSG: std_msgs/MultiArrayLayout\nstd_msgs/MultiArrayDimension[] dim\nuint32 data_offset\n"
    f"{SEPARATOR}MSG: std_msgs/MultiArrayDimension\nstring label\nuint32 size\nuint32 stride\n"
)
# Each array case: (name, message type, element type, numpy type, layout's dimensions, data offset).
ARRAYS = [
    ("float32", "Float32MultiArray", "float32", np.float32, True, 0),
    ("float64", "Float64MultiArray", "float64", np.float64, False, 0),
    ("int16", "Int16MultiArray", "int16", np.int16, True, 2),
    ("int32", "Int32MultiArray", "int32", np.int32, True, 0),
    ("uint16", "UInt16MultiArray", "uint16", np.uint16, True, 0),
    ("uint8", "UInt8MultiArray", "uint8", np.uint8, True, 0),
]
for _, name, element, *_ in ARRAYS:
    DEFINITIONS[f"std_msgs/msg/{name}"] = f"std_msgs/MultiArrayLayout layout\n{element}[] data\n" + LAYOUT_DEF


def rgb(klass, touch, frame):
    """A touch's frame, 8-bit RGB: its class's colours, a square sliding over them."""
    y, x = np.mgrid[0:H, 0:W]
    image = np.stack([(40 * klass + 7 * c + 3 * y + x + 5 * touch) % 256 for c in range(3)], axis=-1)
    square = (abs(y - 3) <= 1) & (abs(x - frame - 1) <= 1)
    image[square] = [250, 20 + 30 * touch, 90]
    return image.astype(np.uint8)


def png(image):
    """The PNG of an 8-bit RGB or grey image, or a 16-bit grey one."""
    grey = image.ndim == 2
    depth = 16 if image.dtype == np.uint16 else 8
    rows = image.astype(">u2") if depth == 16 else image
    raw = b"".join(b"\x00" + row.tobytes() for row in rows)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", image.shape[1], image.shape[0], depth, 0 if grey else 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def jpeg(image):
    """The JPEG FFmpeg makes of an RGB image."""
    with tempfile.TemporaryDirectory() as tmp:
        source, target = Path(tmp, "f.png"), Path(tmp, "f.jpg")
        source.write_bytes(png(image))
        subprocess.run(["ffmpeg", "-v", "error", "-nostdin", "-i", source, "-q:v", "3", target], check=True)
        return target.read_bytes()


def grey(image):
    return (image.astype(np.uint32).sum(axis=-1) // 3).astype(np.uint8)


def image_message(encoding, pixels, step_pad=0, bigendian=False):
    """(type, fields) of an Image of `pixels` (H × W × channels, or H × W) in `encoding`."""
    rows = pixels.reshape(H, -1)
    if pixels.dtype == np.uint16:
        rows = pixels.astype(">u2" if bigendian else "<u2").view(np.uint8).reshape(H, -1)
    padded = np.concatenate([rows, np.full((H, step_pad), 77, np.uint8)], axis=1)
    fields = dict(height=H, width=W, encoding=encoding, is_bigendian=int(bigendian), step=padded.shape[1], data=padded.ravel())
    return "sensor_msgs/msg/Image", fields


def cases():
    """Each case: (name, frame file extension, frame(klass, touch, f) -> (file bytes, (type, fields)))."""

    def raw(encoding, order, pad=0):
        def frame(k, t, f):
            image = rgb(k, t, f)
            channels = image[..., order]
            if encoding.endswith("a8"):
                channels = np.concatenate([channels, np.full((H, W, 1), 128, np.uint8)], axis=-1)
            return png(image), image_message(encoding, channels, pad)

        return frame

    def mono8(k, t, f):
        image = grey(rgb(k, t, f))
        return png(image), image_message("mono8", image)

    def mono16(bigendian):
        def frame(k, t, f):
            image = grey(rgb(k, t, f)).astype(np.uint16) * 257 + np.uint16(3 * f)
            return png(image), image_message("mono16", image, bigendian=bigendian)

        return frame

    def compressed(encode, fmt):
        def frame(k, t, f):
            data = encode(rgb(k, t, f))
            return data, ("sensor_msgs/msg/CompressedImage", dict(format=fmt, data=np.frombuffer(data, np.uint8)))

        return frame

    return [
        ("rgb8", "png", raw("rgb8", [0, 1, 2])),
        ("bgr8-padded", "png", raw("bgr8", [2, 1, 0], pad=5)),
        ("rgba8", "png", raw("rgba8", [0, 1, 2])),
        ("bgra8", "png", raw("bgra8", [2, 1, 0])),
        ("mono8", "png", mono8),
        ("mono16-little", "png", mono16(False)),
        ("mono16-big", "png", mono16(True)),
        ("compressed-png", "png", compressed(png, "png")),
        ("compressed-jpeg", "jpg", compressed(jpeg, "rgb8; jpeg compressed bgr8")),
    ]


def taxels(klass, touch, frame, dtype):
    """A taxel array's frame, ROWS x COLS row-major: values of every sign and size its type holds."""
    k = np.arange(ROWS * COLS)
    base = (37 * klass + 11 * touch + 5 * frame + 3 * k) % 50 - 20
    if dtype in (np.float32, np.float64):
        return (base * 0.25 + 0.125 + (1e-7 * k if dtype == np.float64 else 0)).astype(dtype)
    if dtype == np.uint8:
        return (base + 20 + 4 * k).astype(np.uint8)
    if dtype == np.uint16:
        return (base + 20 + 1000 * k).astype(np.uint16)
    scale = 1000 if dtype == np.int16 else 100_000
    return (base * scale).astype(dtype)


def array_message(name, values, dims, offset):
    """(type, fields) of a multi-array of `values`, after `offset` values of padding."""
    layout = dict(dim=[dict(label="rows", size=ROWS, stride=ROWS * COLS), dict(label="cols", size=COLS, stride=COLS)] if dims else [], data_offset=offset)
    data = np.concatenate([np.full(offset, 99, values.dtype), values])
    return f"std_msgs/msg/{name}", dict(layout=layout, data=data)


def stamped(touch_start, f):
    ns = touch_start + f * 33_000_000
    return ns, dict(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def rosbags_message(msgtype, fields, stamp):
    """The CDR rosbags makes of a message: an image's with its header, a multi-array's layout."""
    types = STORE.types
    if stamp is None:
        layout = fields["layout"]
        dims = [types["std_msgs/msg/MultiArrayDimension"](**d) for d in layout["dim"]]
        layout = types["std_msgs/msg/MultiArrayLayout"](dim=dims, data_offset=layout["data_offset"])
        return STORE.serialize_cdr(types[msgtype](layout=layout, data=fields["data"]), msgtype)
    header = types["std_msgs/msg/Header"](stamp=types["builtin_interfaces/msg/Time"](**stamp), frame_id="camera")
    return STORE.serialize_cdr(types[msgtype](header=header, **fields), msgtype)


def topic_of(msgtype):
    return TOPIC if msgtype.startswith("sensor_msgs") else ARRAY_TOPIC


def write_rosbags(path, messages, storage):
    version = 9 if storage == StoragePlugin.MCAP else 8
    with Writer(path, version=version, storage_plugin=storage) as writer:
        connection = writer.add_connection(topic_of(messages[0][1]), messages[0][1], typestore=STORE)
        for ns, msgtype, fields, stamp in messages:
            writer.write(connection, ns + 1_000_000, rosbags_message(msgtype, fields, stamp))


def mcap_ros2_message(fields, stamp):
    """A message as mcap-ros2-support's writer takes it: a uint8[] as bytes, other arrays as lists."""
    data = fields["data"]
    data = bytes(data) if data.dtype == np.uint8 else data.tolist()
    if stamp is None:
        return dict(fields, data=data)
    return dict(fields, header=dict(stamp=stamp, frame_id="camera"), data=data)


def write_mcap_ros2(path, messages, compression):
    with open(path, "wb") as f:
        writer = McapRos2Writer(f, compression=compression)
        schema = writer.register_msgdef(messages[0][1], DEFINITIONS[messages[0][1]])
        for ns, msgtype, fields, stamp in messages:
            message = mcap_ros2_message(fields, stamp)
            writer.write_message(topic_of(msgtype), schema, message, log_time=ns + 1_000_000, publish_time=ns)
        writer.finish()


WRITERS = {
    "rosbags-mcap": lambda p, m: write_rosbags(p, m, StoragePlugin.MCAP),
    "rosbags-sqlite3": lambda p, m: write_rosbags(p, m, StoragePlugin.SQLITE3),
    "mcap-ros2-zstd": lambda p, m: write_mcap_ros2(p.with_suffix(".mcap"), m, CompressionType.ZSTD),
    "mcap-ros2-lz4": lambda p, m: write_mcap_ros2(p.with_suffix(".mcap"), m, CompressionType.LZ4),
}


def write_long(out, frame):
    """The case's touches in one bag, touch i from i s on, and the labels file that cuts them."""
    (out / "long").mkdir(parents=True)
    messages, rows = [], ["path,class,start,end"]
    for k, klass in enumerate(CLASSES):
        for t in range(TOUCHES):
            i = k * TOUCHES + t
            for f in range(FRAMES):
                ns, stamp = stamped(1_700_000_000_000_000_000 + i * 10**9, f)
                messages.append((ns, *frame(k, t, f)[1], stamp))
            rows.append(f"run,{klass},{i},{i + 0.5}")
    write_rosbags(out / "long" / "run", messages, StoragePlugin.MCAP)
    (out / "long" / "labels.csv").write_text("\n".join(rows) + "\n")


def write_arrays(out):
    """Every array case's touches as CSV files and as bags of every writer."""
    for case, name, _, dtype, dims, offset in ARRAYS:
        for k, klass in enumerate(CLASSES):
            for t in range(TOUCHES):
                folder = out / "csv" / case / klass
                folder.mkdir(parents=True, exist_ok=True)
                rows, messages = [",".join(f"data[{c}]" for c in range(ROWS * COLS))], []
                for f in range(FRAMES + t):
                    values = taxels(k, t, f, dtype)
                    rows.append(",".join(repr(v.item()) for v in values))
                    ns = 1_700_000_000_000_000_000 + t * 10**9 + f * 33_000_000
                    messages.append((ns, *array_message(name, values, dims, offset), None))
                (folder / f"touch{t}.csv").write_text("\n".join(rows) + "\n")
                for writer, write in WRITERS.items():
                    bag = out / "bags" / writer / case / klass / f"touch{t}"
                    bag.parent.mkdir(parents=True, exist_ok=True)
                    write(bag, messages)


def main(out):
    write_arrays(out)
    write_long(out, cases()[0][2])
    for case, extension, frame in cases():
        for k, klass in enumerate(CLASSES):
            for t in range(TOUCHES):
                folder = out / "frames" / case / klass / f"touch{t}"
                folder.mkdir(parents=True)
                messages = []
                for f in range(FRAMES):
                    data, (msgtype, fields) = frame(k, t, f)
                    (folder / f"{f:03}.{extension}").write_bytes(data)
                    ns, stamp = stamped(1_700_000_000_000_000_000 + t * 10**9, f)
                    messages.append((ns, msgtype, fields, stamp))
                for writer, write in WRITERS.items():
                    bag = out / "bags" / writer / case / klass / f"touch{t}"
                    bag.parent.mkdir(parents=True, exist_ok=True)
                    write(bag, messages)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
