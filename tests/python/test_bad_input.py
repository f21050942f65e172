"""Bad arguments raise ValueError with vkmesh's own wording before anything reaches the GPU; what vkmesh cannot
do (devices, capacities, files, a closed object) raises vkmesh.Error, a RuntimeError. Nothing crashes."""

import warnings

import numpy as np
import pytest

import vkmesh
from conftest import canonical_triangles, plane_frame, small_reconstructor


@pytest.fixture(scope="module")
def rec():
    """One Reconstructor that has fused a first 64 x 48 frame: later frames must have that size."""
    r = small_reconstructor()
    depth, k, pose = plane_frame()
    r.integrate(depth, k, pose)
    return r


def integrate(r, depth=None, intrinsics=None, pose=None, **kwargs):
    d, k, p = plane_frame()
    r.integrate(d if depth is None else depth, k if intrinsics is None else intrinsics, p if pose is None else pose, **kwargs)


def test_depth_dtype_and_shape(rec):
    depth, _, _ = plane_frame()
    for bad in (depth.astype(np.float64), depth.astype(np.int32), depth.tolist()):
        with pytest.raises(ValueError, match=r"uint16 array .*float32 array .*got dtype (float64|int32)"):
            integrate(rec, depth=bad)
    with pytest.raises(ValueError, match=r"H x W array, got shape \(48, 64, 1\)"):
        integrate(rec, depth=depth[..., None])
    with pytest.raises(ValueError, match=r"shape \(0, 64\)"):
        integrate(rec, depth=np.zeros((0, 64), np.float32))
    with pytest.raises(ValueError, match=r"depth image is 32x48 but the first frame was 64x48"):
        integrate(rec, depth=np.ascontiguousarray(depth[:, :32]))
    frames = rec.frames_integrated
    assert frames >= 1   # none of the above was fused
    integrate(rec)
    assert rec.frames_integrated == frames + 1


def test_depth_values(rec):
    depth, _, _ = plane_frame()
    negative = depth.copy()
    negative[3, 5] = -0.5
    with pytest.raises(ValueError, match=r"depth\[3, 5\] = -0.5.*finite and >= 0"):
        integrate(rec, depth=negative)
    infinite = depth.copy()
    infinite[0, 0] = np.inf
    with pytest.raises(ValueError, match=r"depth\[0, 0\] = inf"):
        integrate(rec, depth=infinite)
    with pytest.raises(ValueError, match=r"depth_scale 0.* must be a positive finite number"):
        integrate(rec, depth=(depth * 5000).astype(np.uint16), depth_scale=0.0)
    # NaN is "no measurement", as 0.
    holes = depth.copy()
    holes[10:20] = np.nan
    integrate(rec, depth=holes)


def test_non_contiguous_depth_is_the_same_as_contiguous():
    # A slice and a Fortran-order array are copied once and give what the C-contiguous array gives.
    depth, k, pose = plane_frame(width=128)
    views = {"contiguous": np.ascontiguousarray(depth[:, ::2]), "slice": depth[:, ::2],
             "fortran": np.asfortranarray(depth[:, ::2])}
    meshes = {}
    for name, d in views.items():
        assert name == "contiguous" or not d.flags.c_contiguous
        r = small_reconstructor()
        r.integrate(d, (51.2, 51.2, 31.5, 23.5), pose)
        meshes[name] = r.mesh()
    assert len(meshes["contiguous"].triangles) > 100
    for name in ("slice", "fortran"):
        assert canonical_triangles(meshes[name]) == canonical_triangles(meshes["contiguous"])


def test_non_rigid_poses_are_refused_with_the_readers_message(rec):
    _, _, pose = plane_frame()
    scaled = pose.copy()
    scaled[:3, :3] *= 1.5
    # The wording of the dataset reader's check (vkmesh::validatePose), which `vkmesh fuse` reports for a bad pose file.
    with pytest.raises(ValueError, match=r"integrate\(\): pose rotation is not orthonormal \(max \|R\^T R - I\| = 1.25\)"):
        integrate(rec, pose=scaled)
    mirrored = np.diag([1.0, 1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match=r"determinant -1 \(a reflection"):
        integrate(rec, pose=mirrored)
    nan = pose.copy()
    nan[0, 3] = np.nan
    with pytest.raises(ValueError, match=r"pose has non-finite entries"):
        integrate(rec, pose=nan)
    bottom = pose.copy()
    bottom[3, 0] = 0.5
    with pytest.raises(ValueError, match=r"pose bottom row is 0.5 0 0 1; expected 0 0 0 1"):
        integrate(rec, pose=bottom)
    with pytest.raises(ValueError, match=r"4x4 camera-to-world matrix, got shape \(3, 4\)"):
        integrate(rec, pose=pose[:3])
    with pytest.raises(ValueError, match=r"pose must be numbers"):
        integrate(rec, pose=np.full((4, 4), "x"))
    integrate(rec, pose=pose.astype(np.float32))   # any real dtype is fine


def test_intrinsics(rec):
    with pytest.raises(ValueError, match=r"intrinsics: fx = 0; it must be non-zero"):
        integrate(rec, intrinsics=(0, 50, 32, 24))
    with pytest.raises(ValueError, match=r"intrinsics: cx = nan is not finite"):
        integrate(rec, intrinsics=(50, 50, float("nan"), 24))
    with pytest.raises(ValueError, match=r"\(fx, fy, cx, cy\) or a 3x3 camera matrix, got shape \(3,\)"):
        integrate(rec, intrinsics=(50, 50, 32))
    with pytest.raises(ValueError, match=r"camera matrix must be \[\[fx, 0, cx\], \[0, fy, cy\], \[0, 0, 1\]\]"):
        integrate(rec, intrinsics=np.array([[51.2, 0.5, 31.5], [0, 51.2, 23.5], [0, 0, 1]]))
    integrate(rec, intrinsics=np.array([[51.2, 0, 31.5], [0, 51.2, 23.5], [0, 0, 1]]))


def test_color(rec):
    depth, _, _ = plane_frame()
    h, w = depth.shape
    with pytest.raises(ValueError, match=r"color image is 32x24 but the depth image is 64x48 \(colour must be registered to depth\)"):
        integrate(rec, color=np.zeros((24, 32, 3), np.uint8))
    with pytest.raises(ValueError, match=r"color must be a uint8 array .* got dtype float32"):
        integrate(rec, color=np.zeros((h, w, 3), np.float32))
    with pytest.raises(ValueError, match=r"H x W x 3 .* got shape \(48, 64, 4\); drop the alpha channel"):
        integrate(rec, color=np.zeros((h, w, 4), np.uint8))
    rgb = np.zeros((h, w * 2, 3), np.uint8)
    rgb[..., 0] = 200
    integrate(rec, color=rgb[:, ::2])   # a non-contiguous view is fine


def test_settings(tmp_path):
    with pytest.raises(ValueError, match=r"voxel size 40.* is outside the supported range"):
        vkmesh.Reconstructor(voxel_size=40)
    with pytest.raises(ValueError, match=r"color_mode 'loud' is not one of 'average', 'recent', 'off'"):
        vkmesh.Reconstructor(color_mode="loud")
    with pytest.raises(ValueError, match=r"block_capacity = -1 must be in \[0, 2\^32\)"):
        vkmesh.Reconstructor(block_capacity=-1)
    with pytest.raises(ValueError, match=r"hash capacity 1000 must be a power of two"):
        vkmesh.Reconstructor(hash_capacity=1000)
    with pytest.raises(ValueError, match=r"colour recency 0(\.0+)? must be in \(0, 1\]"):
        vkmesh.Reconstructor(color_mode="recent", color_recency=0)
    with pytest.raises(TypeError):
        vkmesh.Reconstructor(0.02)   # settings are keywords
    with pytest.raises(ValueError, match=r"device must be None .* got 'gpu'"):
        vkmesh.Reconstructor(device="gpu")
    with pytest.raises(vkmesh.Error, match=r"--device 99 does not exist"):
        vkmesh.Reconstructor(device=99)
    assert issubclass(vkmesh.Error, RuntimeError)


def test_capacity_problems():
    # More blocks than one storage buffer can hold: a RuntimeError naming the setting, raised by the first frame
    # (when the volume is created), and the object stays usable.
    r = vkmesh.Reconstructor(block_capacity=1 << 30)
    depth, k, pose = plane_frame()
    with pytest.raises(RuntimeError, match=r"blockCapacity|--blocks"):
        r.integrate(depth, k, pose)
    # Fixed capacities: what does not fit is skipped and reported as a CapacityWarning.
    r = small_reconstructor(vertex_capacity=64, grow_capacities=False)
    with pytest.warns(vkmesh.CapacityWarning, match=r"frame 1: .*vertex heap exhausted"):
        r.integrate(depth, k, pose)
    depth, k, pose = plane_frame(distance=1.2, step=10)   # more surface: the heap is still full
    with warnings.catch_warnings():
        warnings.simplefilter("error", vkmesh.CapacityWarning)
        with pytest.raises(vkmesh.CapacityWarning):
            r.integrate(depth, k, pose)


def test_objects_in_the_wrong_state(tmp_path):
    r = small_reconstructor()
    with pytest.raises(vkmesh.Error, match=r"cannot save .* no frame has been integrated yet"):
        r.save(tmp_path / "x.vkmap")
    assert len(r.mesh().vertices) == 0
    with pytest.raises(vkmesh.Error, match=r"track_deltas=True"):
        r.deltas()
    with r:
        pass
    assert r.closed
    with pytest.raises(vkmesh.Error, match=r"closed"):
        r.integrate(*plane_frame())
    with pytest.raises(vkmesh.Error, match=r"closed"):
        r.mesh()
    assert "closed" in repr(r)
    (tmp_path / "garbage.vkmap").write_bytes(b"not a map at all, just some bytes")
    with pytest.raises(vkmesh.Error, match=r"garbage.vkmap: not a vkmesh map"):
        vkmesh.Reconstructor.load(tmp_path / "garbage.vkmap")
    with pytest.raises(vkmesh.Error, match=r"does not exist"):
        vkmesh.open_dataset(tmp_path / "nowhere")
    with pytest.raises(vkmesh.Error, match=r"nothing.ply"):
        vkmesh.read_mesh(tmp_path / "nothing.ply")


def test_mesh_arguments():
    with pytest.raises(ValueError, match=r"N x 3"):
        vkmesh.Mesh(np.zeros((4, 2)), [[0, 1, 2]])
    with pytest.raises(ValueError, match=r"triangles index vertices 0..7 but there are 4 vertices"):
        vkmesh.Mesh(np.zeros((4, 3)), [[0, 1, 7]])
    with pytest.raises(ValueError, match=r"colors must be uint8"):
        vkmesh.Mesh(np.zeros((3, 3)), [[0, 1, 2]], colors=np.ones((3, 3)))
    with pytest.raises(ValueError, match=r"normals must be 3 x 3"):
        vkmesh.Mesh(np.zeros((3, 3)), [[0, 1, 2]], normals=np.ones((2, 3)))
