#!/usr/bin/python3
"""Writes the seed corpora of fuzz_ros1_bag, fuzz_mcap and fuzz_ros_messages into fuzz/corpus/ (committed; rerun
after changing this script). Tiny files, a few hundred bytes each: the ROS 1 bags are written here by the spec
rather than through python3-rosbag, which pads its bag header to 4 KB and stores full message definitions."""
import bz2
import os
import struct
import sys

import lz4.frame

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "support"))
import recording_writers as rw  # noqa: E402

CORPUS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")

IMAGE = {"header": {"stamp_ns": 1000000002, "frame_id": "d"}, "height": 1, "width": 2, "encoding": "16UC1",
         "step": 4, "data": b"\x01\x02\x03\x04"}
INFO = {"header": {"stamp_ns": 5, "frame_id": "d"}, "height": 1, "width": 2, "distortion_model": "plumb_bob",
        "D": [0.1], "K": [1, 0, 1, 0, 1, 0.5, 0, 0, 1], "R": [1, 0, 0, 0, 1, 0, 0, 0, 1], "P": [0] * 12}
TF = {"transforms": [{"header": {"stamp_ns": 7, "frame_id": "w"}, "child_frame_id": "c",
                      "translation": (1, 2, 3), "rotation": (0, 0, 0, 1)}]}
MESSAGES = [
    ("/d", "sensor_msgs/Image", 1000000002, IMAGE),
    ("/i", "sensor_msgs/CameraInfo", 1000000003, INFO),
    ("/tf", "tf2_msgs/TFMessage", 1000000001, TF),
]


def field(name, value):
    b = name.encode() + b"=" + value
    return struct.pack("<I", len(b)) + b


def record(fields, data):
    h = b"".join(fields)
    return struct.pack("<I", len(h)) + h + struct.pack("<I", len(data)) + data


def ros1_bag(compression, messages):
    inner = b""
    for i, (topic, type_, t, f) in enumerate(messages):
        inner += record([field("op", b"\x07"), field("conn", struct.pack("<I", i)), field("topic", topic.encode())],
                        field("type", type_.encode()) + field("md5sum", b"*"))
        inner += record([field("op", b"\x02"), field("conn", struct.pack("<I", i)),
                         field("time", struct.pack("<II", *divmod(t, 1000000000)))], rw.ros1(type_, f))
    data = {"none": inner, "bz2": bz2.compress(inner), "lz4": lz4.frame.compress(inner)}[compression]
    out = b"#ROSBAG V2.0\n"
    out += record([field("op", b"\x03"), field("index_pos", struct.pack("<Q", 0)),
                   field("conn_count", struct.pack("<I", len(messages))), field("chunk_count", struct.pack("<I", 1))], b"")
    out += record([field("op", b"\x05"), field("compression", compression.encode()),
                   field("size", struct.pack("<I", len(inner)))], data)
    return out


def write(target, name, data):
    os.makedirs(os.path.join(CORPUS, target), exist_ok=True)
    with open(os.path.join(CORPUS, target, name), "wb") as fh:
        fh.write(data)


for c in ("none", "bz2", "lz4"):
    write("fuzz_ros1_bag", "tiny_%s.bag" % c, ros1_bag(c, MESSAGES[:2]))
for kind, opts in (("mcap-none", {}), ("mcap-zstd", {}), ("mcap-lz4", {}), ("mcap-none", {"chunk_messages": 0})):
    path = os.path.join(CORPUS, "fuzz_mcap", "tiny_%s%s.mcap" % (kind[5:], "_unchunked" if opts else ""))
    os.makedirs(os.path.dirname(path), exist_ok=True)
    rw.write_recording(kind, path, [MESSAGES[0], MESSAGES[2]], **opts)
# fuzz_ros_messages: the first byte picks the decoder (low 3 bits) and CDR (bit 3).
decoders = [("sensor_msgs/Image", IMAGE), ("sensor_msgs/CameraInfo", INFO), ("tf2_msgs/TFMessage", TF),
            ("geometry_msgs/Transform", {"translation": (1, 2, 3), "rotation": (0, 0, 0, 1)}),
            ("std_msgs/Float32", {"data": 0.5}), ("std_msgs/UInt32", {"data": 7}), ("std_msgs/String", {"data": "ab"}),
            ("diagnostic_msgs/KeyValue", {"key": "k", "value": "v"})]
for i, (type_, f) in enumerate(decoders):
    name = type_.split("/")[1].lower()
    write("fuzz_ros_messages", "%s_ros1" % name, bytes([i]) + rw.ros1(type_, f))
    write("fuzz_ros_messages", "%s_cdr" % name, bytes([i | 8]) + rw.cdr(type_, f))
