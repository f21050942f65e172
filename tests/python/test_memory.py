"""Memory stays flat: per call nothing is kept (the depth and colour buffers are reused, the arrays handed to
numpy own their memory), and a dropped Reconstructor gives everything back. Measured as the process's resident
set (VmRSS) after a warm-up, with a tolerance well below what one leaked buffer per call would add."""

import ctypes
import gc

import numpy as np

import vkmesh
from conftest import plane_frame, small_reconstructor

MB = 1 << 20


def rss() -> int:
    """Resident bytes after a garbage collection, with the C allocator's free pages handed back (malloc_trim), so
    that what is measured is memory still held, not freed memory glibc keeps in its per-thread arenas."""
    gc.collect()
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS in /proc/self/status")


def test_flat_over_1000_integrate_calls():
    width, height = 128, 96
    r = small_reconstructor(track_deltas=True)
    frames = []
    for step in range(20):   # a few poses, so the mesh keeps changing a little
        depth, k, pose = plane_frame(width, height, step=step)
        raw = np.round(depth * 5000).astype(np.uint16)
        color = np.full((height, width, 3), 40 + 10 * step, np.uint8)
        frames.append((depth, raw, k, pose, color))

    def run(calls):
        for i in range(calls):
            depth, raw, k, pose, color = frames[i % len(frames)]
            if i % 2:   # both depth paths, with and without colour, and the mesh and deltas now and then
                r.integrate(raw, k, pose, depth_scale=5000.0, color=color)
            else:
                r.integrate(depth, k, pose)
            if i % 10 == 0:
                assert len(r.mesh().triangles) > 0
                r.deltas()
                r.stats()

    run(100)   # warm-up: capacities, allocator pools, lavapipe's caches
    before = rss()
    run(900)
    grown = rss() - before
    # One float32 depth buffer kept per call would be 900 x 48 KiB = 42 MiB (a leak injected there measured 46.5 MiB);
    # one mesh kept per mesh() call more. Measured without a leak: 3.8 MiB with the validation layer (its own
    # bookkeeping grows with the submissions), 0 without.
    assert grown < 8 * MB, f"resident memory grew by {grown / MB:.1f} MiB over 900 integrate calls"
    assert r.frames_integrated == 1000


def test_flat_over_100_reconstructors():
    depth, k, pose = plane_frame()

    def cycle(count, fuse_every):
        for i in range(count):
            r = small_reconstructor()
            if i % fuse_every == 0:   # all create a device; some fuse a frame (a GPU volume and its pipelines)
                r.integrate(depth, k, pose)
                r.mesh()
            del r

    cycle(3, 1)    # warm-up: the first GPU volumes fill lavapipe's and the validation layer's caches
    cycle(7, 10)
    before = rss()
    cycle(90, 30)
    grown = rss() - before
    # Kept alive, a Reconstructor holds 4 MiB (6 MiB with the validation layer) before its first frame on lavapipe,
    # ~65 MiB after it (the small volume's buffers and pipelines): 90 of them would be 360 MiB, the 3 with a
    # volume 200 MiB. Measured without a leak: 9-17 MiB with validation (caches still settling).
    assert grown < 32 * MB, f"resident memory grew by {grown / MB:.1f} MiB over 90 Reconstructors"
