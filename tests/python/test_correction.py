"""Correcting a map from Python (docs/CORRECTION.md): frames fused at drifted poses and re-fused at the true ones
with correct() give the mesh of a reconstruction fused at the true poses from the start; corrections spread over
later frames by the per-frame budget; the deltas follow; bad input is a clear error and changes nothing."""

import numpy as np
import pytest

import vkmesh
from conftest import canonical_triangles


def drift(pose: np.ndarray, i: int) -> np.ndarray:
    """Frame i's pose turned by i x 0.5 degrees about y and moved by i x 1 cm: a slow drift, as a tracker's."""
    a = np.radians(0.5 * i)
    d = np.eye(4)
    d[:3, :3] = [[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]
    d[:3, 3] = [0.01 * i, 0.0, -0.005 * i]
    return d @ pose


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    folder = vkmesh.synth(tmp_path_factory.mktemp("correct") / "room", frames=24, width=160, height=120, gt_spacing=0.05)
    return list(vkmesh.open_dataset(folder, frames=8))


def reconstructor(**options):
    return vkmesh.Reconstructor(voxel_size=0.04, color_mode="off", keep_frames=True, **options)


def test_corrected_map_equals_the_true_one(frames):
    truth = vkmesh.Reconstructor(voxel_size=0.04, color_mode="off")
    for f in frames:
        truth.integrate(f.depth, f.intrinsics, f.pose)
    r = reconstructor(track_deltas=True)
    for i, f in enumerate(frames):
        r.integrate(f.depth, f.intrinsics, drift(f.pose, i))
    assert canonical_triangles(r.mesh()) != canonical_triangles(truth.mesh())

    r.correct(np.arange(len(frames)), np.stack([f.pose for f in frames]))
    assert r.pending_corrections() == len(frames) - 1, "frame 0 did not move"
    report = r.finish_corrections()
    assert report["frames_refused"] == len(frames) - 1
    assert report["frames"][0] == len(frames) - 1, "the largest pose change first"
    assert report["observations_dropped"] == 0
    assert r.pending_corrections() == 0
    assert canonical_triangles(r.mesh()) == canonical_triangles(truth.mesh())
    np.testing.assert_array_equal(r.trajectory(), np.stack([f.pose for f in frames]))
    assert r.deltas().vertex_ids.size > 0, "the correction's mesh changes reach the deltas"


def test_corrections_spread_over_later_frames(frames):
    r = reconstructor(corrections_per_frame=2)
    for i, f in enumerate(frames[:6]):
        r.integrate(f.depth, f.intrinsics, drift(f.pose, i))
    r.correct(np.arange(1, 6), np.stack([f.pose for f in frames[1:6]]))
    assert r.pending_corrections() == 5
    r.integrate(frames[6].depth, frames[6].intrinsics, frames[6].pose)
    assert r.last_corrections()["frames_refused"] == 2
    assert r.pending_corrections() == 3
    r.integrate(frames[7].depth, frames[7].intrinsics, frames[7].pose)
    assert r.pending_corrections() == 1
    r.finish_corrections()
    truth = vkmesh.Reconstructor(voxel_size=0.04, color_mode="off")
    for f in frames:
        truth.integrate(f.depth, f.intrinsics, f.pose)
    assert canonical_triangles(r.mesh()) == canonical_triangles(truth.mesh())


def test_bad_corrections_are_refused_and_change_nothing(frames, tmp_path):
    r = reconstructor()
    for f in frames[:3]:
        r.integrate(f.depth, f.intrinsics, f.pose)
    before = canonical_triangles(r.mesh())
    bad = frames[1].pose.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="frame 1"):
        r.correct([0, 1], np.stack([frames[0].pose, bad]))
    with pytest.raises(vkmesh.Error, match="frame 7 is not in the frame store"):
        r.correct([7], frames[0].pose[None])
    with pytest.raises(ValueError, match="N x 4 x 4"):
        r.correct([0, 1], frames[0].pose[None])
    assert r.pending_corrections() == 0
    r.finish_corrections()
    assert canonical_triangles(r.mesh()) == before
    with pytest.raises(vkmesh.Error, match="keep_frames"):
        vkmesh.Reconstructor(voxel_size=0.04).correct([0], frames[0].pose[None])

    # Saved with its frames and loaded again: the loaded map's frames can be corrected.
    r.save(tmp_path / "map.vkmap")
    assert (tmp_path / "map.vkframes").exists()
    loaded = vkmesh.Reconstructor.load(tmp_path / "map.vkmap", keep_frames=True)
    loaded.correct([2], drift(frames[2].pose, 3)[None])
    assert loaded.finish_corrections()["frames_refused"] == 1
    (tmp_path / "map.vkframes").unlink()
    with pytest.raises(vkmesh.Error, match="map.vkframes"):
        vkmesh.Reconstructor.load(tmp_path / "map.vkmap", keep_frames=True)
