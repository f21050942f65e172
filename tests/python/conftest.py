"""Shared fixtures of the Python suite (run by ctest, label `python`: tests/CMakeLists.txt puts build/python on
PYTHONPATH and names the CLI in VKMESH_CLI). With VKMESH_VALIDATION=1 (scripts/test.sh) every Reconstructor runs
with the Khronos validation layer, and a test fails on any message it produced, as the C++ tests do."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import vkmesh


def assert_no_validation_messages(when: str):
    messages = vkmesh.validation_messages()
    assert not messages, f"{len(messages)} validation messages {when}, first: {messages[0]}"


@pytest.fixture(autouse=True)
def no_validation_messages():
    assert_no_validation_messages("before the test (from the fixtures it uses)")
    yield
    assert_no_validation_messages("during the test")


def cli_path() -> Path:
    """The vkmesh CLI of the same build: $VKMESH_CLI, else <build>/vkmesh next to <build>/python/vkmesh."""
    if os.environ.get("VKMESH_CLI"):
        return Path(os.environ["VKMESH_CLI"])
    return Path(vkmesh.__file__).resolve().parents[2] / "vkmesh"


def run_cli(*args) -> subprocess.CompletedProcess:
    """Runs the CLI; fails the test on a non-zero exit or a validation message on its stderr."""
    result = subprocess.run([str(cli_path()), *map(str, args)], capture_output=True, text=True)
    assert result.returncode == 0, f"vkmesh {' '.join(map(str, args))} failed ({result.returncode}):\n{result.stderr}"
    assert "[validation" not in result.stderr, result.stderr
    return result


@pytest.fixture(scope="session")
def small_sequence(tmp_path_factory) -> Path:
    """6 frames of the synthetic room at 160 x 120 with colour, written by vkmesh.synth (as `vkmesh synth`)."""
    folder = tmp_path_factory.mktemp("seq") / "room"
    vkmesh.synth(folder, frames=6, width=160, height=120, gt_spacing=0.05)
    return folder


def canonical_triangles(mesh: vkmesh.Mesh) -> list:
    """The mesh as a sorted list of triangles, each the 3 positions starting at the smallest (the rotation
    keeps the orientation): equal lists mean the same triangles, bit for bit, whatever the vertex order."""
    out = []
    for a, b, c in mesh.vertices[mesh.triangles].tolist():
        a, b, c = tuple(a), tuple(b), tuple(c)
        out.append(min((a, b, c), (b, c, a), (c, a, b)))
    out.sort()
    return out


def colors_by_position(mesh: vkmesh.Mesh) -> dict:
    return {tuple(p): tuple(c) for p, c in zip(mesh.vertices.tolist(), mesh.colors.tolist())}


# Small initial capacities (they grow when needed): quick to create on lavapipe; Reconstructor.load takes them too.
SMALL_CAPACITIES = dict(block_capacity=256, vertex_capacity=1 << 14, chunk_capacity=1 << 13)


def small_reconstructor(**kwargs) -> vkmesh.Reconstructor:
    """A Reconstructor with small capacities (SMALL_CAPACITIES): quick to create on lavapipe. The retype list
    keeps its default: a smaller one defers cubes to later frames, and which ones wait depends on the GPU's order."""
    options = dict(SMALL_CAPACITIES)
    options.update(kwargs)
    return vkmesh.Reconstructor(**options)


def plane_frame(width=64, height=48, distance=1.5, step=0):
    """A depth image of a slanted plane in front of the camera (float32 metres), its intrinsics and a pose that
    moves a little with `step`: something to fuse without a dataset."""
    fx = fy = 0.8 * width
    cx, cy = (width - 1) / 2, (height - 1) / 2
    x = np.arange(width, dtype=np.float32)
    depth = np.tile(distance + 0.3 * (x - cx) / width, (height, 1)).astype(np.float32)
    pose = np.eye(4)
    pose[0, 3] = 0.01 * (step % 20)
    return depth, (fx, fy, cx, cy), pose
