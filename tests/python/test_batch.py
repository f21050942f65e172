"""Batch reconstruction on Dask (python3 -m vkmesh.batch; docs/SCALING.md): a sequence cut into fragments, fused on a
LocalCluster of 2 worker processes and merged, is the map of one run over every frame (given poses), even when a
worker dies in the middle of a fragment (the task runs again, one retry reported); with --track, fragments of a real
recording placed through the frames they share track about as well as one run. The kill test starts its own cluster
(--local-workers, the kill hook in its workers' environment); the others share one (--scheduler)."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import vkmesh
from conftest import SMALL_CAPACITIES, canonical_triangles

distributed = pytest.importorskip("distributed", reason="python3-distributed (Dask) is not installed")

VOXEL = 0.04
# Each fragment, merge and tile task makes a Reconstructor of its own, and at vkmesh fuse's default capacities (16,384
# blocks, 2^20 vertices) its first frame takes ~2 s on lavapipe: most of a 3-frame fragment's time. The room's runs
# start small (the capacities grow when needed, to the same map); the tracked runs at a quarter of the defaults, where
# nothing grows and the trajectories are those of the defaults (smaller ones grew, and moved the batch's by up to 8 mm).
SMALL = ["--blocks", SMALL_CAPACITIES["block_capacity"], "--vertices", SMALL_CAPACITIES["vertex_capacity"],
         "--chunks", SMALL_CAPACITIES["chunk_capacity"]]
TRACK_CAPACITIES = dict(block_capacity=1 << 12, vertex_capacity=1 << 18, chunk_capacity=1 << 17)


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    return vkmesh.synth(tmp_path_factory.mktemp("batch") / "room", frames=9, width=160, height=120, noise=True,
                        gt_spacing=0.05)


@pytest.fixture(scope="module")
def one_run(room):
    """The room's 9 frames fused in one Reconstructor: the mesh the batch runs of the room must give."""
    with vkmesh.Reconstructor(voxel_size=VOXEL) as one:
        for f in vkmesh.open_dataset(room, frames=9):
            one.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
        return one.mesh()


@pytest.fixture(scope="module")
def scheduler():
    """A LocalCluster as `--local-workers 2` starts one (2 worker processes, 1 thread each, GPU=1), for the tests that
    run on a running scheduler (--scheduler): one cluster start instead of one per test. Its workers run without the
    validation layer, as batch() does (VKMESH_VALIDATION=0: the workers inherit this process's environment)."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, resources={"GPU": 1},
                                  dashboard_address=None, env={"VKMESH_VALIDATION": "0"}) as cluster:
        yield cluster.scheduler_address


def batch(*args, env=None):
    """python3 -m vkmesh.batch in its own process, as users run it (its workers are processes of their own too).
    Without the validation layer: the workers' messages would reach no check (they run the stages the C++ and Python
    suites validate), and it doubled this file's time in CI."""
    env = {**{k: v for k, v in os.environ.items() if k != "VKMESH_VALIDATION"}, **(env or {})}
    return subprocess.run([sys.executable, "-m", "vkmesh.batch", *map(str, args)], capture_output=True, text=True,
                          env=env, timeout=600)


def vertex_bits(mesh):
    return sorted(map(tuple, np.asarray(mesh.vertices).view(np.uint32)))


def test_fragments_on_two_workers_are_the_one_run_map_even_when_a_worker_dies(room, one_run, tmp_path):
    truth = one_run
    marker = tmp_path / "killed"
    r = batch(room, "--frames", 9, "--fragment-frames", 3, "--local-workers", 2, "--voxel", VOXEL, "-o", tmp_path / "b.vkmap",
              "--mesh", tmp_path / "b.ply", "--stats", tmp_path / "s.json", *SMALL, env={"VKMESH_BATCH_KILL_ONCE": str(marker)})
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


def tum_ate(truth, positions):
    """TUM's absolute trajectory error: RMSE of the positions after the rigid motion that fits them best to the truth's
    (Horn's method, as bench/ate.py)."""
    want = truth[:, :3, 3]
    a, b = positions - positions.mean(axis=0), want - want.mean(axis=0)
    u, _, vt = np.linalg.svd(a.T @ b)
    d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    r = (u @ d @ vt).T
    aligned = (r @ a.T).T + want.mean(axis=0)
    return float(np.sqrt(np.mean(np.sum((aligned - want) ** 2, axis=1))))


def test_tracked_fragments_of_a_real_recording_placed_by_overlaps_and_loops(scheduler, tmp_path):
    """TUM fr1/rpy's first 80 frames (real Kinect data) in 4 tracked fragments, --loop-closure. Placed in a chain
    through the 10 frames each shares with the one before, the global trajectory's error against the recording's
    poses is at most 1.25 x that of one tracked run. The camera turns in place, so every fragment revisits the
    first's view: the non-consecutive pairs are registered, the verified loops agree with the recording's poses, and
    the pose graph's placement has a smaller ATE than the chain's. The chain's trajectory is derived from the same
    run (each fragment's frames moved back by its transform before / after the graph), so one batch run measures both."""
    tum, n = shared_dataset("tum_fr1_rpy"), 80
    frames = list(vkmesh.open_dataset(tum, frames=n))
    truth = np.stack([f.pose for f in frames])
    with vkmesh.Reconstructor(**TRACK_CAPACITIES) as one:
        for i, f in enumerate(frames):
            one.integrate(f.depth, f.intrinsics, f.pose if i == 0 else None, color=f.color)
        one_poses = one.trajectory()
    r = batch(tum, "--frames", n, "--fragment-frames", 20, "--overlap", 10, "--track", "--loop-closure", "--scheduler", scheduler,
              "--blocks", TRACK_CAPACITIES["block_capacity"], "--vertices", TRACK_CAPACITIES["vertex_capacity"],
              "--chunks", TRACK_CAPACITIES["chunk_capacity"], "-o", tmp_path / "t.vkmap", "--trajectory", tmp_path / "t.txt", "--stats", tmp_path / "s.json", "-q")
    assert r.returncode == 0, r.stderr
    stats = json.loads((tmp_path / "s.json").read_text())
    assert stats["frames_integrated"] == n, "every frame once: the shared frames are fused again only where they belong"
    assert [p["overlap"]["frames"] for p in stats["placements"][1:]] == [10, 10, 10]
    lc = stats["loop_closure"]
    assert lc["tried"] >= 1 and [p["fragments"] for p in lc["pairs"]] == [[0, 2], [0, 3], [1, 3]]
    assert lc["accepted"] >= 1 and lc["graph"]["solves"][-1]["converged"]
    # Fragment k's own frame into the truth's world: its first frame is tracked at the identity (the first fragment
    # at the recording's first pose, so its own frame is the world).
    own_to_world = [np.eye(4)] + [truth[f["fused_from"]] for f in stats["fragments"][1:]]
    for p in lc["pairs"]:
        if p["status"] == "accepted":
            i, j = p["fragments"]
            want = np.linalg.inv(own_to_world[i]) @ own_to_world[j]
            got = np.asarray(p["transform"]).reshape(4, 4)
            off_m = np.linalg.norm(got[:3, 3] - want[:3, 3])
            off_deg = np.degrees(np.arccos(np.clip((np.trace(want[:3, :3].T @ got[:3, :3]) - 1) / 2, -1, 1)))
            # Measured 2-5 cm and 1-6 degrees: the fragments' own tracking drift is in the registration (and in
            # the chain's same relative transform: 3.5-5 cm, 2-5 degrees).
            assert off_m < 0.075 and off_deg < 8, f"loop {p['first']} / {p['second']}: {off_m:.3f} m, {off_deg:.1f} degrees off"
    lines = [l.split() for l in (tmp_path / "t.txt").read_text().splitlines() if not l.startswith("#")]
    assert [float(l[0]) for l in lines] == pytest.approx([f.timestamp for f in frames], abs=1e-6)
    after = np.array([[float(x) for x in l[1:4]] for l in lines])
    chain = after.copy()
    for f, pl in zip(stats["fragments"], lc["placement"]):
        back = np.asarray(pl["before"]).reshape(4, 4) @ np.linalg.inv(np.asarray(pl["after"]).reshape(4, 4))
        lo, hi = f["frames"]
        chain[lo:hi] = after[lo:hi] @ back[:3, :3].T + back[:3, 3]
    one_ate, loops_ate, chain_ate = tum_ate(truth, one_poses[:, :3, 3]), tum_ate(truth, after), tum_ate(truth, chain)
    print(f"ATE against the recording's poses: one run {one_ate:.4f} m, chain {chain_ate:.4f} m, with {lc['accepted']} loops {loops_ate:.4f} m")
    assert one_ate < 0.05
    assert chain_ate <= 1.25 * one_ate, f"chain ATE {chain_ate:.4f} m, one run {one_ate:.4f} m"
    assert loops_ate <= chain_ate


def test_bad_options_are_clear_errors(room, tmp_path):
    r = batch(room, "--track", "--overlap", 0, "-o", tmp_path / "x.vkmap")
    assert r.returncode == 2 and "--overlap" in r.stderr
    r = batch(room, "-o", tmp_path / "x.ply")
    assert r.returncode == 2 and "--mesh" in r.stderr
    r = batch(room, "--loop-closure", "-o", tmp_path / "x.vkmap")
    assert r.returncode == 2 and "--loop-closure" in r.stderr
    assert not (tmp_path / "x.vkmap").exists()


def test_tile_tasks_on_two_workers_join_to_the_one_run_mesh(room, one_run, scheduler, tmp_path):
    """--tiles without -o: tile tasks on 2 workers, each reading from the fragments' maps only the blocks of its tiles
    (vkmesh.merge_tiles), no merged map: joined by vertex position bits, the tiles are the one-run mesh (triangles,
    vertex normal bits, no vertex twice, no edge left open along a tile boundary), and no task held the whole map."""
    truth = one_run
    tiles = tmp_path / "tiles"
    r = batch(room, "--tiles", tiles, "--mesh", tmp_path / "m.ply", "--tile-size", 1)   # refused before a cluster starts
    assert r.returncode == 2 and "--mesh needs -o" in r.stderr
    r = batch(room, "--tiles", tiles)
    assert r.returncode == 2 and "go together" in r.stderr and not tiles.exists()
    r = batch(room, "--frames", 9, "--fragment-frames", 5, "--scheduler", scheduler, "--voxel", VOXEL, "--tiles", tiles,
              "--tile-size", 8 * 8 * VOXEL, "--tiles-per-task", 3, "--stats", tmp_path / "s.json", "-q", *SMALL)
    assert r.returncode == 0, r.stderr
    stats = json.loads((tmp_path / "s.json").read_text())
    t = stats["tiles"]
    assert stats["output"] is None and stats["merges"] == 0, "tiles only: no merged map"
    assert stats["frames_integrated"] == 9
    files = sorted(tiles.glob("tile_*.ply"))
    assert len(files) == t["count"] >= 4 and t["tasks"] >= 2
    assert not list(tiles.glob(".writing*")), "every tile file was renamed into place"
    assert 0 < t["max_blocks_gpu"] < t["map_blocks"], "no task had the whole map on the GPU"
    assert t["max_blocks_host"] < t["per_task"][0]["table_blocks"] + t["map_blocks"], \
        "nor in memory what adding the fragments' whole maps holds"

    def bits(a):
        return [tuple(v) for v in np.ascontiguousarray(a, dtype=np.float32).view(np.uint32).tolist()]

    normal_of = dict(zip(bits(truth.vertices), bits(truth.normals)))
    joined, normals, edges = [], {}, {}
    for f in files:
        m = vkmesh.read_mesh(f)
        joined += canonical_triangles(m)
        for p, n in zip(bits(m.vertices), bits(m.normals)):
            assert normals.setdefault(p, n) == n, "a boundary vertex has one normal in every tile"
        p = bits(m.vertices)
        for tri in m.triangles.tolist():
            for k in range(3):
                e = tuple(sorted((p[tri[k]], p[tri[(k + 1) % 3]])))
                edges[e] = edges.get(e, 0) + 1
    assert sorted(joined) == canonical_triangles(truth), "the tiles' triangles are the one run's"
    assert normals == normal_of, "every vertex once, with the one run's position and normal bits"
    truth_edges = {}
    p = bits(truth.vertices)
    for tri in truth.triangles.tolist():
        for k in range(3):
            e = tuple(sorted((p[tri[k]], p[tri[(k + 1) % 3]])))
            truth_edges[e] = truth_edges.get(e, 0) + 1
    assert edges == truth_edges, "the same edges, each used as often: no seam along a tile boundary"


def _rz(degrees, t):
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    p = np.eye(4)
    p[:2, :2] = [[c, -s], [s, c]]
    p[:3, 3] = t
    return p


def test_pose_graph_of_a_square_closes_its_loop_and_flags_a_wrong_one():
    """vkmesh.optimise_pose_graph (slam::PoseGraph), what vkmesh.batch --loop-closure solves over fragments: a square
    walked with drifting odometry (3 cm and 3 degrees too much each side) and one loop edge back to the start ends
    closer to the truth; a loop edge 1 m off keeps a large whitened error (the batch drops such a loop)."""
    truth = [_rz(90 * k, [[0, 0], [1, 0], [1, 1], [0, 1]][k] + [0]) for k in range(4)]
    drift = _rz(3, [0.03, 0, 0])
    odometry = [np.linalg.inv(truth[k - 1]) @ truth[k] @ drift for k in range(1, 4)]
    chained = [np.eye(4)]
    for m in odometry:
        chained.append(chained[-1] @ m)
    edges = [{"from": k - 1, "to": k, "measured": odometry[k - 1], "sigma_m": 0.05, "sigma_deg": 3.0} for k in range(1, 4)]
    loop = {"from": 0, "to": 3, "measured": np.linalg.inv(truth[0]) @ truth[3], "sigma_m": 0.01, "sigma_deg": 0.5, "loop": True}

    def error(poses):
        return sum(np.linalg.norm(np.asarray(p)[:3, 3] - t[:3, 3]) for p, t in zip(poses, truth))

    solved = vkmesh.optimise_pose_graph(chained, edges + [loop])
    assert solved["converged"] and solved["final_cost"] < solved["initial_cost"]
    assert np.allclose(solved["poses"][0], np.eye(4)), "node 0 is held fixed"
    assert error(solved["poses"]) < 0.5 * error(chained), (error(solved["poses"]), error(chained))
    assert len(solved["edge_errors"]) == 4 and solved["edge_errors"][3] < 2

    wrong = dict(loop, measured=loop["measured"] @ _rz(0, [1.0, 0, 0]))
    solved = vkmesh.optimise_pose_graph(chained, edges + [wrong])
    assert solved["edge_errors"][3] > 10, solved["edge_errors"]
    with pytest.raises(ValueError):
        vkmesh.optimise_pose_graph(chained, [dict(loop, sigma_m=0)])


def test_fragment_graph_keeps_a_right_loop_and_drops_a_wrong_one():
    """vkmesh.batch's graph over fragments (no Dask): the chain of 4 fragments drifted 2 cm and 2 degrees per step;
    loops measured as register_maps gives them (inverse(X_i) @ X_j: fragment j's own frame into fragment i's) from
    the truth pull the placement to it, while a loop 0.5 m off is dropped and does not bend it."""
    from vkmesh import batch as vb
    truth = [_rz(30 * k, [0.3 * k, 0.1 * k, 0]) for k in range(4)]
    step = _rz(2, [0.02, 0, 0])
    chain = [truth[0]]
    for k in range(1, 4):
        chain.append(chain[-1] @ np.linalg.inv(truth[k - 1]) @ truth[k] @ step)
    paths = [(0.0, 0.0)] + [(0.3, 30.0)] * 3
    right = [(i, j, np.linalg.inv(truth[i]) @ truth[j]) for i, j in ((0, 2), (0, 3), (1, 3))]
    wrong = (0, 3, right[1][2] @ _rz(0, [0.5, 0, 0]))

    def off(poses):
        return max(np.linalg.norm(p[:3, 3] - t[:3, 3]) for p, t in zip(poses, truth))

    solved, solves, kept, dropped, errors = vb.close_loops(chain, paths, right)
    assert kept == [0, 1, 2] and not dropped and off(solved) < 0.3 * off(chain), (off(solved), off(chain))
    solved_wrong, solves, kept, dropped, errors = vb.close_loops(chain, paths, right + [wrong])
    assert [d[0] for d in dropped] == [3] and len(solves) == 2, dropped
    assert np.allclose(np.stack(solved_wrong), np.stack(solved)), "the graph without the wrong loop"
