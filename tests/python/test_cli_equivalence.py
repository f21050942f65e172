"""The Python module is the C++ library with numpy in and out: the same frames give `vkmesh fuse`'s mesh, with
the same defaults, and maps pass between the two."""

import json

import numpy as np
import pytest

import vkmesh
from conftest import canonical_triangles, colors_by_position, run_cli


@pytest.fixture(scope="module")
def cli_fused(small_sequence, tmp_path_factory):
    """`vkmesh fuse` with its defaults on the small sequence: the mesh and the --stats JSON."""
    out = tmp_path_factory.mktemp("cli")
    run_cli("fuse", small_sequence, "-o", out / "mesh.ply", "--stats", out / "stats.json", "-q")
    return vkmesh.read_mesh(out / "mesh.ply"), json.loads((out / "stats.json").read_text())


def assert_same_mesh(a: vkmesh.Mesh, b: vkmesh.Mesh):
    assert len(a.vertices) == len(b.vertices)
    assert len(a.triangles) == len(b.triangles)
    assert canonical_triangles(a) == canonical_triangles(b)   # positions bit for bit
    assert sorted(a.ages.tolist()) == sorted(b.ages.tolist())
    assert (a.colors is None) == (b.colors is None)
    if a.colors is not None:
        assert colors_by_position(a) == colors_by_position(b)


def test_defaults_are_the_clis(cli_fused):
    _, stats = cli_fused
    r = vkmesh.Reconstructor()
    mine = r.stats()
    # Float settings are float32 in both; the CLI's JSON prints them as doubles (0.029999999329447746), Python as
    # the shortest decimal that reads back as the same float32 (0.03).
    def same(a, b):
        return np.float32(a) == np.float32(b) if isinstance(a, float) else a == b
    for key in ("voxel_size", "truncation_m", "allocation_stride", "allocation_tiles", "max_depth", "refine", "lock_free"):
        assert same(mine[key], stats[key]), key
    assert mine["color"]["mode"] == stats["color"]["mode"] == "average"
    assert same(mine["color"]["recency"], stats["color"]["recency"])
    for key, value in stats["recycling"].items():
        assert same(mine["recycling"][key], value), key
    for key in ("grow", "blocks", "hash_slots", "touched", "vertices", "triangle_chunks", "retype"):
        assert mine["capacities"][key] == stats["capacities"][key], key


def test_same_frames_give_the_clis_mesh(small_sequence, cli_fused):
    cli_mesh, stats = cli_fused
    assert len(cli_mesh.triangles) > 1000 and cli_mesh.colors is not None
    r = vkmesh.Reconstructor()
    for f in vkmesh.open_dataset(small_sequence):
        r.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
    assert r.frames_integrated == stats["frames"]["integrated"] == 6
    assert_same_mesh(r.mesh(), cli_mesh)
    assert r.stats()["blocks"]["in_use"] == stats["blocks"]["in_use"]


def key_paths(d: dict, prefix=()) -> set:
    """Every key path of a nested dict, lists of records not entered (their keys depend on what happened)."""
    out = set()
    for k, v in d.items():
        out.add(prefix + (k,))
        if isinstance(v, dict):
            out |= key_paths(v, prefix + (k,))
    return out


# What only `vkmesh fuse` knows: the dataset, the mesh file and its analyses, map timings, the trajectory files.
CLI_ONLY = {"dataset", "mesh", "gpu_ms_mesh_export", "wall_ms_mesh_export", "wall_ms_mesh_write", "simplify", "map", "viewer"}


def test_stats_have_the_clis_keys(small_sequence, cli_fused):
    """One RunStats behind both (api/run_stats_json.h): Python's stats() has every key `fuse --stats` writes from the
    library's counts, and the per-frame series agree in length with the frames fused."""
    _, stats = cli_fused
    r = vkmesh.Reconstructor()
    for f in vkmesh.open_dataset(small_sequence):
        r.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
    mine = r.stats()
    wanted = {p for p in key_paths(stats) if p[0] not in CLI_ONLY and p[-1] not in ("trajectory", "trajectory_online",
                                                                                    "dataset_has_color", "mesh_has_color")}
    wanted = {p for p in wanted if p[0] != "frame_store" or p[-1] not in ("path", "file_bytes")}
    missing = sorted(".".join(p) for p in wanted - key_paths(mine))
    assert not missing, missing
    assert mine["frames"]["skipped"] == stats["frames"]["skipped"] == 0
    assert mine["per_frame_counts"]["touched_blocks"].keys() == stats["per_frame_counts"]["touched_blocks"].keys()
    assert mine["color"]["frames_with_color"] == stats["color"]["frames_with_color"] == 6
    assert mine["capacity_events"] == stats["capacity_events"]


def raw_depth(frame) -> np.ndarray:
    """The uint16 values of the frame's PNG, recovered exactly from its metres (raw / depth_scale in float)."""
    return np.round(frame.depth.astype(np.float64) * frame.depth_scale).astype(np.uint16)


def test_map_saved_in_python_continues_in_the_cli(small_sequence, cli_fused, tmp_path):
    cli_mesh, _ = cli_fused
    r = vkmesh.Reconstructor()
    frames = list(vkmesh.open_dataset(small_sequence))
    # The first frames as raw uint16 depth, which the module converts with the dataset reader's own formula: the
    # CLI's continuation below gives its uninterrupted mesh only if the saved state is bit for bit the CLI's.
    for f in frames[:3]:
        r.integrate(raw_depth(f), f.intrinsics, f.pose, depth_scale=f.depth_scale, color=f.color)
    r.save(tmp_path / "first.vkmap")   # before mesh(), as the CLI saves before its export
    first = r.mesh()
    # The CLI continues the map with the remaining frames: the mesh of one uninterrupted run.
    run_cli("fuse", small_sequence, "--load", tmp_path / "first.vkmap", "--first-frame", 3, "-o", tmp_path / "rest.ply", "-q")
    assert_same_mesh(vkmesh.read_mesh(tmp_path / "rest.ply"), cli_mesh)
    # ... and exports the map's mesh as Python saw it.
    run_cli("export", tmp_path / "first.vkmap", "-o", tmp_path / "exported.ply")
    assert_same_mesh(vkmesh.read_mesh(tmp_path / "exported.ply"), first)
    # Python continues it too.
    loaded = vkmesh.Reconstructor.load(tmp_path / "first.vkmap")
    assert loaded.frames_integrated == 3
    assert loaded.stats()["voxel_size"] == 0.03
    for f in frames[3:]:
        loaded.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
    assert_same_mesh(loaded.mesh(), cli_mesh)


def test_paging_keeps_the_mesh_in_python_and_the_cli(small_sequence, cli_fused, tmp_path):
    """resident_blocks / --resident-blocks (docs/PAGING.md): blocks the camera cannot reach wait on the host; the
    mesh is the one fused without paging, and stats() / --stats count what moved."""
    cli_mesh, _ = cli_fused
    r = vkmesh.Reconstructor(resident_blocks=40)
    assert r.stats()["resident_blocks"] == 40
    with pytest.warns(vkmesh.CapacityWarning, match="below what the view needs"):
        for f in vkmesh.open_dataset(small_sequence):
            r.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
    paging = r.stats()["paging"]
    assert paging["resident_blocks"] == 40 and paging["blocks_out"] > 0, paging
    assert_same_mesh(r.mesh(), cli_mesh)
    run_cli("fuse", small_sequence, "-o", tmp_path / "paged.ply", "--stats", tmp_path / "stats.json", "-q", "--resident-blocks", "40")
    assert_same_mesh(vkmesh.read_mesh(tmp_path / "paged.ply"), cli_mesh)
    assert json.loads((tmp_path / "stats.json").read_text())["paging"]["blocks_out"] == paging["blocks_out"]
    with pytest.raises(ValueError, match="resident_blocks"):
        vkmesh.Reconstructor(resident_blocks=-1)
