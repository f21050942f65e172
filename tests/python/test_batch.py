"""Batch reconstruction on Dask (python3 -m vkmesh.batch; docs/SCALING.md): a sequence cut into fragments, fused on a
LocalCluster of 2 worker processes and merged, is the map of one run over every frame (given poses), even when a
worker dies in the middle of a fragment (the task runs again, one retry reported); with --track, fragments of a real
recording placed through the frames they share track about as well as one run."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import vkmesh
from conftest import canonical_triangles

distributed = pytest.importorskip("distributed", reason="python3-distributed (Dask) is not installed")

VOXEL = 0.04


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    return vkmesh.synth(tmp_path_factory.mktemp("batch") / "room", frames=9, width=160, height=120, noise=True,
                        gt_spacing=0.05)


def batch(*args, env=None):
    """python3 -m vkmesh.batch in its own process, as users run it (its workers are processes of their own too).
    Without the validation layer: the workers' messages would reach no check (they run the stages the C++ and Python
    suites validate), and it doubled this file's time in CI."""
    env = {**{k: v for k, v in os.environ.items() if k != "VKMESH_VALIDATION"}, **(env or {})}
    return subprocess.run([sys.executable, "-m", "vkmesh.batch", *map(str, args)], capture_output=True, text=True,
                          env=env, timeout=600)


def vertex_bits(mesh):
    return sorted(map(tuple, np.asarray(mesh.vertices).view(np.uint32)))


def test_fragments_on_two_workers_are_the_one_run_map_even_when_a_worker_dies(room, tmp_path):
    frames = list(vkmesh.open_dataset(room, frames=9))
    with vkmesh.Reconstructor(voxel_size=VOXEL) as one:
        for f in frames:
            one.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
        truth = one.mesh()
    marker = tmp_path / "killed"
    r = batch(room, "--frames", 9, "--fragment-frames", 3, "--local-workers", 2, "--voxel", VOXEL, "-o", tmp_path / "b.vkmap",
              "--mesh", tmp_path / "b.ply", "--stats", tmp_path / "s.json", env={"VKMESH_BATCH_KILL_ONCE": str(marker)})
    assert r.returncode == 0, r.stderr
    assert marker.exists(), "the worker fusing fragment 1 was killed in its middle"
    stats = json.loads((tmp_path / "s.json").read_text())
    assert stats["retries"] == 1, "the killed fragment ran again, once"
    assert [f["frames"] for f in stats["fragments"]] == [[0, 3], [3, 6], [6, 9]]
    assert stats["frames_integrated"] == 9
    assert set(stats["ms"]) >= {"fuse_ms", "place_ms", "refuse_ms", "merge_ms", "total_ms"}
    assert len(stats["per_worker"]) >= 2, "both workers took tasks"
    assert "fragment 3/3" in r.stderr and "merge 1/1" in r.stderr, "progress is shown"
    mesh = vkmesh.read_mesh(tmp_path / "b.ply")
    assert canonical_triangles(mesh) == canonical_triangles(truth)
    assert vertex_bits(mesh) == vertex_bits(truth), "vertex positions bit for bit"
    assert not (tmp_path / "b.vkmap.batch").exists(), "the work folder is removed after a run"
    with vkmesh.Reconstructor.load(tmp_path / "b.vkmap") as loaded:
        assert loaded.frames_integrated == 9


def shared_dataset(name):
    root = os.environ.get("VKMESH_DATASETS") or os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "datasets")
    path = os.path.join(root, name)
    if not os.path.isdir(path):
        pytest.skip(f"{name} is not in {root} (set VKMESH_DATASETS)")
    return path


def test_tracked_fragments_of_a_real_recording_track_about_as_well_as_one_run(tmp_path):
    """TUM fr1/rpy's first 80 frames (real Kinect data) in 4 tracked fragments, placed through the 10 frames each shares with the one before:
    the global trajectory's error against the recording's poses is at most 1.25 x that of one tracked run."""
    tum, n = shared_dataset("tum_fr1_rpy"), 80
    frames = list(vkmesh.open_dataset(tum, frames=n))
    with vkmesh.Reconstructor() as one:
        for i, f in enumerate(frames):
            one.integrate(f.depth, f.intrinsics, f.pose if i == 0 else None, color=f.color)
        one_poses = one.trajectory()
    r = batch(tum, "--frames", n, "--fragment-frames", 20, "--overlap", 10, "--track", "--local-workers", 2,
              "-o", tmp_path / "t.vkmap", "--trajectory", tmp_path / "t.txt", "--stats", tmp_path / "s.json", "-q")
    assert r.returncode == 0, r.stderr
    stats = json.loads((tmp_path / "s.json").read_text())
    assert stats["frames_integrated"] == n, "every frame once: the shared frames are fused again only where they belong"
    assert [p["overlap"]["frames"] for p in stats["placements"][1:]] == [10, 10, 10]
    truth = np.stack([f.pose for f in frames])
    lines = [l.split() for l in (tmp_path / "t.txt").read_text().splitlines() if not l.startswith("#")]
    assert [float(l[0]) for l in lines] == pytest.approx([f.timestamp for f in frames], abs=1e-6)
    batch_positions = np.array([[float(x) for x in l[1:4]] for l in lines])

    def ate(positions):
        """TUM's absolute trajectory error: RMSE of the positions after the rigid motion that fits them best to the
        truth (Horn's method, as bench/ate.py)."""
        want = truth[:, :3, 3]
        a, b = positions - positions.mean(axis=0), want - want.mean(axis=0)
        u, _, vt = np.linalg.svd(a.T @ b)
        d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
        r = (u @ d @ vt).T
        aligned = (r @ a.T).T + want.mean(axis=0)
        return float(np.sqrt(np.mean(np.sum((aligned - want) ** 2, axis=1))))

    one_ate, batch_ate = ate(one_poses[:, :3, 3]), ate(batch_positions)
    print(f"ATE against the recording's poses: one run {one_ate:.4f} m, 4 fragments {batch_ate:.4f} m")
    assert one_ate < 0.05
    assert batch_ate <= 1.25 * one_ate, f"batch ATE {batch_ate:.4f} m, one run {one_ate:.4f} m"


def test_bad_options_are_clear_errors(room, tmp_path):
    r = batch(room, "--track", "--overlap", 0, "-o", tmp_path / "x.vkmap")
    assert r.returncode == 2 and "--overlap" in r.stderr
    r = batch(room, "-o", tmp_path / "x.ply")
    assert r.returncode == 2 and "--mesh" in r.stderr
    r = batch(room, "--loop-closure", "-o", tmp_path / "x.vkmap")
    assert r.returncode == 2 and "--loop-closure" in r.stderr
    assert not (tmp_path / "x.vkmap").exists()
