#!/usr/bin/env python3
"""Reading speed of each recording container against the folder it was made from (docs/RESULTS.md,
"Recordings"): the same frames, opened and read through vkmesh's dataset reader (Python's open_dataset, which
is Dataset::open and Dataset::loadDepth/loadColor in C++), alternating the inputs round by round.

    PYTHONPATH=build/python /usr/bin/python3 bench/recordings_bench.py FOLDER [--rounds 3] [--work DIR]
        [--kinds tum-ros1-none,...] [--no-poses]

FOLDER is a TUM-layout folder (a `vkmesh synth` sequence, or TUM fr1/rpy, ICL-NUIM's TUM-compatible release);
tests/support/make_recordings.py writes its recordings into --work (default: a temporary folder) first. Prints
one line per input: open seconds, frames per second reading depth and colour (median over the rounds), size
on disk; and a JSON line with the same.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import vkmesh

HERE = os.path.dirname(os.path.abspath(__file__))
KINDS = ["tum-ros1-none", "tum-ros1-bz2", "tum-ros1-lz4", "tum-mcap-none", "tum-mcap-zstd", "tum-mcap-lz4", "tum-db3",
         "realsense"]


def path_of(work, kind):
    if kind == "realsense":
        return os.path.join(work, "realsense.bag")
    if "ros1" in kind:
        return os.path.join(work, kind + ".bag")
    if "mcap" in kind:
        return os.path.join(work, kind + ".mcap")
    return os.path.join(work, kind)


def size_of(path):
    if os.path.isdir(path):
        return sum(os.path.getsize(os.path.join(dp, f)) for dp, _, files in os.walk(path) for f in files)
    return os.path.getsize(path)


def read_all(path, require_poses):
    t0 = time.perf_counter()
    ds = vkmesh.open_dataset(path, require_poses=require_poses)
    t1 = time.perf_counter()
    n = 0
    for frame in ds:
        n += frame.depth.size > 0
    t2 = time.perf_counter()
    return t1 - t0, n / (t2 - t1), n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--work", default="")
    ap.add_argument("--kinds", default=",".join(KINDS))
    args = ap.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="vkmesh_recordings_bench_")
    kinds = [k for k in args.kinds.split(",") if k]
    subprocess.run([sys.executable, os.path.join(HERE, "..", "tests", "support", "make_recordings.py"), args.folder, work,
                    "--kinds", ",".join(kinds)], check=True, stdout=subprocess.DEVNULL)
    inputs = [("folder", args.folder)] + [(k, path_of(work, k)) for k in kinds]
    results = {name: {"open_s": [], "fps": []} for name, _ in inputs}
    frames = {}
    for _ in range(args.rounds):
        for name, path in inputs:
            # The RealSense layout has no poses (as a real recording): opened for tracking, the others with theirs.
            open_s, fps, n = read_all(path, require_poses=name != "realsense")
            results[name]["open_s"].append(open_s)
            results[name]["fps"].append(fps)
            frames[name] = n
    summary = {}
    for name, path in inputs:
        r = results[name]
        summary[name] = {"frames": frames[name], "open_s": statistics.median(r["open_s"]),
                         "frames_per_s": statistics.median(r["fps"]), "bytes": size_of(path)}
        s = summary[name]
        print(f"{name:15s} {s['frames']:5d} frames  open {s['open_s']:7.3f} s  {s['frames_per_s']:7.1f} frames/s  "
              f"{s['bytes'] / 1e6:8.1f} MB")
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
