#!/usr/bin/env python3
"""Turns a TUM-layout folder (what `vkmesh synth` writes) into the recordings vkmesh reads, with the same frames,
for the tests that check each recording fuses to exactly the folder's mesh (tests/cpu/test_recording_datasets.cpp,
tests/gpu/test_recordings_fuse.cpp) and for bench/recordings_bench.sh.

    make_recordings.py FOLDER OUT_DIR [--kinds K1,K2,...] [--chunk-bytes N]

Kinds (file written in OUT_DIR):
  tum-ros1-none, tum-ros1-bz2, tum-ros1-lz4   <kind>.bag   a ROS 1 bag in TUM's layout: /camera/depth/image (32FC1
                                                metres, NaN where there is no measurement), /camera/rgb/image_color
                                                (rgb8), both cameras' sensor_msgs/CameraInfo, and the ground truth
                                                in /tf (world -> openni_rgb_optical_frame at every depth frame's time)
  tum-mcap-none, tum-mcap-zstd, tum-mcap-lz4  <kind>.mcap  the same messages, CDR-encoded (ROS 2)
  tum-db3                                     <kind>/      a rosbag2 folder: metadata.yaml + <kind>_0.db3 (CDR)
  realsense                                   <kind>.bag   librealsense's layout: mono16 depth in its Depth Units,
                                                rgb8 colour, each stream's camera_info and tf/0 extrinsics; no
                                                poses (as a RealSense recording): fused with --track

The colour camera is the folder's camera.json color_* calibration and depth_to_color when it has them (the
RealSense kind writes them as the colour stream's intrinsics and extrinsics), else the depth camera.

Messages are built here as plain dicts and written by recording_writers.py (ROS 1 through Debian's rosbag,
MCAP and rosbag2 by the container specifications). Depth goes in exactly as vkmesh converts the folder's PNGs:
32FC1 holds float32(raw / depth_scale), the same float vkmesh computes; mono16 holds the raw samples with Depth
Units 1 / depth_scale.
"""
import argparse
import json
import math
import os
import sys

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import recording_writers  # noqa: E402

ALL_KINDS = ["tum-ros1-none", "tum-ros1-bz2", "tum-ros1-lz4", "tum-mcap-none", "tum-mcap-zstd", "tum-mcap-lz4",
             "tum-db3", "realsense"]


def read_list(path):
    rows = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith("#"):
                rows.append(line.split())
    return rows


def time_ns(seconds_text):
    # Exact decimal to integer nanoseconds (a float would round 1.033 to 1032999999).
    whole, _, frac = seconds_text.partition(".")
    return int(whole) * 1_000_000_000 + int((frac + "000000000")[:9])


def rotation_to_quaternion(r):
    """Unit quaternion (x, y, z, w) of a 3x3 rotation matrix (Shepperd's method)."""
    t = r[0][0] + r[1][1] + r[2][2]
    if t > 0:
        s = math.sqrt(t + 1.0) * 2
        return ((r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s, 0.25 * s)
    if r[0][0] > r[1][1] and r[0][0] > r[2][2]:
        s = math.sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]) * 2
        return (0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s, (r[2][1] - r[1][2]) / s)
    if r[1][1] > r[2][2]:
        s = math.sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]) * 2
        return ((r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s, (r[0][2] - r[2][0]) / s)
    s = math.sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]) * 2
    return ((r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s, (r[1][0] - r[0][1]) / s)


def camera_info(stamp, frame_id, width, height, fx, fy, cx, cy):
    return {"header": {"stamp_ns": stamp, "frame_id": frame_id}, "height": height, "width": width,
            "distortion_model": "plumb_bob", "D": [0.0] * 5, "K": [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
            "R": [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0], "P": [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]}


def image(stamp, frame_id, array, encoding):
    a = np.ascontiguousarray(array)
    height, width = a.shape[:2]
    return {"header": {"stamp_ns": stamp, "frame_id": frame_id}, "height": height, "width": width,
            "encoding": encoding, "is_bigendian": 0, "step": a.strides[0], "data": a.tobytes()}


def load_folder(folder):
    cam = json.load(open(os.path.join(folder, "camera.json")))
    depth = read_list(os.path.join(folder, "depth.txt"))
    rgb = {row[0]: row[1] for row in read_list(os.path.join(folder, "rgb.txt"))} \
        if os.path.exists(os.path.join(folder, "rgb.txt")) else {}
    gt = {row[0]: [float(v) for v in row[1:8]] for row in read_list(os.path.join(folder, "groundtruth.txt"))}
    frames = []
    for stamp_text, depth_rel in depth:
        raw = np.array(Image.open(os.path.join(folder, depth_rel)), dtype=np.uint16)
        color = None
        if stamp_text in rgb:
            color = np.array(Image.open(os.path.join(folder, rgb[stamp_text])).convert("RGB"), dtype=np.uint8)
        frames.append({"t": time_ns(stamp_text), "raw": raw, "color": color, "pose": gt.get(stamp_text)})
    return cam, frames


def tum_messages(cam, frames):
    """TUM's published bags: depth in metres as 32FC1 (NaN: no measurement), registered to the rgb camera."""
    scale = float(cam["depth_scale"])
    frame_id = "/openni_rgb_optical_frame"
    h, w = frames[0]["raw"].shape
    msgs = []
    for f in frames:
        t = f["t"]
        metres = (f["raw"].astype(np.float64) / scale).astype(np.float32)   # float(raw / scale), as vkmesh
        metres[f["raw"] == 0] = np.nan
        msgs.append(("/camera/depth/camera_info", "sensor_msgs/CameraInfo", t,
                     camera_info(t, frame_id, w, h, cam["fx"], cam["fy"], cam["cx"], cam["cy"])))
        msgs.append(("/camera/depth/image", "sensor_msgs/Image", t, image(t, frame_id, metres, "32FC1")))
        if f["color"] is not None:
            # The colour 3 ms after the depth, as a real sensor's streams are never simultaneous.
            msgs.append(("/camera/rgb/image_color", "sensor_msgs/Image", t + 3_000_000,
                         image(t + 3_000_000, frame_id, f["color"], "rgb8")))
            msgs.append(("/camera/rgb/camera_info", "sensor_msgs/CameraInfo", t + 3_000_000,
                         camera_info(t + 3_000_000, frame_id, w, h, cam["fx"], cam["fy"], cam["cx"], cam["cy"])))
        if f["pose"] is not None:
            tx, ty, tz, qx, qy, qz, qw = f["pose"]
            msgs.append(("/tf", "tf2_msgs/TFMessage", t,
                         {"transforms": [{"header": {"stamp_ns": t, "frame_id": "/world"},
                                          "child_frame_id": frame_id,
                                          "translation": [tx, ty, tz], "rotation": [qx, qy, qz, qw]}]}))
    msgs.sort(key=lambda m: m[2])
    return msgs


def realsense_messages(cam, frames):
    """librealsense's layout (src/media/readme.md in librealsense): device 0, the depth stream on sensor 0, the
    colour stream on sensor 1, depth units as sensor 0's option, each stream's extrinsics to group 0 in tf/0."""
    scale = float(cam["depth_scale"])
    h, w = frames[0]["raw"].shape
    depth_stream, color_stream = "/device_0/sensor_0/Depth_0", "/device_0/sensor_1/Color_0"
    t0 = frames[0]["t"]
    msgs = [("/file_version", "std_msgs/UInt32", t0, {"data": 3}),
            ("/device_0/info", "diagnostic_msgs/KeyValue", t0, {"key": "Name", "value": "Intel RealSense D435"}),
            ("/device_0/sensor_0/option/Depth Units/value", "std_msgs/Float32", t0, {"data": 1.0 / scale}),
            (depth_stream + "/info/camera_info", "sensor_msgs/CameraInfo", t0,
             camera_info(t0, "", w, h, cam["fx"], cam["fy"], cam["cx"], cam["cy"])),
            (depth_stream + "/tf/0", "geometry_msgs/Transform", t0,
             {"translation": [0.0, 0.0, 0.0], "rotation": [0.0, 0.0, 0.0, 1.0]})]
    has_color = any(f["color"] is not None for f in frames)
    if has_color:
        first = next(f["color"] for f in frames if f["color"] is not None)
        ch, cw = first.shape[:2]
        cfx, cfy = cam.get("color_fx", cam["fx"]), cam.get("color_fy", cam["fy"])
        ccx, ccy = cam.get("color_cx", cam["cx"]), cam.get("color_cy", cam["cy"])
        # librealsense's colour streams carry their lens model; vkmesh uses the image as rectified and says so.
        color_info = camera_info(t0, "", cw, ch, cfx, cfy, ccx, ccy)
        color_info["distortion_model"] = "Inverse Brown Conrady"
        color_info["D"] = [0.01, -0.02, 0.0, 0.0, 0.0]
        msgs.append((color_stream + "/info/camera_info", "sensor_msgs/CameraInfo", t0, color_info))
        # The colour stream's transform from the group's reference (the depth stream) to it: depth_to_color.
        extr = cam.get("depth_to_color", {"rotation": [1, 0, 0, 0, 1, 0, 0, 0, 1], "translation": [0, 0, 0]})
        r = extr["rotation"]
        q = rotation_to_quaternion([r[0:3], r[3:6], r[6:9]])
        msgs.append((color_stream + "/tf/0", "geometry_msgs/Transform", t0,
                     {"translation": list(map(float, extr["translation"])), "rotation": list(q)}))
    for f in frames:
        t = f["t"]
        msgs.append((depth_stream + "/image/data", "sensor_msgs/Image", t, image(t, "0", f["raw"], "mono16")))
        if f["color"] is not None:
            msgs.append((color_stream + "/image/data", "sensor_msgs/Image", t + 1_000_000,
                         image(t + 1_000_000, "0", f["color"], "rgb8")))
    msgs.sort(key=lambda m: m[2])
    return msgs


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    ap.add_argument("out_dir")
    ap.add_argument("--kinds", default=",".join(ALL_KINDS))
    ap.add_argument("--chunk-bytes", type=int, default=256 * 1024,
                    help="chunk size of the ROS 1 bags (small: several chunks even for a few frames)")
    ap.add_argument("--chunk-messages", type=int, default=8, help="messages per MCAP chunk")
    args = ap.parse_args()
    kinds = [k for k in args.kinds.split(",") if k]
    for k in kinds:
        if k not in ALL_KINDS:
            sys.exit(f"make_recordings.py: unknown kind {k} (known: {', '.join(ALL_KINDS)})")
    cam, frames = load_folder(args.folder)
    os.makedirs(args.out_dir, exist_ok=True)
    tum = tum_messages(cam, frames) if any(k.startswith("tum-") for k in kinds) else None
    for k in kinds:
        if k == "realsense":
            path = os.path.join(args.out_dir, "realsense.bag")
            recording_writers.write_recording("ros1-lz4", path, realsense_messages(cam, frames),
                                              chunk_threshold=args.chunk_bytes)
            continue
        container, _, compression = k[len("tum-"):].partition("-")
        if container == "ros1":
            path = os.path.join(args.out_dir, k + ".bag")
            recording_writers.write_recording("ros1-" + compression, path, tum, chunk_threshold=args.chunk_bytes)
        elif container == "mcap":
            path = os.path.join(args.out_dir, k + ".mcap")
            recording_writers.write_recording("mcap-" + compression, path, tum, chunk_messages=args.chunk_messages)
        else:
            path = os.path.join(args.out_dir, k)
            recording_writers.write_recording("db3", path, tum)
        print(path)


if __name__ == "__main__":
    main()
