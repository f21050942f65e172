#!/usr/bin/env python3
"""What the Python module adds to a frame: Reconstructor.integrate from Python (numpy arrays in) against the C++
API's Reconstructor::integrate on the same frames, side by side in one run.

Three Reconstructors with the same settings fuse the same frames in the same order, so their GPU work is the
same frame by frame:
  python float32   r.integrate(depth_metres_float32, intrinsics, pose, color=rgb): timed in Python
                   (time.perf_counter around the call: argument checks, the copy into the reused buffers,
                   releasing the GIL, the C++ call)
  python uint16    the same with the PNG's raw uint16 depth and depth_scale (adds the conversion to metres)
  C++              vkmesh::Reconstructor::integrate on a DepthImage/ColorImage converted beforehand, timed in
                   C++ (std::chrono around the call; vkmesh._vkmesh._timed_cpp_integrate)
Within every frame the three run one after the other, in an order that rotates from frame to frame, so that
load changes on the shared machine hit all three alike. Overhead = Python time / C++ time - 1, from the
medians and from the per-frame paired differences. Both swing by a few per cent with the machine's load (the
GPU work of a frame on lavapipe varies that much from one volume to the next), so the module's own cost is also
measured exactly, per call: the wall time of each Python integrate() minus the time it spent inside the C++
Reconstructor::integrate (timed in C++ within the same call).

    scripts/build.sh
    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [--frames 120] [--width 640 --height 480]
"""

import argparse
import datetime
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import vkmesh
from vkmesh import _vkmesh


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="out/python_overhead", help="folder for the synthetic sequence and the JSON")
    p.add_argument("--dataset", help="fuse this dataset instead of a synthetic room")
    p.add_argument("--frames", type=int, default=120)
    p.add_argument("--width", type=int, default=640)
    p.add_argument("--height", type=int, default=480)
    p.add_argument("--voxel", type=float, default=0.03)
    args = p.parse_args()

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    folder = args.dataset
    if folder is None:
        folder = out / f"room_{args.width}x{args.height}_{args.frames}"
        if not (folder / "groundtruth.txt").exists():
            print(f"writing {args.frames} synthetic frames to {folder}", file=sys.stderr)
            vkmesh.synth(folder, frames=args.frames, width=args.width, height=args.height, noise=True)
    frames = list(vkmesh.open_dataset(folder, frames=args.frames))
    print(f"{len(frames)} frames of {frames[0].depth.shape[1]}x{frames[0].depth.shape[0]} from {folder}", file=sys.stderr)

    methods = ["python float32", "python uint16", "C++"]
    recs = {m: vkmesh.Reconstructor(voxel_size=args.voxel) for m in methods}
    inputs = []
    for f in frames:
        raw = np.round(f.depth.astype(np.float64) * f.depth_scale).astype(np.uint16)
        cpp = _vkmesh._CppFrame(f.depth, f.intrinsics, f.pose, color=f.color,
                                max_depth=recs["C++"].stats()["max_depth"])
        inputs.append((f, raw, cpp))

    def run(method, f, raw, cpp):
        r = recs[method]
        if method == "C++":
            return _vkmesh._timed_cpp_integrate(r, cpp)
        depth, scale = (f.depth, 5000.0) if method == "python float32" else (raw, f.depth_scale)
        t0 = time.perf_counter()
        r.integrate(depth, f.intrinsics, f.pose, depth_scale=scale, color=f.color)
        return time.perf_counter() - t0

    times = {m: [] for m in methods}
    inner = {m: [] for m in methods[:2]}   # per Python call: the part spent in the C++ Reconstructor::integrate
    for i, (f, raw, cpp) in enumerate(inputs):
        order = methods[i % 3:] + methods[:i % 3]
        for m in order:
            times[m].append(run(m, f, raw, cpp) * 1000.0)
            if m in inner:
                inner[m].append(recs[m]._last_cpp_seconds * 1000.0)
        print(f"\rframe {i + 1}/{len(inputs)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)

    # The three volumes saw the same frames: their meshes must be the same (else the comparison is not fair).
    counts = {m: len(recs[m].mesh().triangles) for m in methods}
    assert len(set(counts.values())) == 1, counts

    skip = min(5, len(inputs) // 10)   # the first frames build the GPU volume (pipelines): not per-frame cost
    cpp = np.array(times["C++"][skip:])
    rows = []
    for m in methods:
        t = np.array(times[m][skip:])
        diff = t - cpp
        row = {"method": m, "median_ms": float(np.median(t)), "mean_ms": float(np.mean(t)),
               "paired_diff_median_ms": float(np.median(diff)),
               "overhead_median_pct": 100.0 * (np.median(t) / np.median(cpp) - 1.0),
               "overhead_paired_pct": 100.0 * float(np.median(diff)) / float(np.median(cpp))}
        if m in inner:
            own = t - np.array(inner[m][skip:])
            row.update(module_ms_median=float(np.median(own)), module_ms_max=float(np.max(own)),
                       module_pct_median=100.0 * float(np.median(own / np.array(inner[m][skip:]))))
        rows.append(row)
    result = {"date": datetime.datetime.now().isoformat(timespec="seconds"), "cpus": os.cpu_count(),
              "machine": platform.machine(), "device": recs["C++"].stats()["device"], "dataset": str(folder),
              "frames_timed": len(cpp), "frames_skipped": skip, "triangles": counts["C++"], "rows": rows,
              "per_frame_ms": times, "per_frame_inner_cpp_ms": inner}
    (out / "python_overhead.json").write_text(json.dumps(result, indent=2))

    print(f"\n{result['frames_timed']} frames timed ({skip} first skipped), {frames[0].depth.shape[1]}x"
          f"{frames[0].depth.shape[0]}, voxel {args.voxel} m, {counts['C++']} triangles at the end; "
          f"{result['device']}, {result['cpus']} CPUs, {result['date']}\n")
    print("| integrate from | median ms | mean ms | median of per-frame (X - C++) ms | overhead (medians) | "
          "overhead (paired) | module's own ms per call (median / max) | module's own share |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        own = (f"{r['module_ms_median']:.3f} / {r['module_ms_max']:.3f} | {r['module_pct_median']:.2f} %"
               if "module_ms_median" in r else "- | -")
        print(f"| {r['method']} | {r['median_ms']:.2f} | {r['mean_ms']:.2f} | {r['paired_diff_median_ms']:+.3f} | "
              f"{r['overhead_median_pct']:+.1f} % | {r['overhead_paired_pct']:+.1f} % | {own} |")
    print(f"\nwrote {out / 'python_overhead.json'}")


if __name__ == "__main__":
    main()
