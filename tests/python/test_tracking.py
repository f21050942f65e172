"""Camera tracking from Python (docs/TRACKING.md): integrate() without a pose tracks the camera against the mesh,
returns what tracking did, and trajectory() gives every frame's pose."""

import os
import shutil

import numpy as np
import pytest

import vkmesh


@pytest.fixture(scope="module")
def orbit_room(tmp_path_factory):
    """240 frames to the orbit: about 3.6 cm and 1.5 degrees between neighbours; the tests use the first 10 at most.
    Rendered once for the module's tests (~7 s each time)."""
    return vkmesh.synth(tmp_path_factory.mktemp("orbit") / "room", frames=240, width=160, height=120, gt_spacing=0.05)


def test_integrate_without_a_pose_tracks_the_camera(orbit_room):
    folder = orbit_room
    frames = list(vkmesh.open_dataset(folder, frames=10))
    r = vkmesh.Reconstructor(voxel_size=0.03)
    results = [r.integrate(f.depth, f.intrinsics, color=f.color) for f in frames]
    assert all(res["tracked"] for res in results), [res["lost_reason"] for res in results]
    assert set(results[1]) >= {"pose", "tracked", "lost_reason", "iterations", "inliers", "valid_pixels", "rmse", "ms"}
    assert results[1]["iterations"] > 0 and results[1]["inliers"] > 1000
    trajectory = r.trajectory()
    assert trajectory.shape == (10, 4, 4)
    np.testing.assert_array_equal(trajectory[0], np.eye(4))   # the first frame is fused at the identity
    # The tracked poses relative to the first equal the true ones relative to the first.
    first = np.linalg.inv(frames[0].pose)
    for i, f in enumerate(frames):
        truth = first @ f.pose
        np.testing.assert_array_equal(trajectory[i], results[i]["pose"])
        assert np.linalg.norm(trajectory[i][:3, 3] - truth[:3, 3]) < 0.01, i

    # A frame without depth is lost: not fused, the pose predicted, and tracking picks up afterwards.
    integrated = r.frames_integrated
    lost = r.integrate(np.zeros_like(frames[0].depth), frames[0].intrinsics)
    assert not lost["tracked"] and "depth" in lost["lost_reason"]
    assert r.frames_integrated == integrated
    again = r.integrate(frames[-1].depth, frames[-1].intrinsics)
    assert again["tracked"], again["lost_reason"]


def test_tracking_with_the_systems_solved_on_the_gpu(orbit_room):
    folder = orbit_room
    frames = list(vkmesh.open_dataset(folder, frames=6))
    r = vkmesh.Reconstructor(voxel_size=0.03, track_solve="gpu", track_color_weight=0)
    settings = {"color_weight": 0.0, "solve": "gpu", "downsample": 0, "model_reuse": 2}   # 0: by width
    tracking = r.stats()["tracking"]
    assert {k: tracking[k] for k in settings} == settings
    assert tracking["enabled"] is False   # the run's statistics (RunStats): no frame tracked yet
    results = [r.integrate(f.depth, f.intrinsics) for f in frames]
    tracking = r.stats()["tracking"]
    assert tracking["enabled"] is True and tracking["frames_tracked"] + tracking["lost_frames"] == len(frames) - 1
    assert all(res["tracked"] for res in results[1:]), [res["lost_reason"] for res in results]
    assert any(not res["model_drawn"] for res in results[1:]), "the model maps reused (track_model_reuse=2)"
    first = np.linalg.inv(frames[0].pose)
    for i, f in enumerate(frames):
        assert np.linalg.norm(r.trajectory()[i][:3, 3] - (first @ f.pose)[:3, 3]) < 0.01, i
    # Tracked and fused in one submission: a frame without depth is lost on the GPU and not fused.
    integrated = r.frames_integrated
    lost = r.integrate(np.zeros_like(frames[0].depth), frames[0].intrinsics)
    assert not lost["tracked"] and "depth" in lost["lost_reason"]
    assert r.frames_integrated == integrated
    assert r.integrate(frames[-1].depth, frames[-1].intrinsics)["tracked"]
    assert r.frames_integrated == integrated + 1
    with pytest.raises(ValueError, match="track_solve"):
        vkmesh.Reconstructor(track_solve="cpu")
    with pytest.raises(ValueError, match="track_color_weight"):
        vkmesh.Reconstructor(track_color_weight=-1)
    with pytest.raises(ValueError, match="track_downsample"):
        vkmesh.Reconstructor(track_downsample=3)
    with pytest.raises(ValueError, match="track_model_reuse"):
        vkmesh.Reconstructor(track_model_reuse=-1)


def test_integrate_with_a_pose_returns_none_and_is_in_the_trajectory(small_sequence):
    frames = list(vkmesh.open_dataset(small_sequence, frames=2))
    r = vkmesh.Reconstructor(voxel_size=0.04)
    for f in frames:
        assert r.integrate(f.depth, f.intrinsics, f.pose) is None
    np.testing.assert_allclose(r.trajectory(), np.stack([f.pose for f in frames]))


def test_a_sequence_without_poses_opens_for_tracking(orbit_room, tmp_path):
    folder = shutil.copytree(orbit_room, tmp_path / "room")   # a copy: its ground truth is removed below
    truth = [f.pose for f in vkmesh.open_dataset(folder, frames=6)]
    os.remove(os.path.join(folder, "groundtruth.txt"))
    with pytest.raises(vkmesh.Error, match="--track"):
        vkmesh.open_dataset(folder)
    frames = list(vkmesh.open_dataset(folder, frames=6, require_poses=False))
    assert len(frames) == 6 and all(f.pose is None for f in frames)
    r = vkmesh.Reconstructor(voxel_size=0.03)
    results = [r.integrate(f.depth, f.intrinsics, f.pose, color=f.color) for f in frames]
    assert all(res["tracked"] for res in results), [res["lost_reason"] for res in results]
    first = np.linalg.inv(truth[0])
    for tracked, true in zip(r.trajectory(), truth):
        assert np.linalg.norm(tracked[:3, 3] - (first @ true)[:3, 3]) < 0.01


def test_loop_closure_relocalises_a_kidnapped_camera(tmp_path):
    # Three laps of the room (60 frames each); the camera jumps from frame 55 of lap 1 to frame 72 of lap 2, a view
    # lap 1 saw: tracking from the prediction loses it, a keyframe's pose finds it again (docs/LOOP_CLOSURE.md).
    folder = vkmesh.synth(tmp_path / "room", frames=180, width=320, height=240, noise=True, path="revisit", gt_spacing=0.05)
    frames = list(vkmesh.open_dataset(folder, frames=80))
    with pytest.raises(ValueError, match="keep_frames"):
        vkmesh.Reconstructor(voxel_size=0.03, loop_closure=True)
    r = vkmesh.Reconstructor(voxel_size=0.03, keep_frames=True, loop_closure=True)
    used = frames[:56] + frames[72:80]
    results = [r.integrate(f.depth, f.intrinsics, color=f.color, pose=None) for f in used]
    assert {"relocalised", "relocalisation_candidates_tried", "loop_corrections"} <= set(results[1])
    after = results[56:]
    found = [i for i, res in enumerate(after) if res["relocalised"]]
    assert found and found[0] < 5, [(res["tracked"], res["lost_reason"]) for res in after]
    pose = r.trajectory()[56 + found[0]]
    truth = np.linalg.inv(frames[0].pose) @ used[56 + found[0]].pose   # the first frame is fused at the identity
    assert np.linalg.norm(pose[:3, 3] - truth[:3, 3]) < 0.05
    stats = r.stats()["loop_closure"]
    assert stats["enabled"] and stats["relocalisations"] >= 1 and stats["keyframes"] > 10
    assert vkmesh.Reconstructor(voxel_size=0.03).stats()["loop_closure"] == {"enabled": False}
