"""Sessions of one place from Python (vkmesh.merge_maps(register=True), `vkmesh merge --register`; docs/SCALING.md):
two maps saved in world frames of their own are registered by their kept frames and joined where they belong. The
real-data case (ICL-NUIM, two sessions from different images) is tests/gpu/test_sessions.cpp; here the synthetic
room checks what Python gets: the transform, the pairs, the joined map and its frames, and the refusals."""

import json
import subprocess

import numpy as np
import pytest

import vkmesh
from conftest import cli_path, small_reconstructor

VOXEL = 0.04


def turned(degrees, t):
    a = np.radians(degrees)
    m = np.eye(4)
    m[:3, :3] = [[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]]
    m[:3, 3] = t
    return m


@pytest.fixture(scope="module")
def sessions(tmp_path_factory):
    """Frames 0-11 of the room at their poses, and frames 10-23 in a world turned 30 degrees and moved 1.1 m."""
    folder = tmp_path_factory.mktemp("sessions")
    frames = list(vkmesh.open_dataset(vkmesh.synth(folder / "room", frames=24, width=160, height=120, gt_spacing=0.05)))
    elsewhere = turned(30, [1.0, -0.5, 0.2])
    paths = []
    for name, part, world in (("first", frames[:12], np.eye(4)), ("second", frames[10:], elsewhere)):
        with small_reconstructor(voxel_size=VOXEL, keep_frames=True) as r:
            for f in part:
                r.integrate(f.depth, f.intrinsics, world @ f.pose, color=f.color)
            paths.append(folder / f"{name}.vkmap")
            r.save(paths[-1])
    return paths, elsewhere, len(frames) + 2


def test_sessions_are_joined_where_they_belong(sessions, tmp_path):
    paths, elsewhere, frames = sessions
    with pytest.warns(UserWarning, match="share a timestamp"):   # both sessions number their frames from 0
        stats = vkmesh.merge_maps(paths, tmp_path / "both.vkmap", mesh=tmp_path / "both.ply", register=True)
    (session,) = stats["registration"]["sessions"]
    error = np.array(session["transform"]).reshape(4, 4) @ elsewhere   # the identity when the transform is right
    assert np.linalg.norm(error[:3, 3]) < 0.005
    assert np.degrees(np.arccos(np.clip((np.trace(error[:3, :3]) - 1) / 2, -1, 1))) < 0.3
    assert session["pairs_agreeing"] >= 3 and session["pairs_agreeing"] <= session["pairs_verified"] <= session["pairs_registered"]
    assert sum(p["agrees"] for p in session["pairs"]) == session["pairs_agreeing"]
    assert stats["registration"]["frames_moved"] == 14
    assert stats["frames_integrated"] == frames and stats["frame_store"]["frames"] == frames
    assert not list(tmp_path.glob("*.session*")), "the moved session is not left behind"
    with vkmesh.Reconstructor.load(tmp_path / "both.vkmap") as r:
        assert len(r.mesh().triangles) == len(vkmesh.read_mesh(tmp_path / "both.ply").triangles) > 1000

    # The CLI gives the same transform (the same stores, the same keyframes and pairs: deterministic).
    run = subprocess.run([str(cli_path()), "merge", *map(str, paths), "--register", "-o", str(tmp_path / "cli.vkmap"), "--stats",
                          str(tmp_path / "cli.json")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    cli = json.loads((tmp_path / "cli.json").read_text())["registration"]["sessions"][0]
    assert cli["transform"] == session["transform"]


def test_a_map_cannot_join_alone_or_without_its_frames(sessions, tmp_path):
    paths, _, _ = sessions
    with pytest.raises(ValueError, match="two maps or more"):
        vkmesh.merge_maps(paths[:1], tmp_path / "x.vkmap", register=True)
    with small_reconstructor(voxel_size=VOXEL) as r:   # no keep_frames: no frame store beside it
        f = next(iter(vkmesh.open_dataset(paths[0].parent / "room", frames=1)))
        r.integrate(f.depth, f.intrinsics, f.pose)
        r.save(tmp_path / "bare.vkmap")
    with pytest.raises(vkmesh.Error, match="bare.vkmap has no frame store"):
        vkmesh.merge_maps([paths[0], tmp_path / "bare.vkmap"], tmp_path / "x.vkmap", register=True)
    assert not (tmp_path / "x.vkmap").exists()
