"""The rest of the API: devices, datasets, meshes on disk, deltas, stats, threads and the documentation."""

import os
import shutil
import threading
import time
import warnings

import numpy as np
import pytest

import vkmesh
from conftest import canonical_triangles, plane_frame, small_reconstructor


def test_devices():
    devices = vkmesh.devices()
    assert devices and any(d.suitable for d in devices)
    assert devices[0].index == 0 and devices[0].name
    assert all(d.why_not == "" for d in devices if d.suitable)


def test_validation_follows_the_environment_as_in_the_cli():
    r = small_reconstructor()
    assert r.stats()["validation"] == (os.environ.get("VKMESH_VALIDATION") == "1")
    assert small_reconstructor(validation=True).stats()["validation"]


def test_dataset_frames(small_sequence):
    ds = vkmesh.open_dataset(small_sequence, frames=4)
    assert len(ds) == 4 and ds.kind == "TUM RGB-D" and ds.has_color
    assert (ds.width, ds.height) == (160, 120) and ds.depth_scale == 5000
    f = ds[-1]
    assert f.index == 3
    assert f.depth.dtype == np.float32 and f.depth.shape == (120, 160)
    assert f.color.dtype == np.uint8 and f.color.shape == (120, 160, 3)
    assert f.pose.shape == (4, 4) and np.allclose(f.pose[:3, :3].T @ f.pose[:3, :3], np.eye(3), atol=1e-6)
    assert f.intrinsics == ds.intrinsics and len(f.intrinsics) == 4
    assert f.depth_path.endswith("000003.png") and f.color_path.endswith("000003.png")
    with pytest.raises(IndexError):
        ds[4]
    assert [f.index for f in ds] == [0, 1, 2, 3]
    with pytest.raises(ValueError, match="depth_scale -1"):
        vkmesh.open_dataset(small_sequence, depth_scale=-1)


def test_dataset_from_a_recording(small_sequence, tmp_path):
    """A recording opens as its folder does: the same frames, depth, colour and poses (docs/RECORDINGS.md)."""
    import subprocess
    import sys
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        subprocess.run([sys.executable, "-c", "import rosbag, PIL, zstandard, lz4"], check=True, capture_output=True)
    except subprocess.CalledProcessError:
        pytest.skip("the recording fixtures need python3-rosbag, python3-pil, python3-zstandard, python3-lz4")
    subprocess.run([sys.executable, os.path.join(here, "..", "support", "make_recordings.py"), str(small_sequence),
                    str(tmp_path), "--kinds", "tum-mcap-zstd"], check=True, capture_output=True)
    folder = vkmesh.open_dataset(small_sequence)
    rec = vkmesh.open_dataset(tmp_path / "tum-mcap-zstd.mcap", depth_topic="/camera/depth/image")
    assert rec.kind == "MCAP" and len(rec) == len(folder) and rec.intrinsics == folder.intrinsics
    for a, b in zip(folder, rec):
        assert np.array_equal(a.depth, b.depth) and np.array_equal(a.color, b.color) and np.array_equal(a.pose, b.pose)
    with pytest.raises(vkmesh.Error, match="--depth-topic /nothing"):
        vkmesh.open_dataset(tmp_path / "tum-mcap-zstd.mcap", depth_topic="/nothing")


def test_iteration_skips_what_the_cli_skips(small_sequence, tmp_path):
    seq = tmp_path / "seq"
    shutil.copytree(small_sequence, seq)
    (seq / "depth" / "000001.png").write_bytes(b"this is not a png")
    (seq / "rgb" / "000004.png").write_bytes(b"nor is this")
    with pytest.warns(UserWarning) as caught:
        frames = list(vkmesh.open_dataset(seq))
    assert [f.index for f in frames] == [0, 2, 3, 4, 5]
    messages = [str(w.message) for w in caught]
    assert any(m.startswith("frame 1 skipped: ") and "000001.png" in m for m in messages), messages
    assert any(m.startswith("frame 4 fused without colour: ") for m in messages), messages
    assert frames[3].color is None
    with pytest.raises(vkmesh.Error, match="000001.png"):
        vkmesh.open_dataset(seq)[1]


def test_mesh_files_round_trip(tmp_path):
    r = small_reconstructor()
    depth, k, pose = plane_frame()
    r.integrate(depth, k, pose, color=np.full(depth.shape + (3,), (10, 200, 30), np.uint8))
    m = r.mesh()
    n = len(m.vertices)
    assert n > 100 and m.vertices.dtype == np.float32 and m.vertices.shape == (n, 3)
    assert m.triangles.dtype == np.uint32 and m.triangles.max() < n
    assert m.normals.shape == (n, 3) and np.allclose(np.linalg.norm(m.normals, axis=1), 1, atol=1e-3)
    assert m.colors.dtype == np.uint8 and (m.colors == (10, 200, 30)).all()
    assert m.ages.dtype == np.uint32 and (m.ages == 0).all()
    m.save(tmp_path / "m.ply")
    back = vkmesh.read_mesh(tmp_path / "m.ply")
    for name in ("vertices", "triangles", "normals", "colors", "ages"):
        assert np.array_equal(getattr(back, name), getattr(m, name)), name
    # A mesh built from other arrays (as from Open3D: float64 positions, int32 indices) is converted.
    plain = vkmesh.Mesh(m.vertices.astype(np.float64), m.triangles.astype(np.int32))
    plain.save(tmp_path / "plain.obj")
    obj = (tmp_path / "plain.obj").read_text()
    assert obj.count("\nv ") == n and obj.count("\nf ") == len(m.triangles)
    assert "vertices" in repr(m) and "with normals, colors, ages" in repr(m)
    # Binary glTF reads back equal (normals to float precision: glTF stores them normalised).
    assert m.save(tmp_path / "m.glb") is None
    glb = vkmesh.read_mesh(tmp_path / "m.glb")
    for name in ("vertices", "triangles", "colors", "ages"):
        assert np.array_equal(getattr(glb, name), getattr(m, name)), name
    assert np.allclose(glb.normals, m.normals / np.linalg.norm(m.normals, axis=1, keepdims=True), atol=1e-6)
    # simplify= writes a simplified copy (m is unchanged) and says what it did.
    report = m.save(tmp_path / "half.glb", simplify=0.5)
    half = vkmesh.read_mesh(tmp_path / "half.glb")
    assert report["triangles_before"] == len(m.triangles) and report["triangles_after"] == len(half.triangles)
    assert len(half.triangles) <= len(m.triangles) // 2 and report["error_m"] >= 0
    assert (half.colors == (10, 200, 30)).all() and len(m.vertices) == n
    with pytest.raises(vkmesh.Error, match="1.5"):
        m.save(tmp_path / "bad.glb", simplify=1.5)
    with pytest.raises(vkmesh.Error, match=r"\.glb"):
        m.save(tmp_path / "m.stl")


def test_deltas_replay_to_the_mesh():
    r = small_reconstructor(track_deltas=True)
    vertices, triangles = {}, {}
    kinds = set()
    for step in range(4):
        depth, k, pose = plane_frame(step=4 * step)
        r.integrate(depth, k, pose)
        d = r.deltas()
        assert d.frame == step + 1
        kinds.update(d.vertex_kinds.tolist())
        for i, kind in zip(d.vertex_ids.tolist(), d.vertex_kinds.tolist()):
            if kind == vkmesh.REMOVED:
                vertices.pop(i)
        for i, kind in zip(d.triangle_ids.tolist(), d.triangle_kinds.tolist()):
            if kind == vkmesh.REMOVED:
                triangles.pop(i)
        for i, kind, p in zip(d.vertex_ids.tolist(), d.vertex_kinds.tolist(), d.vertex_positions.tolist()):
            if kind != vkmesh.REMOVED:
                vertices[i] = tuple(p)
        for i, kind, t in zip(d.triangle_ids.tolist(), d.triangle_kinds.tolist(), d.triangle_vertices.tolist()):
            if kind == vkmesh.ADDED:
                triangles[i] = t
    assert {vkmesh.ADDED, vkmesh.CHANGED} <= kinds
    ids = sorted(vertices)
    index = {v: n for n, v in enumerate(ids)}
    replica = vkmesh.Mesh(np.array([vertices[v] for v in ids]), [[index[v] for v in t] for t in triangles.values()])
    assert canonical_triangles(replica) == canonical_triangles(r.mesh())
    assert "frame 4" in repr(d)


def test_stats():
    r = small_reconstructor(color_mode="recent", color_recency=0.5, voxel_size=0.02)
    s = r.stats()
    # Keys are only ever added (the run's statistics, RunStats, add "skipped", "frames_with_color", ...).
    assert "blocks" not in s and s["frames"]["integrated"] == 0 and s["frames"]["skipped"] == 0
    r.integrate(*plane_frame())
    s = r.stats()
    assert s["voxel_size"] == 0.02
    assert {k: s["color"][k] for k in ("fused", "mode", "recency")} == {"fused": True, "mode": "recent", "recency": 0.5}
    assert s["color"]["frames_with_color"] == 0 and s["frames"]["integrated"] == 1
    assert s["blocks"]["in_use"] > 0 and s["heaps"]["live_triangles"] == len(r.mesh().triangles)
    assert s["gpu_bytes_total"] == sum(s["gpu_pool_bytes"].values())
    assert "fuse" in s["last_frame"]["gpu_ms"] and s["last_frame"]["warnings"] == []
    assert "voxel 0.02 m, 1 frames" in repr(r)


def test_threads_share_a_reconstructor_and_the_gil_is_released():
    r = small_reconstructor()
    depth, k, pose = plane_frame()
    # Two threads integrating into one Reconstructor take turns (its mutex): every frame is fused once.
    threads = [threading.Thread(target=lambda: [r.integrate(depth, k, pose) for _ in range(5)]) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert r.frames_integrated == 10
    # While a thread is inside integrate() (here the first frame of a new Reconstructor, which builds the GPU
    # volume and its pipelines: long), this thread keeps running Python.
    fresh = small_reconstructor()
    window = []

    def fuse():
        window.append(time.perf_counter())
        fresh.integrate(depth, k, pose)
        window.append(time.perf_counter())

    t = threading.Thread(target=fuse)
    ticks = []
    t.start()
    while t.is_alive():
        ticks.append(time.perf_counter())
    t.join()
    start, end = window
    inside = [x for x in ticks if start < x < end]
    # Held GIL: at most one switch interval (5 ms) of ticks between the two time stamps.
    assert inside and inside[-1] - inside[0] > 0.5 * (end - start), (end - start, len(inside))


def test_synth_arguments(tmp_path):
    with pytest.raises(ValueError, match="frames 0 must be >= 1"):
        vkmesh.synth(tmp_path / "x", frames=0)
    with pytest.raises(ValueError, match="width 8 must be in"):
        vkmesh.synth(tmp_path / "x", width=8)
    with pytest.raises(ValueError, match="path 'spiral'"):
        vkmesh.synth(tmp_path / "x", path="spiral")
    with pytest.raises(ValueError, match="gt_spacing 0 must be in"):
        vkmesh.synth(tmp_path / "x", gt_spacing=0)


def test_synth_gt_spacing_sets_the_ground_truth_density(tmp_path):
    def points(spacing):
        folder = vkmesh.synth(tmp_path / str(spacing), frames=1, width=16, height=16, gt_spacing=spacing)
        with open(os.path.join(folder, "gt_points.ply"), "rb") as f:
            header = f.read(400).split(b"end_header")[0].decode()
        return int(header.split("element vertex ")[1].split()[0])
    # Uniform by area: half the spacing, about four times the points.
    assert 3.5 < points(0.05) / points(0.1) < 4.5


def test_everything_public_is_documented():
    for name in vkmesh.__all__:
        obj = getattr(vkmesh, name)
        if isinstance(obj, int):
            continue
        assert obj.__doc__ and len(obj.__doc__.strip()) > 40, name
    for method in ("integrate", "mesh", "deltas", "stats", "save", "load", "close"):
        doc = getattr(vkmesh.Reconstructor, method).__doc__
        assert doc and len(doc) > 120, method
    assert "voxel_size" in vkmesh.Reconstructor.__doc__ and "VKMESH_VALIDATION" in vkmesh.Reconstructor.__doc__
