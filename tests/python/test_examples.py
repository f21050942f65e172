"""The examples in examples/python run (the Open3D one only where python3-open3d is installed)."""

import subprocess
import sys
from pathlib import Path

import pytest

import vkmesh

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "python"


def run_example(name, *args):
    result = subprocess.run([sys.executable, str(EXAMPLES / name), *map(str, args)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "[validation" not in result.stderr, result.stderr
    return result


def test_fuse_dataset_writes_a_coloured_ply(small_sequence, tmp_path):
    result = run_example("fuse_dataset.py", small_sequence, "-o", tmp_path / "mesh.ply", "--frames", 2, "--voxel", 0.05)
    mesh = vkmesh.read_mesh(tmp_path / "mesh.ply")
    assert len(mesh.triangles) > 500 and mesh.colors is not None
    assert "2 frames" in result.stdout and "with colour" in result.stdout
    assert "2/2" in result.stderr   # the progress line (tqdm's or the plain one)


def test_open3d_round_trip(small_sequence, tmp_path):
    pytest.importorskip("open3d")
    result = run_example("open3d_interop.py", small_sequence, "-o", tmp_path / "o3d.ply", "--frames", 2, "--voxel", 0.05)
    mesh = vkmesh.read_mesh(tmp_path / "o3d.ply")
    assert len(mesh.triangles) > 500 and mesh.colors is not None and mesh.normals is not None
    assert "Open3D wrote" in result.stdout
