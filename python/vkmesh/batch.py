"""Batch reconstruction on Dask (docs/SCALING.md): recordings cut into fragments, fused on workers, placed in one
world frame, and their maps added into one (vkmesh.merge_maps), exactly.

    python3 -m vkmesh.batch RECORDING... -o map.vkmap --mesh mesh.ply [--fragment-frames N] [--overlap K]
        [--track [--loop-closure]] [--trajectory FILE] [--local-workers W | --scheduler ADDRESS] [--stats FILE]
        [--tiles DIR --tile-size S [--tiles-per-task N]]
        [vkmesh fuse's dataset, map, capacity and tracking options: --voxel, --max-depth, --intrinsics, ...]

With the recordings' poses, every fragment is fused at them and the maps add up to the map `vkmesh fuse` makes of
the same frames, bit for bit (the TSDF is an integer sum, independent of the order of the frames). With --track,
each fragment is tracked from its own first frame (the first fragment from the recording's first pose, as
`vkmesh fuse --track` starts), consecutive fragments are placed through the K frames they share, and each
fragment's frames are fused again at their global poses; every frame enters the map once.

With --track --loop-closure, fragments that are not consecutive but whose chained frames come near each other are
registered on the workers (vkmesh.register_maps, through the frames each fragment keeps), and one pose graph over
the fragments (vkmesh.optimise_pose_graph: the chain's placements as odometry, the verified registrations as loops)
places them before the re-fusion; a loop the others disagree with is dropped and the graph solved again.

With --tiles, the mesh is also written tile by tile, by tile tasks on the workers that read from the fragments' maps
only the blocks their tiles need (vkmesh.merge_tiles): no worker holds the whole map. Without -o there is no merged
map at all, only the tiles.

Tasks name their inputs (recording, frame range, settings, poses) and write their maps under a name derived from
them (written under a temporary name and renamed): a task that ran before is not run again (a run stopped half
way resumes), and a task whose worker died is run again by Dask. A fragment that keeps failing stops the run with
an error naming its recording and frame range.
"""

import argparse
import functools
import hashlib
import json
import os
import shutil
import socket
import sys
import time
import warnings

import numpy as np

import vkmesh
from vkmesh import _vkmesh

# Setting kinds (api/settings.cpp) that the batch passes on, and those it handles itself.
_PASSED_KINDS = ("input", "map", "capacity", "tracking", "correction", "processing", "device")
_OWN_OPTIONS = {"--track", "--loop-closure", "--frames", "--first-frame", "--keep-frames", "--no-keep-frames", "--mode",
                "--track-iterations", "--corrections-per-frame", "--frames-budget", "--frames-spill",
                "--loop-place-candidates"}
# Options of the dataset reader (vkmesh.open_dataset keywords), not of the Reconstructor.
_DATASET_OPTIONS = {"--intrinsics": "intrinsics", "--depth-scale": "depth_scale", "--depth-topic": "depth_topic",
                    "--color-topic": "color_topic", "--info-topic": "info_topic"}
# Testing hook: the first fuse task of fragment 1 to reach its middle exits its worker process (os._exit) when this
# file does not exist yet, after creating it: a worker killed in the middle of a fragment (tests/python/test_batch.py).
_KILL_ONCE = "VKMESH_BATCH_KILL_ONCE"


# ---- options ------------------------------------------------------------------------------------------------

def _value(text):
    """A setting's value from the command line: an int, a float, or the text."""
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _add_setting_options(parser):
    """vkmesh fuse's dataset, map, capacity, tracking and device options, from the one table of settings
    (api/settings.cpp): the same names, help and defaults."""
    added = []
    for s in _vkmesh._settings():
        cli, python = s["cli"], s["python"]
        if s["kind"] not in _PASSED_KINDS or not cli or cli in _OWN_OPTIONS:
            continue
        if not python and cli not in _DATASET_OPTIONS and cli not in ("--no-color", "--alloc-pixels"):
            continue
        dest = "setting_" + cli.lstrip("-").replace("-", "_")
        help_text = s["help"] + (f" (default {s['default']})" if s["default"] not in ("", "false") else "")
        if s["default"] in ("true", "false"):
            if s["cli_negates"]:   # --no-grow sets grow_capacities False
                parser.add_argument(cli, dest=dest, action="store_const", const=False, default=None, help=help_text)
            else:
                parser.add_argument(cli, dest=dest, action="store_const", const=True, default=None, help=help_text)
                if s["default"] == "true":
                    parser.add_argument("--no-" + cli[2:], dest=dest, action="store_const", const=False,
                                        help=f"turn {cli} off")
        else:
            parser.add_argument(cli, dest=dest, default=None, choices=s["choices"] or None, help=help_text,
                                metavar=None if s["choices"] else cli.lstrip("-").upper().replace("-", "_"))
        added.append((cli, python, dest))
    return added


def _settings_from(args, added):
    """(Reconstructor keywords, open_dataset keywords) from the options given."""
    reconstructor, dataset = {}, {}
    for cli, python, dest in added:
        v = getattr(args, dest)
        if v is None:
            continue
        if cli == "--no-color":
            reconstructor["color_mode"] = "off"
        elif cli == "--alloc-pixels":
            reconstructor["allocation_tiles"] = False
        elif cli == "--intrinsics":
            dataset["intrinsics"] = tuple(float(x) for x in str(v).split(","))
        elif cli in _DATASET_OPTIONS:
            dataset[_DATASET_OPTIONS[cli]] = _value(v) if cli == "--depth-scale" else v
        else:
            reconstructor[python] = v if isinstance(v, bool) else _value(v)
    return reconstructor, dataset


# ---- tasks (run on the workers) -----------------------------------------------------------------------------

def _key(kind, spec):
    text = json.dumps({k: v for k, v in spec.items() if k not in ("work_dir",)}, sort_keys=True, default=str)
    return f"{kind}-{hashlib.sha1(text.encode()).hexdigest()[:16]}"


def _write_json(path, value):
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "w") as f:
        json.dump(value, f)
    os.replace(tmp, path)


def _attempt(work_dir, key):
    """Counts the runs of a task (a retried task runs again): returns this run's number."""
    path = os.path.join(work_dir, key + ".attempts")
    with open(path, "a") as f:
        f.write(f"{socket.gethostname()}:{os.getpid()}\n")
    with open(path) as f:
        return len(f.read().splitlines())


def _done(work_dir, key):
    path = os.path.join(work_dir, key + ".json")
    if os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    return None


def _worker_name():
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return f"{socket.gethostname()}:{os.getpid()}"


def _frames_path(map_path):
    """The kept frames saved beside a map (gpu::frameStorePathOf: the extension replaced by .vkframes)."""
    return os.path.splitext(map_path)[0] + ".vkframes"


def _task(kind, finished=lambda spec, done: True):
    """Makes `work(spec, key)` a task the workers run: keyed by its inputs (the spec), idempotent (a finished run's
    result, written as the key's .json, is returned again while `finished(spec, result)` says its outputs are there),
    its runs counted (a retried task runs again: "attempt"), timed ("ms") and placed ("worker")."""
    def wrap(work):
        @functools.wraps(work)
        def task(spec):
            work_dir = spec["work_dir"]
            key = _key(kind, spec)
            done = _done(work_dir, key)
            if done is not None and finished(spec, done):
                return done
            attempt = _attempt(work_dir, key)
            t0 = time.perf_counter()
            result = {"key": key, **work(spec, key)}
            result.update(ms=(time.perf_counter() - t0) * 1e3, worker=_worker_name(), attempt=attempt)
            _write_json(os.path.join(work_dir, key + ".json"), result)
            return result
        return task
    return wrap


@_task("fragment")
def fuse_fragment(spec, key):
    """Fuses frames [first, stop) of one recording into a map of their own, saved in the work folder under a name
    derived from the spec (the result's "map").

    spec["poses"]: None (the recording's poses), "track" (tracked from the first frame, fused at spec["first_pose"]),
    or {frame index: 4x4 list} (fused at these global poses, frames not listed skipped). Returns what it did: every
    frame's index, timestamp, pose and whether it was fused; idempotent (a finished task's result is read back)."""
    work_dir = spec["work_dir"]
    ds = vkmesh.open_dataset(spec["recording"], require_poses=spec["poses"] is None, **spec["dataset"])
    settings = dict(spec["settings"])
    frames, skipped = [], []
    given = spec["poses"] if isinstance(spec["poses"], dict) else None
    kill_at = (spec["first"] + spec["stop"]) // 2 if spec["index"] == 1 and not isinstance(spec["poses"], dict) else None
    with vkmesh.Reconstructor(**settings) as r:
        for i in range(spec["first"], spec["stop"]):
            if kill_at is not None and i == kill_at and os.environ.get(_KILL_ONCE) and not os.path.exists(os.environ[_KILL_ONCE]):
                open(os.environ[_KILL_ONCE], "w").close()
                os._exit(17)   # the testing hook: this worker dies in the middle of the fragment
            if given is not None and str(i) not in given:
                continue
            try:
                f = ds[i]
            except vkmesh.Error as e:
                skipped.append([i, str(e)])
                continue
            if not np.any(f.depth > 0):
                skipped.append([i, f"no valid depth in {f.depth_path}"])
                continue
            if given is not None:
                pose = np.asarray(given[str(i)], dtype=np.float64).reshape(4, 4)
                r.integrate(f.depth, f.intrinsics, pose, color=f.color)
                frames.append([i, f.timestamp, pose.ravel().tolist(), True])
            elif spec["poses"] is None:
                r.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
                frames.append([i, f.timestamp, np.asarray(f.pose).ravel().tolist(), True])
            elif not frames:   # tracked: the first frame is fused where the fragment starts
                pose = np.asarray(spec["first_pose"], dtype=np.float64).reshape(4, 4)
                r.integrate(f.depth, f.intrinsics, pose, color=f.color)
                frames.append([i, f.timestamp, pose.ravel().tolist(), True])
            else:
                out = r.integrate(f.depth, f.intrinsics, None, color=f.color)
                frames.append([i, f.timestamp, np.asarray(out["pose"]).ravel().tolist(), bool(out["tracked"])])
        tmp_map = os.path.join(work_dir, f"{key}.tmp{os.getpid()}.vkmap")
        r.save(tmp_map)
        if settings.get("keep_frames"):   # the kept frames, saved beside the map, renamed first: a map in place has its frames
            os.replace(_frames_path(tmp_map), _frames_path(os.path.join(work_dir, key + ".vkmap")))
        os.replace(tmp_map, os.path.join(work_dir, key + ".vkmap"))
    return {"map": os.path.join(work_dir, key + ".vkmap"), "frames": frames, "skipped": skipped}


@_task("tiles", finished=lambda spec, done: all(os.path.exists(t["path"]) for t in done["stats"]["tiles"] if t["path"]))
def make_tiles(spec, key):
    """Makes some tiles (spec["tiles"], (x, y, z) keys) of the sum of maps (spec["inputs"]) into spec["tiles_dir"]:
    vkmesh.merge_tiles on a worker, each tile from the blocks it needs read from every map, never the whole map.
    Idempotent: a finished task's result is read back while the tiles it wrote are there (each tile file is written
    under a temporary name and renamed)."""
    return {"stats": vkmesh.merge_tiles(spec["inputs"], spec["tiles_dir"], spec["tile_size"], tiles=spec["tiles"],
                                        **spec.get("device", {}))}


@_task("loop")
def register_fragments(spec, key):
    """Registers fragment spec["second"]'s map to fragment spec["first"]'s (vkmesh.register_maps) on a worker: a loop
    between them, or none. Returns {"registration": its dict (its "transform" takes the second fragment's own frame
    into the first's) or None, "reason": why not (vkmesh.Error's message)}; idempotent (keyed by the two maps, whose
    names derive from their fragments' specs)."""
    registration, reason = None, None
    for m in (spec["first_map"], spec["second_map"]):
        if not os.path.exists(_frames_path(m)):   # a bug, not "no loop": the fragments are fused with keep_frames=True
            raise RuntimeError(f"{spec['name']}: {m} has no kept frames beside it ({_frames_path(m)})")
    try:
        registration = vkmesh.register_maps(spec["first_map"], spec["second_map"])
    except vkmesh.Error as e:   # not sure, or no overlap: no loop (a failure of the task itself is another exception)
        reason = str(e)
    return {"registration": registration, "reason": reason}


@_task("merge", finished=lambda spec, done: os.path.exists(spec["output"]))
def merge_fragment_maps(spec, key):
    """Adds maps (spec["inputs"]) into spec["output"] (and spec["mesh"] when given): vkmesh.merge_maps on a worker."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the loop closers' states, not kept by fragments
        stats = vkmesh.merge_maps(spec["inputs"], spec["output"], mesh=spec.get("mesh"), keep_frames=False,
                                  tiles=spec.get("tiles"), tile_size=spec.get("tile_size", 0), **spec.get("device", {}))
    return {"output": spec["output"], "stats": stats}


# ---- placement (on the client) ------------------------------------------------------------------------------

def place_after(previous_global, local, shared):
    """The transform from a fragment's own frame into the world, from the frames it shares with the fragment before
    it (placed already). The earliest shared frame fused by both gives it: world pose x local pose^-1. The fragment
    tracked that frame from nothing (its first frame, at the identity) and the later shared frames against a map of
    a few frames only, so their estimates carry its cold start's error; they are reported, as how far they lie from
    the transform (metres, degrees), not averaged in. None when no shared frame was fused by both."""
    both = [i for i in shared if i in previous_global and i in local]
    if not both:
        return None, None
    t = previous_global[both[-1]] @ np.linalg.inv(local[both[-1]])
    estimates = [previous_global[i] @ np.linalg.inv(local[i]) for i in both]
    spread_m = max(float(np.linalg.norm(e[:3, 3] - t[:3, 3])) for e in estimates)
    spread_deg = max(float(np.degrees(np.arccos(np.clip((np.trace(t[:3, :3].T @ e[:3, :3]) - 1) / 2, -1, 1)))) for e in estimates)
    return t, {"frames": len(both), "spread_m": spread_m, "spread_deg": spread_deg}


# ---- loops between fragments and the pose graph over them (on the client; --loop-closure) ----------------------

# Two non-consecutive fragments are a loop candidate when, by the chain's placement, some frame of one lies within
# these of some frame of the other: the camera came back to a place it saw, within what registration can recover
# (the chain's drift over a few fragments is centimetres and degrees, far below these).
LOOP_CANDIDATE_METRES = 0.5
LOOP_CANDIDATE_DEGREES = 30.0
# The pose graph's standard deviations. A loop is one registration of two fragments' kept frames, its agreeing pairs
# within a few cm and degrees of each other: fixed. An odometry edge (the chain's placement of a fragment after the
# one before) carries the drift of the one before's tracking from its first frame to the shared frame it is placed
# by: a floor plus a share of that path's length, translation and rotation separately. With these, a loop across a
# few fragments weighs more than the chain's odometry it closes, as drift grows with the path.
LOOP_SIGMA_M, LOOP_SIGMA_DEG = 0.02, 1.0
ODOMETRY_SIGMA_M, ODOMETRY_SIGMA_DEG = 0.01, 0.5              # floor
ODOMETRY_SIGMA_M_PER_M, ODOMETRY_SIGMA_DEG_PER_DEG = 0.05, 0.05  # per metre travelled, per degree turned
# A loop whose whitened error after the solve is above this (standard deviations) disagrees with the odometry and
# the other loops: it is dropped and the graph solved again, worst first, so that a wrong loop cannot bend the map.
LOOP_MAX_WHITENED = 5.0


def _angle_deg(r):
    return float(np.degrees(np.arccos(np.clip((np.trace(r) - 1) / 2, -1, 1))))


def _path_length(poses):
    """Metres travelled and degrees turned along poses in order."""
    metres = sum(float(np.linalg.norm(b[:3, 3] - a[:3, 3])) for a, b in zip(poses, poses[1:]))
    degrees = sum(_angle_deg(a[:3, :3].T @ b[:3, :3]) for a, b in zip(poses, poses[1:]))
    return metres, degrees


def closest_frames(first_placed, second_placed):
    """The two frames, one of each fragment, nearest each other by their placed poses: (metres, degrees, first frame,
    second frame) of the pair within LOOP_CANDIDATE_* with the least distance, or of the nearest pair by position
    when none is. Every pair at once (numpy): fragments of a thousand frames compare in a moment."""
    first_ids, second_ids = list(first_placed), list(second_placed)
    a = np.stack([first_placed[i] for i in first_ids])
    b = np.stack([second_placed[i] for i in second_ids])
    metres = np.linalg.norm(a[:, None, :3, 3] - b[None, :, :3, 3], axis=2)
    # trace(Ra^T Rb) is the sum of the elementwise products of Ra and Rb.
    cosine = (np.einsum("aij,bij->ab", a[:, :3, :3], b[:, :3, :3]) - 1) / 2
    degrees = np.degrees(np.arccos(np.clip(cosine, -1, 1)))
    near = (metres <= LOOP_CANDIDATE_METRES) & (degrees <= LOOP_CANDIDATE_DEGREES)
    k = np.unravel_index(np.argmin(np.where(near, metres, np.inf) if near.any() else metres), metres.shape)
    return float(metres[k]), float(degrees[k]), first_ids[k[0]], second_ids[k[1]]


def loop_candidates(placed):
    """Non-consecutive fragment pairs (i, j), i < j - 1, that a frame of each comes near (closest_frames within
    LOOP_CANDIDATE_*), with their closest frames. Consecutive ones are tied by their shared frames already."""
    out = []
    for j in range(len(placed)):
        for i in range(j - 1):
            metres, degrees, fi, fj = closest_frames(placed[i], placed[j])
            near = metres <= LOOP_CANDIDATE_METRES and degrees <= LOOP_CANDIDATE_DEGREES
            out.append({"first": i, "second": j, "closest_m": metres, "closest_deg": degrees, "frames": [fi, fj], "near": near})
    return out


def fragment_graph(transforms, odometry_paths, loops):
    """The pose graph over fragments. Node k is fragment k's transform X_k from its own frame into the world (node 0,
    the first fragment, fixed). An edge from a to b measures inverse(X_a) @ X_b, which takes b's own frame into a's:
      odometry (k-1, k): inverse(X_{k-1}) @ X_k from the chain's placement (so the chain itself has no residual);
      loop (i, j): register_maps(map_i, map_j)["transform"], which takes the second map's world (fragment j's own
        frame, where its frames were tracked and kept) into the first's (fragment i's own frame): the same quantity.
    odometry_paths[k]: (metres, degrees) fragment k-1 travelled from its first frame to the frame k is placed by.
    loops: [(i, j, 4 x 4)]. Returns (poses, edges) for vkmesh.optimise_pose_graph."""
    edges = []
    for k in range(1, len(transforms)):
        metres, degrees = odometry_paths[k]
        edges.append({"from": k - 1, "to": k, "measured": (np.linalg.inv(transforms[k - 1]) @ transforms[k]).tolist(),
                      "sigma_m": ODOMETRY_SIGMA_M + ODOMETRY_SIGMA_M_PER_M * metres,
                      "sigma_deg": ODOMETRY_SIGMA_DEG + ODOMETRY_SIGMA_DEG_PER_DEG * degrees, "loop": False})
    for i, j, measured in loops:
        edges.append({"from": i, "to": j, "measured": np.asarray(measured).tolist(), "sigma_m": LOOP_SIGMA_M,
                      "sigma_deg": LOOP_SIGMA_DEG, "loop": True})
    return [np.asarray(t).tolist() for t in transforms], edges


def close_loops(transforms, odometry_paths, loops):
    """Solves the fragment graph; while a loop's whitened error is above LOOP_MAX_WHITENED, drops the worst such loop
    and solves again. Returns (the fragments' transforms, the solves, the loops kept as indices into `loops`, the
    dropped ones as (index, whitened error), each kept loop's whitened error)."""
    kept, dropped, solves = list(range(len(loops))), [], []
    while True:
        poses, edges = fragment_graph(transforms, odometry_paths, [loops[k] for k in kept])
        solve = vkmesh.optimise_pose_graph(poses, edges)
        solves.append({k: solve[k] for k in ("converged", "iterations", "initial_cost", "final_cost", "ms")} | {"loops": len(kept)})
        loop_errors = solve["edge_errors"][len(transforms) - 1:]
        worst = int(np.argmax(loop_errors)) if loop_errors else None
        if worst is None or loop_errors[worst] <= LOOP_MAX_WHITENED:
            return ([np.asarray(p, dtype=np.float64) for p in solve["poses"]], solves, kept, dropped,
                    dict(zip(kept, loop_errors)))
        dropped.append((kept.pop(worst), float(loop_errors[worst])))


def _transform_change(a, b):
    return float(np.linalg.norm(a[:3, 3] - b[:3, 3])), _angle_deg(a[:3, :3].T @ b[:3, :3])


# ---- the run (on the client) --------------------------------------------------------------------------------

class BatchError(Exception):
    pass


def _plan(recordings, dataset_options, fragment_frames, overlap, track, first_frame, last_frame):
    """Fragments: (recording, index, owned [start, stop), fused from `first`): owned ranges cut the frames, and with
    --track each fragment after the first also fuses the `overlap` frames before its own, to be placed by them."""
    fragments = []
    for rec in recordings:
        n = len(vkmesh.open_dataset(rec, require_poses=not track, **dataset_options))
        stop_all = n if last_frame <= 0 else min(n, last_frame)
        if first_frame >= stop_all:
            raise BatchError(f"{rec}: --first-frame {first_frame} but it has {stop_all} frames to fuse")
        starts = list(range(first_frame, stop_all, fragment_frames))
        if len(starts) > 1 and stop_all - starts[-1] < fragment_frames // 2:
            starts.pop()   # a short tail joins the fragment before it rather than be tracked from a cold start
        for k, s in enumerate(starts):
            e = starts[k + 1] if k + 1 < len(starts) else stop_all
            first = max(first_frame, s - overlap) if (track and k > 0) else s
            fragments.append({"recording": os.path.abspath(rec), "index": k, "start": s, "stop": e, "first": first})
    return fragments


def _submit_all(client, fn, specs, what, retries, progress):
    """Runs fn over specs on the cluster (one GPU each), reporting progress; a spec that keeps failing stops the run
    naming it."""
    return _gather(_submit(client, fn, specs, what, retries), specs, what, progress)


def _submit(client, fn, specs, what, retries):
    """Submits fn over specs (one GPU each) without waiting: {future: index}."""
    return {client.submit(fn, spec, key=f"{what}-{i}-{_key(what, spec)}", retries=retries, resources={"GPU": 1},
                          pure=False): i for i, spec in enumerate(specs)}


def _gather(futures, specs, what, progress):
    """The results of _submit's futures in the order of specs, reporting progress; a spec that keeps failing stops the
    run naming it."""
    from distributed import as_completed
    results = [None] * len(specs)
    done = 0
    for future in as_completed(futures):
        i = futures[future]
        try:
            results[i] = future.result()
        except Exception as e:   # a task error, or KilledWorker after the scheduler's allowed failures
            for f in futures:
                f.cancel()
            raise BatchError(f"{what} {specs[i].get('name', i)} failed: {type(e).__name__}: {e}") from e
        done += 1
        if progress:
            print(f"vkmesh.batch: {what} {done}/{len(specs)} ({specs[i].get('name', i)})", file=sys.stderr, flush=True)
    return results


def _pose_dict(frames):
    return {int(i): np.asarray(p, dtype=np.float64).reshape(4, 4) for i, _, p, fused in frames if fused}


def run(args, added):
    t_start = time.perf_counter()
    settings, dataset_options = _settings_from(args, added)
    if args.loop_closure and not args.track:
        raise BatchError("--loop-closure needs --track: loops correct tracked fragments' placements (with the recordings' "
                         "poses there is nothing to correct)")
    if args.loop_closure and len(args.recordings) > 1:
        raise BatchError("--loop-closure: one recording at a time (fragments of different recordings are not chained; "
                         "sessions are joined by vkmesh merge --register)")
    # What merging refuses, refused before anything is fused (core/map_merge.h says why).
    if settings.get("keep_radius", 0) or settings.get("recycle"):
        raise BatchError("--keep-radius and --recycle make bounded maps, which forget what they fused: their sum is not the map "
                         "of their frames")
    if settings.get("color_mode") == "recent":
        raise BatchError("--color-mode recent keeps no weights to combine the fragments' colours by (use average or --no-color)")
    if args.fragment_frames < 1:
        raise BatchError(f"--fragment-frames {args.fragment_frames} must be at least 1")
    if args.track and not (1 <= args.overlap < args.fragment_frames):
        raise BatchError(f"--overlap {args.overlap} must be at least 1 and below --fragment-frames ({args.fragment_frames}) "
                         "with --track: consecutive fragments are placed through the frames they share")
    if bool(args.tiles) != (args.tile_size > 0):
        raise BatchError("--tiles DIR and --tile-size S (metres, > 0) go together")
    if not args.output and not args.tiles:
        raise BatchError("give the map (-o map.vkmap), tiles (--tiles DIR --tile-size S), or both")
    if args.mesh and not args.output:
        raise BatchError("--mesh needs -o: without a merged map there are only --tiles")
    if args.tiles_per_task < 0:
        raise BatchError(f"--tiles-per-task {args.tiles_per_task} must be 0 (automatic) or more")
    out = os.path.abspath(args.output) if args.output else None
    if out and os.path.splitext(out)[1] in (".ply", ".obj", ".glb"):
        raise BatchError(f"-o {args.output}: -o is the map (.vkmap); write its mesh with --mesh")
    if args.mesh:
        _vkmesh._check_mesh_path(os.fspath(args.mesh))
    work_dir = os.path.abspath(args.work_dir or (out or os.path.abspath(args.tiles)) + ".batch")
    os.makedirs(work_dir, exist_ok=True)
    fragments = _plan(args.recordings, dataset_options, args.fragment_frames, args.overlap, args.track,
                      args.first_frame, args.frames)
    for f in fragments:
        f["name"] = f"{os.path.basename(f['recording'])} frames {f['first']}-{f['stop'] - 1}"
    device = {k: settings[k] for k in ("device", "validation") if k in settings}

    try:
        from distributed import Client, LocalCluster
    except ImportError as e:
        raise BatchError(f"Dask is needed ({e}): on Debian, apt install python3-distributed") from e
    cluster = None
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(n_workers=args.local_workers, threads_per_worker=1, processes=True,
                               resources={"GPU": 1}, dashboard_address=None)
        client = Client(cluster)
    try:
        workers = client.scheduler_info()["workers"]
        if not any(w.get("resources", {}).get("GPU", 0) >= 1 for w in workers.values()):
            raise BatchError(f"no worker of the scheduler offers the GPU resource: start workers with "
                             f"`dask worker {args.scheduler or 'ADDRESS'} --nthreads 1 --resources GPU=1` (one per GPU)")
        progress = not args.quiet
        phases = {}

        # 1. Fuse every fragment (at the recording's poses, or tracked from its own first frame).
        t0 = time.perf_counter()
        specs = []
        # With --loop-closure each fragment keeps its frames (.vkframes beside its map): register_maps registers them.
        track_settings = {**settings, "keep_frames": True} if args.loop_closure else settings
        for f in fragments:
            spec = {"recording": f["recording"], "dataset": dataset_options, "settings": track_settings, "index": f["index"],
                    "first": f["first"], "stop": f["stop"], "work_dir": work_dir, "name": f["name"],
                    "poses": "track" if args.track else None, "first_pose": None}
            if args.track:
                if f["index"] == 0:
                    ds = vkmesh.open_dataset(f["recording"], require_poses=False, **dataset_options)
                    p = ds[f["first"]].pose
                    spec["first_pose"] = (np.eye(4) if p is None else np.asarray(p)).ravel().tolist()
                else:
                    spec["first_pose"] = np.eye(4).ravel().tolist()
            specs.append(spec)
        fused = _submit_all(client, fuse_fragment, specs, "fragment", args.retries, progress)
        phases["fuse_ms"] = (time.perf_counter() - t0) * 1e3

        # 2. Place (--track): each fragment through the frames it shares with the one before.
        t0 = time.perf_counter()
        finals, placements, trajectory = [], [], []
        previous, transforms, locals_, chain_placed, odometry_paths = None, [], [], [], []
        for f, result in zip(fragments, fused):
            local = _pose_dict(result["frames"])
            if not args.track:
                finals.append(result["map"])
                trajectory += [(f["recording"], i, ts, np.asarray(p).reshape(4, 4)) for i, ts, p, fused_ in result["frames"]]
                continue
            if f["index"] == 0:
                transform, residual = np.eye(4), None
                odometry_paths.append(None)
            else:
                shared = range(f["first"], f["start"])
                transform, residual = place_after(previous, local, shared)
                if transform is None:
                    raise BatchError(f"{f['name']}: none of its first {f['start'] - f['first']} frames was tracked in both it and "
                                     "the fragment before, so it cannot be placed (give a larger --overlap)")
                # The path the fragment before tracked from its first frame to the shared frame this one is placed by
                # (place_after's: the last shared frame both fused): the drift the odometry edge carries.
                before = locals_[-1]
                by = max(i for i in shared if i in previous and i in local)
                odometry_paths.append(_path_length([before[i] for i in sorted(before) if i <= by]))
            placed = {i: transform @ p for i, p in local.items()}
            previous = placed
            transforms.append(transform)
            locals_.append(local)
            chain_placed.append(placed)
            placements.append({"fragment": f["name"], "transform": transform.ravel().tolist(), "overlap": residual})
        phases["place_ms"] = (time.perf_counter() - t0) * 1e3

        # 2b. Loops (--loop-closure; one recording, checked at the start): non-consecutive fragments that come near
        # each other registered on the workers, then one pose graph over the fragments gives their transforms.
        t0 = time.perf_counter()
        loop_stats, registrations = None, []
        if args.loop_closure:
            candidates = loop_candidates(chain_placed)
            tried = [c for c in candidates if c["near"]]
            loop_specs = [{"first_map": fused[c["first"]]["map"], "second_map": fused[c["second"]]["map"], "work_dir": work_dir,
                           "name": f"loop {fragments[c['first']]['name']} / {fragments[c['second']]['name']}"} for c in tried]
            registrations = _submit_all(client, register_fragments, loop_specs, "loop", args.retries, progress) if loop_specs else []
            verified = [(c, r) for c, r in zip(tried, registrations) if r["registration"] is not None]
            loops = [(c["first"], c["second"], np.asarray(r["registration"]["transform"], dtype=np.float64)) for c, r in verified]
            graph_paths = [p if p is not None else (0.0, 0.0) for p in odometry_paths]
            solved, solves, kept, dropped, errors = close_loops(transforms, graph_paths, loops) if loops else (transforms, [], [], [], {})
            pairs = []
            for c, r in zip(tried, registrations):
                entry = {"first": fragments[c["first"]]["name"], "second": fragments[c["second"]]["name"],
                         "fragments": [c["first"], c["second"]], "closest_m": c["closest_m"], "closest_deg": c["closest_deg"],
                         "closest_frames": c["frames"], "ms": r["ms"]}
                if r["registration"] is None:
                    entry.update(status="no loop", reason=r["reason"])
                else:
                    k = next(n for n, (cc, _) in enumerate(verified) if cc is c)
                    reg = r["registration"]
                    entry.update(transform=np.asarray(reg["transform"]).ravel().tolist(),
                                 pairs_registered=reg["pairs_registered"], pairs_verified=reg["pairs_verified"],
                                 pairs_agreeing=reg["pairs_agreeing"], spread_m=reg["spread_m"], spread_degrees=reg["spread_degrees"])
                    if k in kept:
                        entry.update(status="accepted", whitened_error=errors[k])
                    else:
                        entry.update(status="dropped", whitened_error=dict(dropped)[k],
                                     reason=f"disagrees with the odometry and the other loops by {dict(dropped)[k]:.1f} standard "
                                            f"deviations (> {LOOP_MAX_WHITENED})")
                pairs.append(entry)
            loop_stats = {
                "candidates": len(candidates), "tried": len(tried), "verified": len(verified), "accepted": len(kept),
                "pairs": pairs,
                "not_near": [{"fragments": [c["first"], c["second"]], "closest_m": c["closest_m"], "closest_deg": c["closest_deg"]}
                             for c in candidates if not c["near"]],
                "graph": {"solves": solves, "dropped": len(dropped)},
                "placement": [{"fragment": fragments[k]["name"], "before": transforms[k].ravel().tolist(),
                               "after": solved[k].ravel().tolist(),
                               "moved_m": _transform_change(transforms[k], solved[k])[0],
                               "turned_deg": _transform_change(transforms[k], solved[k])[1]} for k in range(len(fragments))],
            }
            transforms = list(solved)
        phases["loops_ms"] = (time.perf_counter() - t0) * 1e3

        # The global poses: each fragment's own frames through its transform (the chain's, or the graph's).
        if args.track:
            for k, (f, result) in enumerate(zip(fragments, fused)):
                transform = transforms[k]
                for i, ts, p, fused_ in result["frames"]:
                    if f["start"] <= i < f["stop"]:
                        trajectory.append((f["recording"], i, ts, transform @ np.asarray(p).reshape(4, 4)))
                f["global"] = {str(i): (transform @ locals_[k][i]).ravel().tolist()
                               for i in range(f["start"], f["stop"]) if i in locals_[k]}

        # 3. Re-fuse (--track): every fragment's own frames at their global poses (the first fragment's are there already:
        # node 0 of the graph is held fixed).
        t0 = time.perf_counter()
        refused = []
        if args.track:
            specs = [{"recording": f["recording"], "dataset": dataset_options, "settings": settings, "index": f["index"],
                      "first": f["start"], "stop": f["stop"], "work_dir": work_dir, "name": f["name"] + " (global poses)",
                      "poses": f["global"], "first_pose": None}
                     for f in fragments if f["index"] > 0]
            refused = _submit_all(client, fuse_fragment, specs, "re-fusion", args.retries, progress)
            finals = [r["map"] for f, r in zip(fragments, fused) if f["index"] == 0] + [r["map"] for r in refused]
        phases["refuse_ms"] = (time.perf_counter() - t0) * 1e3

        # 4. Tiles (--tiles), from the fragments' maps: tile tasks on the workers, each reading the blocks of its tiles
        # only, submitted before the merge tree and running beside it.
        t_tiles = time.perf_counter()
        tile_specs, tile_futures, plan = [], None, None
        if args.tiles:
            plan = vkmesh.list_tiles(finals, args.tile_size)   # the maps' block tables only
            keys = [list(t) for t in plan["tiles"]]
            per_task = args.tiles_per_task or max(1, -(-len(keys) // (4 * len(workers))))
            for i in range(0, len(keys), per_task):
                group = keys[i:i + per_task]
                tile_specs.append({"inputs": finals, "tiles": group, "tile_size": args.tile_size,
                                   "tiles_dir": os.path.abspath(args.tiles), "work_dir": work_dir, "device": device,
                                   "name": f"tiles {i + 1}-{i + len(group)} of {len(keys)}"})
            tile_futures = _submit(client, make_tiles, tile_specs, "tiles", args.retries)

        # 5. Merge in a tree on the workers (with -o); the last merge writes the map and the mesh.
        t0 = time.perf_counter()
        merges = []
        level = finals if out else []
        while level:
            last = len(level) <= args.merge_fan_in
            groups = [level[i:i + args.merge_fan_in] for i in range(0, len(level), args.merge_fan_in)]
            specs = []
            for g in groups:
                spec = {"inputs": g, "work_dir": work_dir, "device": device, "name": f"{len(g)} maps"}
                spec["output"] = out if last else os.path.join(work_dir, _key("merged", {"inputs": g}) + ".vkmap")
                if last and args.mesh:
                    spec["mesh"] = os.path.abspath(args.mesh)
                specs.append(spec)
            results = _submit_all(client, merge_fragment_maps, specs, "merge", args.retries, progress)
            merges += results
            if last:
                break
            level = [r["output"] for r in results]
        phases["merge_ms"] = (time.perf_counter() - t0) * 1e3
        final = merges[-1]["stats"] if merges else None
        made = _gather(tile_futures, tile_specs, "tiles", progress) if tile_futures else []
        phases["tiles_ms"] = (time.perf_counter() - t_tiles) * 1e3

        if args.trajectory:
            with open(args.trajectory, "w") as t:
                t.write("# timestamp tx ty tz qx qy qz qw (camera to world; vkmesh.batch)\n")
                for _, _, ts, p in trajectory:
                    t.write(_tum_line(ts, p))
        phases["total_ms"] = (time.perf_counter() - t_start) * 1e3

        tasks = fused + registrations + refused + merges + made
        per_worker = {}
        for r in tasks:
            w = per_worker.setdefault(r["worker"], {"tasks": 0, "ms": 0.0})
            w["tasks"] += 1
            w["ms"] += r["ms"]
        stats = {
            "output": out, "mesh": final["mesh"] if final else None,
            "frames_integrated": final["frames_integrated"] if final else plan["frames_integrated"],
            "blocks": final["blocks"] if final else {"merged": plan["blocks"]}, "workers": len(workers), "fragments": [
                {"name": f["name"], "recording": f["recording"], "frames": [f["start"], f["stop"]], "fused_from": f["first"],
                 "skipped": r["skipped"], "lost": sum(1 for x in r["frames"] if not x[3]), "ms": r["ms"],
                 "worker": r["worker"], "attempts": r["attempt"]} for f, r in zip(fragments, fused)],
            "placements": placements, "ms": phases, "per_worker": per_worker,
            "retries": sum(_attempts(work_dir, r["key"]) - 1 for r in tasks),
            "merges": len(merges), "warnings": final["warnings"] if final else [],
        }
        if args.tiles:
            stats["tiles"] = _tile_stats(args, plan, tile_specs, made, work_dir)
        if loop_stats is not None:
            stats["loop_closure"] = loop_stats
        if args.stats:
            with open(args.stats, "w") as s:
                json.dump(stats, s, indent=2)
        if not args.keep_work:
            shutil.rmtree(work_dir, ignore_errors=True)
        return stats
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _tile_stats(args, plan, specs, made, work_dir):
    """What the tile tasks made and the most blocks any of them held, against the whole map's: the measure of "no worker
    needs the whole map"."""
    tasks = [{"name": spec["name"], "tiles": len(spec["tiles"]), "written": r["stats"]["count"],
              "triangles": r["stats"]["triangles"], "max_blocks_host": r["stats"]["max_blocks_host"],
              "max_blocks_gpu": r["stats"]["max_blocks_gpu"], "table_blocks": r["stats"]["table_blocks"], "ms": r["ms"],
              "worker": r["worker"], "attempts": _attempts(work_dir, r["key"])} for spec, r in zip(specs, made)]
    return {"path": os.path.abspath(args.tiles), "size_m": args.tile_size, "listed": len(plan["tiles"]),
            "count": sum(t["written"] for t in tasks), "triangles": sum(t["triangles"] for t in tasks),
            "tasks": len(tasks), "map_blocks": plan["blocks"],
            "max_blocks_host": max((t["max_blocks_host"] for t in tasks), default=0),
            "max_blocks_gpu": max((t["max_blocks_gpu"] for t in tasks), default=0), "per_task": tasks}


def _attempts(work_dir, key):
    try:
        with open(os.path.join(work_dir, key + ".attempts")) as f:
            return len(f.read().splitlines())
    except FileNotFoundError:
        return 1


def _tum_line(timestamp, pose):
    r = pose[:3, :3]
    # Rotation matrix to quaternion (x, y, z, w), the branch with the largest diagonal term for accuracy.
    tr = np.trace(r)
    if tr > 0:
        s = np.sqrt(tr + 1.0) * 2
        q = [(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s]
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = np.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k]) * 2
        q = [0.0, 0.0, 0.0, (r[k, j] - r[j, k]) / s]
        q[i] = 0.25 * s
        q[j] = (r[j, i] + r[i, j]) / s
        q[k] = (r[k, i] + r[i, k]) / s
    t = pose[:3, 3]
    return f"{timestamp:.6f} {t[0]:.9f} {t[1]:.9f} {t[2]:.9f} {q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}\n"


def parser():
    p = argparse.ArgumentParser(prog="python3 -m vkmesh.batch", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("recordings", nargs="+", metavar="RECORDING", help="datasets or recordings, as vkmesh fuse reads them")
    p.add_argument("-o", "--output", help="the map (.vkmap); may be left out with --tiles (tiles only)")
    p.add_argument("--mesh", help="also write the map's mesh (.ply, .obj or .glb)")
    p.add_argument("--tiles", help="also write the mesh tile by tile into this folder (tile_X_Y_Z.ply), made by tile tasks "
                                   "that read from the fragments' maps only the blocks of their tiles")
    p.add_argument("--tile-size", type=float, default=0, help="--tiles: the tiles' side in metres")
    p.add_argument("--tiles-per-task", type=int, default=0,
                   help="--tiles: tiles made by one task (default 0: about 4 tasks per worker)")
    p.add_argument("--fragment-frames", type=int, default=100, help="frames per fragment (default 100)")
    p.add_argument("--overlap", type=int, default=10,
                   help="with --track: frames each fragment shares with the one before, to place it (default 10)")
    p.add_argument("--track", action="store_true", help="track the camera (the recordings' poses are not used beyond their first frame)")
    p.add_argument("--loop-closure", action="store_true",
                   help="with --track: register fragments that come back near each other and place every fragment by one "
                        "pose graph over them (the chain as odometry, verified registrations as loops)")
    p.add_argument("--trajectory", help="write every frame's global pose (TUM format)")
    p.add_argument("--first-frame", type=int, default=0, help="start at this frame of each recording")
    p.add_argument("--frames", type=int, default=0, help="use at most the first N frames of each recording (0: all)")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--local-workers", type=int, default=2, help="start a LocalCluster of W worker processes (default 2)")
    group.add_argument("--scheduler", help="a running Dask scheduler's address (workers started with --resources GPU=1)")
    p.add_argument("--retries", type=int, default=2, help="times a failed task is run again (default 2)")
    p.add_argument("--merge-fan-in", type=int, default=4, help="maps added by one merge task (default 4)")
    p.add_argument("--work-dir", help="folder for the fragments' maps, on storage every worker reaches (default: OUTPUT.batch)")
    p.add_argument("--keep-work", action="store_true", help="keep the work folder (a later run with the same inputs reuses it)")
    p.add_argument("--stats", help="write statistics as JSON (time per phase and per worker, fragments, placements, retries)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    added = _add_setting_options(p)
    return p, added


def main(argv=None):
    p, added = parser()
    args = p.parse_args(argv)
    if args.merge_fan_in < 2:
        p.error("--merge-fan-in must be at least 2")
    try:
        stats = run(args, added)
    except (BatchError, vkmesh.Error, ValueError) as e:
        print(f"vkmesh.batch: error: {e}", file=sys.stderr)
        return 2
    made = [f"mesh {stats['mesh']['triangles']} triangles -> {stats['output']}"] if stats["output"] else []
    if "tiles" in stats:
        t = stats["tiles"]
        made.append(f"{t['count']} tiles of {t['size_m']} m, {t['triangles']} triangles -> {t['path']} (a tile task held at "
                    f"most {t['max_blocks_host']} blocks, {t['max_blocks_gpu']} on the GPU; the map has {t['map_blocks']})")
    print(f"vkmesh.batch: {len(stats['fragments'])} fragments on {stats['workers']} workers, {stats['frames_integrated']} frames, "
          f"{stats['blocks']['merged']} blocks, {'; '.join(made)} ({stats['ms']['total_ms'] / 1e3:.1f} s; {stats['retries']} retries)")
    if "loop_closure" in stats:
        lc = stats["loop_closure"]
        print(f"vkmesh.batch: loops: {lc['tried']} fragment pairs tried, {lc['verified']} verified, {lc['accepted']} accepted")
    return 0


if __name__ == "__main__":
    sys.exit(main())
