#!/usr/bin/env python3
"""Fuses a dataset folder (TUM RGB-D, ICL-NUIM, Redwood or 7-Scenes layout) with vkmesh and writes the coloured
mesh as PLY, with a progress bar (tqdm when installed, a plain text line otherwise).

    PYTHONPATH=build/python python3 examples/python/fuse_dataset.py DATASET -o mesh.ply [--voxel 0.02]
    (try it on a synthetic room: python3 -c "import vkmesh; vkmesh.synth('out/room', frames=60)")
"""

import argparse
import sys
import time

import vkmesh


def progress(frames, total):
    """Yields `frames`, drawing a progress bar on stderr."""
    try:
        from tqdm import tqdm
    except ImportError:
        tqdm = None
    if tqdm is not None:
        yield from tqdm(frames, total=total, unit="frame")
        return
    start = time.perf_counter()
    done = 0
    for frame in frames:
        yield frame
        done += 1
        rate = done / max(time.perf_counter() - start, 1e-9)
        print(f"\rframe {done}/{total}  {rate:.1f} frames/s", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", help="dataset folder")
    parser.add_argument("-o", "--output", required=True, help="mesh file (.ply, or .obj)")
    parser.add_argument("--voxel", type=float, default=0.03, help="voxel size in metres (default 0.03)")
    parser.add_argument("--frames", type=int, default=0, help="use at most N frames (0 = all)")
    parser.add_argument("--max-depth", type=float, default=4.0, help="ignore depth beyond M metres (default 4)")
    parser.add_argument("--device", type=int, default=None, help="Vulkan device index (see vkmesh.devices())")
    args = parser.parse_args()

    dataset = vkmesh.open_dataset(args.dataset, frames=args.frames)
    print(dataset, file=sys.stderr)
    reconstructor = vkmesh.Reconstructor(voxel_size=args.voxel, max_depth=args.max_depth, device=args.device)
    for frame in progress(dataset, len(dataset)):
        reconstructor.integrate(frame.depth, frame.intrinsics, frame.pose, color=frame.color)
    mesh = reconstructor.mesh()
    mesh.save(args.output)
    stats = reconstructor.stats()
    print(f"{reconstructor.frames_integrated} frames on {stats['device']}: {len(mesh.vertices)} vertices, "
          f"{len(mesh.triangles)} triangles{' with colour' if mesh.colors is not None else ''} -> {args.output}")


if __name__ == "__main__":
    main()
