"""Merging saved maps from Python (vkmesh.merge_maps, `vkmesh merge`; docs/PYTHON.md, docs/SCALING.md): two maps fused
from the two halves of a sequence add up to the map of one run over every frame, mesh and frame store included, and
the merged map loads and corrects like any other; maps with other settings are refused and nothing is written."""

import numpy as np
import pytest

import vkmesh
from conftest import SMALL_CAPACITIES, canonical_triangles, small_reconstructor

VOXEL = 0.04


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    folder = vkmesh.synth(tmp_path_factory.mktemp("merge") / "room", frames=24, width=160, height=120, gt_spacing=0.05)
    return list(vkmesh.open_dataset(folder, frames=8))


def fused(frames, **options):
    r = small_reconstructor(**{"voxel_size": VOXEL, **options})
    for f in frames:
        r.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
    return r


@pytest.fixture(scope="module")
def parts(frames, tmp_path_factory):
    """The one-run mesh over all 8 frames, and maps of frames [0, 4) and [4, 8) saved with their frame stores."""
    folder = tmp_path_factory.mktemp("parts")
    with fused(frames) as whole:
        truth = canonical_triangles(whole.mesh())
    paths = []
    for name, part in (("a", frames[:4]), ("b", frames[4:])):
        with fused(part, keep_frames=True) as r:
            paths.append(folder / f"{name}.vkmap")
            r.save(paths[-1])
            # A Reconstructor numbers its frames 0, 1, ... in integration order: both parts hold 0..3 (so the merge
            # must renumber). Correcting a frame to the pose it has queues nothing; a frame not kept is refused.
            r.correct(np.arange(4), np.stack([f.pose for f in part]))
            assert r.pending_corrections() == 0
            with pytest.raises(vkmesh.Error, match="frame 4 is not in the frame store"):
                r.correct([4], part[0].pose[None])
    assert all(p.exists() and p.with_suffix(".vkframes").exists() for p in paths)
    return truth, paths


def test_merged_map_equals_one_run(frames, parts, tmp_path, capfd):
    truth, paths = parts
    out = tmp_path / "ab.vkmap"
    # A Reconstructor's kept frames have their index as timestamp: the parts' timestamps collide too, which matters to
    # `vkmesh correct` (it matches trajectory lines by timestamp), not to correct() here (by index). A warning says so.
    with pytest.warns(UserWarning, match="4 kept frames share a timestamp"):
        stats = vkmesh.merge_maps(paths, out, mesh=tmp_path / "ab.ply")
    assert "[validation" not in capfd.readouterr().err, "the merge's own device reports to stderr only"
    assert stats["output"] == str(out) and out.exists()
    assert stats["frames_integrated"] == 8
    assert [(i["frames_integrated"], i["frame_store"], i["frames_stored"]) for i in stats["inputs"]] == [(4, True, 4)] * 2
    assert stats["frame_store"]["frames"] == 8
    assert stats["frame_store"]["renumbered"] is True, "both parts hold frames 0..3"
    assert stats["frame_store"]["path"] == str(out.with_suffix(".vkframes")) and out.with_suffix(".vkframes").exists()
    assert stats["blocks"]["shared"] > 0, "the halves overlap: the test adds TSDF sums, not just unites blocks"
    assert len(stats["warnings"]) == 1
    assert set(stats["ms"]) == {"read", "merge", "rebuild", "save", "tiles"}
    assert stats["tiles"]["count"] == 0, "no tiles asked for"
    assert stats["mesh"]["path"] == str(tmp_path / "ab.ply")
    mesh = vkmesh.read_mesh(tmp_path / "ab.ply")
    assert stats["mesh"]["triangles"] == len(mesh.triangles) == len(truth)
    assert canonical_triangles(mesh) == truth

    # The merged map loads with its frames: the same mesh, and frames 4..7 are the second part's 0..3.
    with vkmesh.Reconstructor.load(out, keep_frames=True, **SMALL_CAPACITIES) as loaded:
        assert loaded.frames_integrated == 8
        assert canonical_triangles(loaded.mesh()) == truth
        loaded.correct(np.arange(8), np.stack([f.pose for f in frames]))
        assert loaded.pending_corrections() == 0, "each kept frame has its own pose under its merged index"
        with pytest.raises(vkmesh.Error, match="frame 8 is not in the frame store"):
            loaded.correct([8], frames[0].pose[None])


def test_maps_that_do_not_add_up_are_refused(frames, parts, tmp_path):
    _, paths = parts
    with fused(frames[4:5], voxel_size=0.05) as other:
        other.save(tmp_path / "c.vkmap")
    out = tmp_path / "ac.vkmap"
    with pytest.raises(vkmesh.Error, match="--voxel"):
        vkmesh.merge_maps([paths[0], tmp_path / "c.vkmap"], out, mesh=tmp_path / "ac.ply")
    assert not out.exists() and not out.with_suffix(".vkframes").exists() and not (tmp_path / "ac.ply").exists()
    # Refused before anything is read: a mesh vkmesh cannot write, no maps, one path instead of a list.
    with pytest.raises(vkmesh.Error, match="ac.stl"):
        vkmesh.merge_maps(paths, out, mesh=tmp_path / "ac.stl")
    with pytest.raises(ValueError, match="no maps"):
        vkmesh.merge_maps([], out)
    with pytest.raises(TypeError, match="list"):
        vkmesh.merge_maps(paths[0], out)
    with pytest.raises(ValueError, match="frames_budget_mb"):
        vkmesh.merge_maps(paths, out, frames_budget_mb=0)
    with pytest.raises(vkmesh.Error, match="missing.vkmap"):
        vkmesh.merge_maps([paths[0], tmp_path / "missing.vkmap"], out)
    assert not out.exists()


@pytest.fixture(scope="module")
def whole_tiles(parts, tmp_path_factory):
    """merge_maps(tiles=..., tile_size=...) with no output map (tiles of 8 x 8 x 8 blocks): its stats and folder."""
    folder = tmp_path_factory.mktemp("tiles") / "tiles"
    stats = vkmesh.merge_maps(parts[1], None, tiles=folder, tile_size=8 * 8 * VOXEL, keep_frames=False)
    return stats, folder


def test_tiles_joined_are_the_merged_mesh(parts, whole_tiles, tmp_path):
    """merge_maps(tiles=..., tile_size=...) with no output map: tile files only, each tile meshed alone; joined by
    vertex position they are the one-run mesh."""
    truth, paths = parts
    stats, folder = whole_tiles
    assert stats["output"] is None and stats["tiles"]["count"] >= 2
    files = sorted(folder.glob("tile_*.ply"))
    assert len(files) == stats["tiles"]["count"]
    triangles = []
    for f in files:
        m = vkmesh.read_mesh(f)
        triangles += canonical_triangles(m)
    assert sorted(triangles) == sorted(truth)
    with pytest.raises(ValueError, match="go together"):
        vkmesh.merge_maps(paths, None, tiles=tmp_path / "t2")


def test_tiles_made_alone_are_the_merged_maps_tiles(parts, whole_tiles, tmp_path):
    """vkmesh.list_tiles from the block tables, vkmesh.merge_tiles for two tiles (what a worker runs): each tile read
    from the parts' files alone is the tile merge_maps writes from the whole sum."""
    _, paths = parts
    whole, folder = whole_tiles
    size = whole["tiles"]["size_m"]
    plan = vkmesh.list_tiles(paths, size)
    assert plan["frames_integrated"] == 8 and plan["blocks"] > 0
    assert plan["blocks"] == whole["blocks"]["merged"]
    files = {f.name: f for f in folder.glob("tile_*.ply")}
    assert {f"tile_{x}_{y}_{z}.ply" for x, y, z in plan["tiles"]} >= set(files), "every tile with triangles is listed"
    biggest = sorted(files, key=lambda n: -len(vkmesh.read_mesh(files[n]).triangles))[:2]
    asked = [tuple(int(v) for v in n[len("tile_"):-len(".ply")].split("_")) for n in biggest]
    stats = vkmesh.merge_tiles(paths, tmp_path / "alone", size, tiles=asked)
    assert [t["tile"] for t in stats["tiles"]] == asked and stats["count"] == 2
    assert 0 < stats["max_blocks_gpu"] < plan["blocks"]
    for t, name in zip(stats["tiles"], biggest):
        assert t["path"] == str(tmp_path / "alone" / name) and t["blocks_read"] > 0
        alone, from_whole = vkmesh.read_mesh(t["path"]), vkmesh.read_mesh(files[name])
        assert canonical_triangles(alone) == canonical_triangles(from_whole)
        assert sorted(map(tuple, alone.normals.view(np.uint32).tolist())) == sorted(map(tuple, from_whole.normals.view(np.uint32).tolist()))
    assert sorted(p.name for p in (tmp_path / "alone").iterdir()) == sorted(biggest), "no temporary file left"
    with pytest.raises(ValueError, match="tile_size"):
        vkmesh.merge_tiles(paths, tmp_path / "x", 0)
    with pytest.raises(ValueError, match="tile key"):
        vkmesh.merge_tiles(paths, tmp_path / "x", size, tiles=[(1, 2)])
    with pytest.raises(vkmesh.Error, match="missing.vkmap"):
        vkmesh.list_tiles([paths[0], tmp_path / "missing.vkmap"], size)
