#!/usr/bin/python3
"""Writers of ROS recordings for vkmesh's tests and fixtures (run with Debian's /usr/bin/python3).

API
---
    write_recording(kind, path, messages, **options)

kind:
    "ros1-none", "ros1-bz2", "ros1-lz4"  ROS 1 bag 2.0 through Debian's python3-rosbag (genpy serialises the
                                         messages; option chunk_threshold, default 1024 bytes: several chunks)
    "mcap-none", "mcap-zstd", "mcap-lz4"  MCAP written here by the spec (https://mcap.dev/spec), messages CDR
                                         (ROS 2); options chunk_messages (default 4 messages a chunk; 0 writes
                                         unchunked message records), crc (default True: chunk CRC-32s filled in)
    "db3"                                rosbag2 SQLite3 storage, messages CDR. `path` ending in .db3: that one file;
                                         otherwise a rosbag2 folder (metadata.yaml + <name>_<i>.db3); option
                                         split (messages a file, default 0 = one file)
messages: an iterable of (topic, type, time_ns, fields): type in ROS 1 spelling (the ROS 2 name
    "pkg/msg/Type" is derived), time_ns the record / log time; fields a dict per type:
    sensor_msgs/Image       header, height, width, encoding, is_bigendian, step, data (bytes)
    sensor_msgs/CameraInfo  header, height, width, distortion_model, D, K (9), R (9), P (12),
                            binning_x, binning_y (default 0), roi (dict x_offset y_offset height width do_rectify)
    tf2_msgs/TFMessage      transforms: [{header, child_frame_id, translation (x, y, z), rotation (x, y, z, w)}]
    geometry_msgs/Transform translation, rotation
    std_msgs/Float32, std_msgs/UInt32, std_msgs/String   data
    diagnostic_msgs/KeyValue key, value
    header: {"stamp_ns": int, "frame_id": str} (ROS 1's seq is written as 0).

The serialisers (cdr(type, fields), ros1(type, fields)) are usable on their own.

Command line:  recording_writers.py fixture KIND PATH [OPTION=INTEGER ...]  writes the test fixture of tests/cpu/test_recordings.cpp
(fixture_messages() below; that test checks the same values).
"""
import io
import os
import sqlite3
import struct
import sys
import zlib

# ----------------------------------------------------------------------------------------------- serialisers


class _Writer:
    """Little-endian; CDR when `cdr` (4-byte encapsulation header CDR_LE, primitives aligned to their size
    counted from the end of the header, strings with their NUL counted)."""

    def __init__(self, cdr):
        self.cdr = cdr
        self.buf = bytearray(b"\x00\x01\x00\x00" if cdr else b"")
        self.origin = 4 if cdr else 0

    def align(self, n):
        if self.cdr:
            while (len(self.buf) - self.origin) % n:
                self.buf.append(0)

    def prim(self, fmt, v):
        size = struct.calcsize("<" + fmt)
        self.align(size)
        self.buf += struct.pack("<" + fmt, v)

    def string(self, s):
        b = s.encode() if isinstance(s, str) else bytes(s)
        if self.cdr:
            b += b"\x00"
        self.prim("I", len(b))
        self.buf += b

    def header(self, h):
        sec, nsec = divmod(int(h.get("stamp_ns", 0)), 1000000000)
        if self.cdr:
            self.prim("i", sec)
            self.prim("I", nsec)
        else:
            self.prim("I", 0)  # seq
            self.prim("I", sec)
            self.prim("I", nsec)
        self.string(h.get("frame_id", ""))

    def transform(self, t):
        for v in t["translation"]:
            self.prim("d", v)
        for v in t["rotation"]:
            self.prim("d", v)


def _serialise(type_, f, cdr):
    w = _Writer(cdr)
    if type_ == "sensor_msgs/Image":
        w.header(f["header"])
        w.prim("I", f["height"])
        w.prim("I", f["width"])
        w.string(f["encoding"])
        w.prim("B", f.get("is_bigendian", 0))
        w.prim("I", f["step"])
        w.prim("I", len(f["data"]))
        w.buf += bytes(f["data"])
    elif type_ == "sensor_msgs/CameraInfo":
        w.header(f["header"])
        w.prim("I", f["height"])
        w.prim("I", f["width"])
        w.string(f["distortion_model"])
        w.prim("I", len(f["D"]))
        for name in ("D", "K", "R", "P"):
            for v in f[name]:
                w.prim("d", v)
        w.prim("I", f.get("binning_x", 0))
        w.prim("I", f.get("binning_y", 0))
        roi = f.get("roi", {})
        for k in ("x_offset", "y_offset", "height", "width"):
            w.prim("I", roi.get(k, 0))
        w.prim("B", roi.get("do_rectify", 0))
    elif type_ == "tf2_msgs/TFMessage":
        w.prim("I", len(f["transforms"]))
        for t in f["transforms"]:
            w.header(t["header"])
            w.string(t["child_frame_id"])
            w.transform(t)
    elif type_ == "geometry_msgs/Transform":
        w.transform(f)
    elif type_ == "std_msgs/Float32":
        w.prim("f", f["data"])
    elif type_ == "std_msgs/UInt32":
        w.prim("I", f["data"])
    elif type_ == "std_msgs/String":
        w.string(f["data"])
    elif type_ == "diagnostic_msgs/KeyValue":
        w.string(f["key"])
        w.string(f["value"])
    else:
        raise ValueError("no serialiser for " + type_)
    return bytes(w.buf)


def cdr(type_, fields):
    """The CDR (ROS 2) bytes of a message, with the encapsulation header."""
    return _serialise(type_, fields, True)


def ros1(type_, fields):
    """The ROS 1 bytes of a message."""
    return _serialise(type_, fields, False)


def ros2_type(type_):
    pkg, name = type_.split("/")
    return pkg + "/msg/" + name


# ------------------------------------------------------------------------------------------------ ROS 1 bag


def _genpy_message(type_, f):
    """The genpy message object of Debian's python3-*-msgs, or None for a type without one installed."""
    import genpy

    def header(h, msg):
        msg.stamp = genpy.Time(*divmod(int(h.get("stamp_ns", 0)), 1000000000))
        msg.frame_id = h.get("frame_id", "")

    if type_ == "sensor_msgs/Image":
        from sensor_msgs.msg import Image
        m = Image()
        header(f["header"], m.header)
        m.height, m.width, m.encoding = f["height"], f["width"], f["encoding"]
        m.is_bigendian, m.step, m.data = f.get("is_bigendian", 0), f["step"], bytes(f["data"])
        return m
    if type_ == "sensor_msgs/CameraInfo":
        from sensor_msgs.msg import CameraInfo
        m = CameraInfo()
        header(f["header"], m.header)
        m.height, m.width, m.distortion_model = f["height"], f["width"], f["distortion_model"]
        m.D, m.K, m.R, m.P = list(f["D"]), list(f["K"]), list(f["R"]), list(f["P"])
        m.binning_x, m.binning_y = f.get("binning_x", 0), f.get("binning_y", 0)
        for k, v in f.get("roi", {}).items():
            setattr(m.roi, k, v)
        return m
    if type_ == "tf2_msgs/TFMessage":
        from geometry_msgs.msg import TransformStamped
        from tf2_msgs.msg import TFMessage
        m = TFMessage()
        for t in f["transforms"]:
            ts = TransformStamped()
            header(t["header"], ts.header)
            ts.child_frame_id = t["child_frame_id"]
            _set_transform(ts.transform, t)
            m.transforms.append(ts)
        return m
    if type_ == "geometry_msgs/Transform":
        from geometry_msgs.msg import Transform
        m = Transform()
        _set_transform(m, f)
        return m
    if type_ in ("std_msgs/Float32", "std_msgs/UInt32", "std_msgs/String"):
        import std_msgs.msg
        m = getattr(std_msgs.msg, type_.split("/")[1])()
        m.data = f["data"]
        return m
    return None


def _set_transform(m, t):
    m.translation.x, m.translation.y, m.translation.z = t["translation"]
    m.rotation.x, m.rotation.y, m.rotation.z, m.rotation.w = t["rotation"]


# Types Debian ships no python3-*-msgs for: written raw (their ROS 1 bytes, md5sum and definition).
_RAW_TYPES = {
    "diagnostic_msgs/KeyValue": ("cf57fdc6617a881a88c16e768132149c", "string key\nstring value\n"),
}


def _write_ros1(path, messages, compression, chunk_threshold=1024):
    import genpy
    import rosbag
    with rosbag.Bag(path, "w", compression=compression, chunk_threshold=chunk_threshold) as bag:
        for topic, type_, t_ns, f in messages:
            t = genpy.Time(*divmod(int(t_ns), 1000000000))
            m = _genpy_message(type_, f)
            if m is not None:
                bag.write(topic, m, t)
            else:
                md5, text = _RAW_TYPES[type_]
                pytype = type("Raw", (), {"_type": type_, "_md5sum": md5, "_full_text": text})
                bag.write(topic, (type_, ros1(type_, f), md5, pytype), t, raw=True)


# ----------------------------------------------------------------------------------------------------- MCAP

MCAP_MAGIC = b"\x89MCAP0\r\n"


def _s(s):
    b = s.encode() if isinstance(s, str) else bytes(s)
    return struct.pack("<I", len(b)) + b


def _record(op, content):
    return struct.pack("<BQ", op, len(content)) + content


def mcap_message_record(channel, seq, t_ns, data):
    return _record(0x05, struct.pack("<HIQQ", channel, seq, t_ns, t_ns) + data)


def _write_mcap(path, messages, compression, chunk_messages=4, crc=True):
    out = bytearray(MCAP_MAGIC)
    out += _record(0x01, _s("ros2") + _s("vkmesh recording_writers.py"))
    schemas, channels = {}, {}
    pending = []  # the current chunk's records

    def flush(start, end):
        if not pending:
            return
        records = b"".join(pending)
        if compression == "zstd":
            import zstandard
            data = zstandard.ZstdCompressor().compress(records)
        elif compression == "lz4":
            import lz4.frame
            data = lz4.frame.compress(records)
        else:
            data = records
        c = zlib.crc32(records) if crc else 0
        out.extend(_record(0x06, struct.pack("<QQQI", start, end, len(records), c) + _s(compression) +
                           struct.pack("<Q", len(data)) + data))
        pending.clear()

    times = []
    for seq, (topic, type_, t_ns, f) in enumerate(messages):
        if type_ not in schemas:
            schemas[type_] = len(schemas) + 1
            out += _record(0x03, struct.pack("<H", schemas[type_]) + _s(ros2_type(type_)) + _s("ros2msg") +
                           _s(b""))
        if topic not in channels:
            channels[topic] = len(channels) + 1
            out += _record(0x04, struct.pack("<HH", channels[topic], schemas[type_]) + _s(topic) + _s("cdr") +
                           struct.pack("<I", 0))
        rec = mcap_message_record(channels[topic], seq, t_ns, cdr(type_, f))
        if chunk_messages <= 0:
            out += rec
            continue
        pending.append(rec)
        times.append(t_ns)
        if len(pending) >= chunk_messages:
            flush(min(times), max(times))
            times = []
    if times:
        flush(min(times), max(times))
    out += _record(0x0F, struct.pack("<I", 0))  # DataEnd (no data section CRC)
    out += _record(0x02, struct.pack("<QQI", 0, 0, 0))  # Footer: no summary section
    out += MCAP_MAGIC
    with open(path, "wb") as fh:
        fh.write(out)


# ------------------------------------------------------------------------------------------- rosbag2 SQLite


def _write_db3_file(path, messages):
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
               "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)")
    db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
               "timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
    topics = {}
    for topic, type_, t_ns, f in messages:
        if topic not in topics:
            topics[topic] = len(topics) + 1
            db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", (topics[topic], topic, ros2_type(type_)))
        db.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)",
                   (topics[topic], int(t_ns), cdr(type_, f)))
    db.commit()
    db.close()


def _write_db3(path, messages, split=0):
    messages = list(messages)
    if path.endswith(".db3"):
        _write_db3_file(path, messages)
        return
    os.makedirs(path, exist_ok=True)
    name = os.path.basename(os.path.normpath(path))
    parts = [messages[i:i + split] for i in range(0, len(messages), split)] if split > 0 else [messages]
    files = []
    for i, part in enumerate(parts):
        files.append("%s_%d.db3" % (name, i))
        _write_db3_file(os.path.join(path, files[-1]), part)
    with open(os.path.join(path, "metadata.yaml"), "w") as fh:
        fh.write("rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
                 "  relative_file_paths:\n" + "".join("    - %s\n" % f for f in files) +
                 "  message_count: %d\n" % len(messages))


def write_recording(kind, path, messages, **options):
    """Writes `messages` (topic, type, time_ns, fields) as a recording of `kind` at `path` (module doc)."""
    path = str(path)
    if kind.startswith("ros1-"):
        _write_ros1(path, messages, kind[5:], **options)
    elif kind.startswith("mcap-"):
        c = kind[5:]
        _write_mcap(path, messages, "" if c == "none" else c, **options)
    elif kind == "db3":
        _write_db3(path, messages, **options)
    else:
        raise ValueError("unknown recording kind " + kind)


# ------------------------------------------------------------------------------------ the tests' fixture
# tests/cpu/test_recordings.cpp checks these values; keep the two in step.

FRAMES = 6
W, H = 8, 6


def frame_time_ns(i):
    return 1000000000 + i * 33333333


def fixture_messages():
    import math
    msgs = []
    for i in range(FRAMES):
        t = frame_time_ns(i)
        depth = b"".join(struct.pack("<H", 1000 + 100 * i + 10 * y + x) for y in range(H) for x in range(W))
        msgs.append(("/camera/depth/image_rect_raw", "sensor_msgs/Image", t, {
            "header": {"stamp_ns": t, "frame_id": "camera_depth_optical_frame"},
            "height": H, "width": W, "encoding": "16UC1", "is_bigendian": 0, "step": 2 * W, "data": depth}))
        rgb = bytes((i * 7 + k) & 255 for k in range(3 * W * H))
        msgs.append(("/camera/color/image_raw", "sensor_msgs/Image", t + 1000, {
            "header": {"stamp_ns": t + 1000, "frame_id": "camera_color_optical_frame"},
            "height": H, "width": W, "encoding": "rgb8", "is_bigendian": 0, "step": 3 * W, "data": rgb}))
        msgs.append(("/camera/depth/camera_info", "sensor_msgs/CameraInfo", t + 2000, {
            "header": {"stamp_ns": t, "frame_id": "camera_depth_optical_frame"},
            "height": H, "width": W, "distortion_model": "plumb_bob", "D": [0.1, -0.2, 0.001, 0.002, 0.0],
            "K": [5.25 + i, 0, 3.5, 0, 5.5, 2.5, 0, 0, 1], "R": [1, 0, 0, 0, 1, 0, 0, 0, 1],
            "P": [5.25 + i, 0, 3.5, 0, 0, 5.5, 2.5, 0, 0, 0, 1, 0]}))
        a = 0.1 * i
        msgs.append(("/tf", "tf2_msgs/TFMessage", t + 3000, {"transforms": [
            {"header": {"stamp_ns": t, "frame_id": "world"}, "child_frame_id": "camera_link",
             "translation": (0.1 * i, 0.2, 0.3), "rotation": (0.0, 0.0, math.sin(a / 2), math.cos(a / 2))},
            {"header": {"stamp_ns": t, "frame_id": "camera_link"}, "child_frame_id": "camera_depth_optical_frame",
             "translation": (0.0, 0.015, 0.0), "rotation": (-0.5, 0.5, -0.5, 0.5)}]}))
    t0 = frame_time_ns(0)
    msgs.append(("/device/depth_scale", "std_msgs/Float32", t0 + 5, {"data": 0.001}))
    msgs.append(("/device/frame_count", "std_msgs/UInt32", t0 + 6, {"data": FRAMES}))
    msgs.append(("/device/name", "std_msgs/String", t0 + 7, {"data": "Intel RealSense D435"}))
    msgs.append(("/device/info", "diagnostic_msgs/KeyValue", t0 + 8, {"key": "Serial Number", "value": "0123"}))
    msgs.append(("/extrinsics", "geometry_msgs/Transform", t0 + 9,
                 {"translation": (0.015, 0.0, 0.0), "rotation": (0.0, 0.0, 0.0, 1.0)}))
    return msgs


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "fixture":
        opts = dict((k, int(v)) for k, v in (a.split("=", 1) for a in sys.argv[4:]))
        write_recording(sys.argv[2], sys.argv[3], fixture_messages(), **opts)
    else:
        sys.exit("usage: recording_writers.py fixture KIND PATH [OPTION=INTEGER ...]")
