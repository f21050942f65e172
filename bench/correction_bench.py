#!/usr/bin/env python3
"""Correcting a map (issue 29, docs/CORRECTION.md): what re-fusing a frame costs against fusing one, and how a
live run behaves while a loop's worth of corrections drains at the per-frame budget.

A sequence is fused at drifted poses (frame i turned by i x 0.2 degrees and moved by i x 4 mm, as a tracker
drifts), then every fused frame gets its true pose back through Reconstructor.correct(), as a loop closure
would hand them over. The run then goes on fusing the next frames of the sequence at their true poses, each
integrate() re-fusing corrections_per_frame queued frames first, until the queue is empty:
  - frames until the mesh is consistent (the queue drained) at the budget;
  - the wall time of those frames against the frames after, which re-fuse nothing;
  - at the end the mesh is compared with one fused at the true poses from the start (must be equal: TSDF and
    triangles), and finish_corrections() on a second copy gives the all-at-once time per re-fused frame.

    scripts/build.sh
    PYTHONPATH=build/python /usr/bin/python3 bench/correction_bench.py DATASET [--frames 60] [--after 20]
        [--voxel 0.02] [--budget 2] [--json out.json]

DATASET: any folder `vkmesh fuse` reads with poses (the shared TUM / ICL-NUIM copies, or `vkmesh synth`).
"""

import argparse
import json
import statistics
import sys
import time

import numpy as np

import vkmesh


def drift(pose: np.ndarray, i: int) -> np.ndarray:
    a = np.radians(0.2 * i)
    d = np.eye(4)
    d[:3, :3] = [[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]
    d[:3, 3] = [0.004 * i, 0.0, -0.002 * i]
    return d @ pose


def canonical(mesh: vkmesh.Mesh) -> list:
    out = []
    for a, b, c in mesh.vertices[mesh.triangles].tolist():
        a, b, c = tuple(a), tuple(b), tuple(c)
        out.append(min((a, b, c), (b, c, a), (c, a, b)))
    out.sort()
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dataset")
    p.add_argument("--frames", type=int, default=60, help="frames fused at drifted poses, then all corrected")
    p.add_argument("--after", type=int, default=20, help="frames fused after the correction (the queue drains meanwhile)")
    p.add_argument("--voxel", type=float, default=0.02)
    p.add_argument("--budget", type=int, default=2, help="corrections_per_frame")
    p.add_argument("--json", default="")
    a = p.parse_args()

    frames = list(vkmesh.open_dataset(a.dataset, frames=a.frames + a.after))
    if len(frames) < a.frames + a.after:
        sys.exit(f"{a.dataset} has {len(frames)} usable frames, fewer than --frames + --after")
    first, rest = frames[: a.frames], frames[a.frames:]

    def reconstructor(**extra):
        return vkmesh.Reconstructor(voxel_size=a.voxel, **extra)

    live = reconstructor(keep_frames=True, corrections_per_frame=a.budget)
    fuse_ms = []
    for i, f in enumerate(first):
        t0 = time.perf_counter()
        live.integrate(f.depth, f.intrinsics, drift(f.pose, i), color=f.color)
        fuse_ms.append(1e3 * (time.perf_counter() - t0))
    store = live.stats().get("frame_store")
    live.correct(np.arange(len(first)), np.stack([f.pose for f in first]))
    queued = live.pending_corrections()
    draining_ms, after_ms, refused = [], [], 0
    frames_to_consistent = None
    for n, f in enumerate(rest, 1):
        t0 = time.perf_counter()
        live.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
        ms = 1e3 * (time.perf_counter() - t0)
        done = live.last_corrections()["frames_refused"]
        refused += done
        (draining_ms if done else after_ms).append(ms)
        if frames_to_consistent is None and live.pending_corrections() == 0:
            frames_to_consistent = n
    live.finish_corrections()

    truth = reconstructor()
    for f in frames:
        truth.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
    equal = canonical(live.mesh()) == canonical(truth.mesh())

    # All at once: a second copy of the drifted map, corrected by finish_corrections().
    once = reconstructor(keep_frames=True)
    for i, f in enumerate(first):
        once.integrate(f.depth, f.intrinsics, drift(f.pose, i), color=f.color)
    once.correct(np.arange(len(first)), np.stack([f.pose for f in first]))
    report = once.finish_corrections()

    med = statistics.median
    out = {
        "dataset": a.dataset, "voxel": a.voxel, "budget": a.budget, "frames_fused_drifted": len(first),
        "corrections_queued": queued, "refused_while_live": refused,
        "frames_until_consistent": frames_to_consistent,
        "fuse_ms_median": med(fuse_ms),
        "frame_ms_while_draining_median": med(draining_ms) if draining_ms else None,
        "frame_ms_after_median": med(after_ms) if after_ms else None,
        "finish_corrections": {"frames": report["frames_refused"], "ms": report["ms"],
                               "ms_per_frame": report["ms"] / max(1, report["frames_refused"]),
                               "blocks_freed": report["blocks_freed"], "observations_dropped": report["observations_dropped"]},
        "mesh_equals_true_poses_run": equal,
        "frame_store": store,
    }
    per = out["finish_corrections"]["ms_per_frame"]
    print(f"{a.dataset}: {len(first)} frames fused drifted, {queued} corrections queued; budget {a.budget}/frame: "
          f"consistent after {frames_to_consistent} frames; frame {out['frame_ms_while_draining_median']:.1f} ms while "
          f"draining vs {out['frame_ms_after_median'] or float('nan'):.1f} ms after (fusing alone {out['fuse_ms_median']:.1f} ms); "
          f"all at once {per:.1f} ms per re-fused frame ({per / out['fuse_ms_median']:.2f}x a fused frame); "
          f"mesh equals the true-pose run: {equal}")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return 0 if equal else 1


if __name__ == "__main__":
    sys.exit(main())
