#!/usr/bin/python3
"""Why allocation by tiles leaves a tile to the pixels' band walks, counted over a few depth images.

An approximation of shaders_comp/allocate/allocate_tiles.comp's decisions (numpy's least squares in doubles instead
of the shader's float moments; the bound on the slab's block box, which needs the pose, is not checked): for each
tile of 8 x 8 samples of every 2nd pixel, the first reason that applies:
  no depth        no valid depth at all: covered, with nothing to claim (nothing to walk either)
  < 48 valid      fewer than ALLOC_TILE_MIN_VALID valid depths
  D sign          D = 1 - a x' - b y' does not take g's sign at every sample: the fitted plane z = a x + b y + g
                  does not meet every ray of the tile in front of the camera (g / D > 0); a plane with g < 0
                  and D < 0 on every ray is covered like one with g > 0 and D > 0
  residual        a depth farther than ALLOC_TILE_MAX_RESIDUAL x the truncation from the plane (split by whether
                  most depths fit it: an edge; or not: noise or a curved surface)
  covered         the slab is claimed (`covered, g < 0` where the plane's g is negative)

Usage (Debian's interpreter, which has python3-open3d for the PNG reader):
  /usr/bin/python3 bench/alloc_tile_reasons.py DATASET FX FY TRUNCATION_M DEPTH_PNG...
  e.g. ../shared/datasets/iclnuim_office_traj0 481.2 -480 0.08 2.png 302.png 602.png 902.png
       (names relative to DATASET/depth; cx, cy = 319.5, 239.5; depth scale 5000; depth range 0.1-4 m)
"""

import collections
import sys

import numpy as np
import open3d as o3d

MIN_DEPTH, MAX_DEPTH, STRIDE, TILE = 0.1, 4.0, 2, 8
MIN_VALID, MAX_RESIDUAL = 48, 0.5   # shared_layout.h: ALLOC_TILE_MIN_VALID, ALLOC_TILE_MAX_RESIDUAL


def reasons_for(depth, fx, fy, cx, cy, truncation, counts):
    height, width = depth.shape
    for ty in range(0, height // STRIDE, TILE):
        for tx in range(0, width // STRIDE, TILE):
            ys, xs = np.mgrid[ty:ty + TILE, tx:tx + TILE] * STRIDE
            ys, xs = np.minimum(ys, height - 1), np.minimum(xs, width - 1)
            d = depth[ys, xs]
            valid = (d >= MIN_DEPTH) & (d <= MAX_DEPTH)
            if not valid.any():
                counts["no depth"] += 1
                continue
            if valid.sum() < MIN_VALID:
                counts["< 48 valid"] += 1
                continue
            rx, ry, dv = (xs[valid] - cx) / fx, (ys[valid] - cy) / fy, d[valid]
            design = np.stack([rx * dv, ry * dv, np.ones(len(dv))], 1)
            (a, b, g), *_ = np.linalg.lstsq(design, dv, rcond=None)
            D = 1 - a * rx - b * ry
            if (np.sign(g) * D <= 0).any():
                counts["D sign"] += 1
                continue
            residual = np.abs(dv - g / D)
            if residual.max() > MAX_RESIDUAL * truncation:
                edge = np.median(residual) < 0.1 * truncation
                counts["residual (an edge)" if edge else "residual (noise or curved)"] += 1
                continue
            counts["covered" if g > 0 else "covered, g < 0"] += 1


def main():
    if len(sys.argv) < 6:
        sys.exit(__doc__)
    root, fx, fy, truncation = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
    counts = collections.Counter()
    for name in sys.argv[5:]:
        depth = np.asarray(o3d.io.read_image(f"{root}/depth/{name}")).astype(np.float64) / 5000.0
        reasons_for(depth, fx, fy, 319.5, 239.5, truncation, counts)
    total = sum(counts.values())
    for reason, n in counts.most_common():
        print(f"{reason:28s} {n:6d} {100 * n / total:5.1f} %")


if __name__ == "__main__":
    main()
