# The runs of bench/paper_bench.py: vkmesh (fuse, frames, eval, the resolution sweep) and Open3D as subprocesses,
# with the helpers that read their JSON (the Open3D per-frame extraction estimate, eval summaries, stats fields).
import json
import math
import os
import re
import resource
import shlex
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# Per-block cost on the GPU (TSDF sdf + weight, cube state, 3 edge slots: 24 B x 512 cubes) plus its
# share of the hash table and its owned-slot mask (192 B); vertices 32 B + owner/remap/free stack; chunks
# 60 B + stacks. Used only to size the sweep's pools and warn before asking for more memory than the
# machine has.
BLOCK_BYTES = 24 * 512 + 64 + 192
VERTEX_BYTES = 44
CHUNK_BYTES = 68
DEFAULT_BLOCKS, DEFAULT_VERTICES, DEFAULT_CHUNKS = 16384, 1 << 20, 1 << 19


# ---------------------------------------------------------------------------------------------- utilities

def get(d, path, default=None):
    """d['a']['b'] for path 'a.b', or default where any part is missing."""
    for part in path.split("."):
        if not isinstance(d, dict) or part not in d:
            return default
        d = d[part]
    return d


def cpu_jiffies():
    try:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:9]]
    except (OSError, ValueError):
        return None
    return sum(v) - v[3] - v[4], sum(v)


def own_cpu_seconds():
    """CPU seconds of this process and its waited-for children."""
    s = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


class Runner:
    """Runs subprocesses one at a time; logs each to OUT/logs, records how long it took and how much of
    the machine other processes used meanwhile, and turns any failure into a record instead of an exit."""

    def __init__(self, out, timeout):
        self.logs = out / "logs"
        self.logs.mkdir(parents=True, exist_ok=True)
        self.timeout = timeout
        self.records = []
        self.failures = []

    def __call__(self, name, cmd, what=None, timeout=None):
        cmd = [str(c) for c in cmd]
        log = self.logs / f"{name}.log"
        print(f"+ {shlex.join(cmd)}", file=sys.stderr, flush=True)
        j0, c0, t0 = cpu_jiffies(), own_cpu_seconds(), time.perf_counter()
        rc, err = None, ""
        try:
            with open(log, "w") as f:
                p = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, timeout=timeout or self.timeout)
            rc = p.returncode
        except subprocess.TimeoutExpired:
            rc, err = "timeout", f"killed after {timeout or self.timeout} s"
        except OSError as e:
            rc, err = "oserror", str(e)
        seconds = time.perf_counter() - t0
        j1, c1 = cpu_jiffies(), own_cpu_seconds()
        share = None
        if j0 and j1 and j1[1] > j0[1]:
            busy = (j1[0] - j0[0]) - (c1 - c0) * os.sysconf("SC_CLK_TCK")
            share = round(max(0.0, busy / (j1[1] - j0[1])), 3)
        rec = {"name": name, "cmd": shlex.join(cmd), "rc": rc, "seconds": round(seconds, 2),
               "other_cpu_share": share, "log": str(log)}
        self.records.append(rec)
        print(f"  [{seconds:.1f} s, rc {rc}, other processes {share if share is None else f'{100 * share:.0f}%'}]",
              file=sys.stderr, flush=True)
        if rc != 0:
            tail = err or tail_of(log)
            fail = {"what": what or name, "cmd": rec["cmd"], "rc": rc, "stderr_tail": tail, "log": str(log)}
            self.failures.append(fail)
            print(f"FAILED ({what or name}): rc {rc}\n  command: {rec['cmd']}\n  " +
                  "\n  ".join(tail.splitlines()), file=sys.stderr, flush=True)
            return None
        return rec


def tail_of(path, lines=15, chars=2000):
    try:
        text = Path(path).read_text(errors="replace")
    except OSError:
        return ""
    # A tty-less vkmesh prints progress lines; keep the end, where the error is.
    return "\n".join(text.rstrip().splitlines()[-lines:])[-chars:]


def load_json(path):
    try:
        return json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None


def fmt(x, spec=".2f", none="-"):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return none
    return format(x, spec)


def ratio(a, b):
    return a / b if a is not None and b else None


def median(xs):
    return statistics.median(xs) if xs else None


def mean(xs):
    return statistics.fmean(xs) if xs else None


def mem_available_bytes():
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


# ---------------------------------------------------------------------------------------- vkmesh features

def detect_features(vkmesh):
    """Which of the flags and subcommands being added exist in this build (from the --help texts)."""
    def help_text(args):
        try:
            p = subprocess.run([vkmesh] + args, capture_output=True, text=True, timeout=30)
            return p.stdout + p.stderr
        except (OSError, subprocess.TimeoutExpired):
            return ""
    top, fuse = help_text(["--help"]), help_text(["fuse", "--help"])
    has_eval = any(line.strip().startswith("eval ") or line.strip() == "eval" for line in top.splitlines())
    ev = help_text(["eval", "--help"]) if has_eval else ""
    return {
        "vkmesh_runs": bool(top),
        "no_refine": "--no-refine" in fuse,
        "refine": re.search(r"--refine[,\s]", fuse) is not None,
        "refine_eps": "--refine-eps" in fuse,
        "lock_free": "--lock-free" in fuse,
        "analyse_mesh": "--analyse-mesh" in fuse,
        "eval": has_eval,
        "eval_frames": "--frames" in ev,
        "eval_max_depth": "--max-depth" in ev,
    }


# ------------------------------------------------------------------------- Open3D extraction every frame

def estimate_extraction(extractions, n_frames):
    """Extraction time after each frame 1..n, linearly interpolated between the measured extractions
    (after_frames, ms), starting from (0 frames, 0 ms). The mesh, and with it the extraction time, grows
    fast at first and then levels off as the scene is covered (a concave curve), so the chords lie below
    it: the estimate errs low, i.e. in Open3D's favour."""
    pts = sorted({(0, 0.0)} | {(e["after_frames"], e["ms"]) for e in extractions})
    est, j = [], 0
    for k in range(1, n_frames + 1):
        while j + 1 < len(pts) - 1 and pts[j + 1][0] < k:
            j += 1
        (k0, m0), (k1, m1) = pts[j], pts[min(j + 1, len(pts) - 1)]
        est.append(m1 if k1 == k0 or k >= k1 else m0 + (m1 - m0) * (k - k0) / (k1 - k0))
    return est


def o3d_full_per_frame(plain, extract_run, exact_run=None):
    """Open3D VBG 'integrate + full extraction after every frame', per frame: the plain run's integrate
    time of each frame + the (estimated) extraction time after it."""
    vbg = get(plain, "methods.vbg")
    ext = get(extract_run, "methods.vbg.extractions")
    if not vbg or not ext:
        return None
    integ = vbg["integrate_ms"]
    est = estimate_extraction(ext, len(integ))
    total = [a + b for a, b in zip(integ, est)]
    r = {"method": "integrate_ms of the plain run + extraction time interpolated linearly between %d "
                   "measured extractions (after frames %s)" % (len(ext), [e["after_frames"] for e in ext]),
         "extraction_points": [{"after_frames": e["after_frames"], "ms": round(e["ms"], 2),
                                "vertices": e["vertices"]} for e in ext],
         "extraction_ms_mean": mean(est), "median_ms": median(total), "mean_ms": mean(total)}
    exact = get(exact_run, "methods.vbg.extractions")
    if exact and len(exact) == len(integ):
        exact_total = [a + e["ms"] for a, e in zip(integ, exact)]
        r["exact"] = {"median_ms": median(exact_total), "mean_ms": mean(exact_total),
                      "extraction_ms_mean": mean([e["ms"] for e in exact])}
        r["estimate_error_mean"] = r["mean_ms"] / r["exact"]["mean_ms"] - 1.0
        r["estimate_error_median"] = r["median_ms"] / r["exact"]["median_ms"] - 1.0
    return r


# ----------------------------------------------------------------------------------------------- eval JSON

def eval_summary(ev):
    """The fields the tables use from `vkmesh eval --json` (names as in the brief; a few spellings)."""
    if not ev:
        return None
    def pick(*names):
        for n in names:
            v = get(ev, n)
            if isinstance(v, (int, float)):
                return float(v)
        return None
    s = {"accuracy_mean": pick("accuracyMean", "accuracy_mean", "accuracy.mean"),
         "completeness_mean": pick("completenessMean", "completeness_mean", "completeness.mean"),
         "scores": {}}
    scores = ev.get("scores") or []
    thresholds = [get(x, "threshold") for x in scores if isinstance(get(x, "threshold"), (int, float))]
    unit = 0.01 if thresholds and min(thresholds) >= 0.5 else 1.0  # metres expected; cm tolerated
    for x in scores:
        t = get(x, "threshold")
        if not isinstance(t, (int, float)):
            continue
        cm = round(t * unit * 100, 3)
        s["scores"][f"{cm:g}"] = {k: get(x, k) for k in ("precision", "recall", "fscore")}
    return s


def refine_runs(e):
    """The vkmesh variants (keys) with refinement on and off, from the stats' `refine` field or the flag."""
    on = off = None
    for v in ("incremental", "refine", "no_refine"):
        run = e["vkmesh"].get(v) or {}
        if not run.get("ok"):
            continue
        state = get(run, "stats.refine", {"refine": True, "no_refine": False}.get(v))
        if state is True and on is None:
            on = v
        elif state is False and off is None:
            off = v
    return on, off


def vk(e, variant, path):
    return get(e["vkmesh"].get(variant) or {}, "stats." + path)


# ----------------------------------------------------------------------------------------------- the runs

class Bench:
    def __init__(self, args):
        self.a = args
        self.out = Path(args.out).resolve()
        self.out.mkdir(parents=True, exist_ok=True)
        self.run = Runner(self.out, args.timeout)
        self.notes = []
        self.vkmesh = args.vkmesh
        self.features = detect_features(self.vkmesh)
        if not self.features["vkmesh_runs"]:
            self.note(f"{self.vkmesh} does not run: build it (cmake --build build --target vkmesh_cli)")

    def note(self, text):
        if text not in self.notes:
            self.notes.append(text)
            print("note: " + text, file=sys.stderr, flush=True)

    # --- datasets

    def synth_dataset(self):
        a = self.a
        name = f"synth_room_{a.synth_frames}f_{a.synth_width}x{a.synth_height}"
        path = self.out / name
        if (path / "gt_points.ply").is_file() and (path / "depth.txt").is_file():
            print(f"reusing {path}", file=sys.stderr)
            return path
        if self.run("synth", [self.vkmesh, "synth", path, "--frames", a.synth_frames, "--noise",
                              "--width", a.synth_width, "--height", a.synth_height], "generate the synthetic room"):
            return path
        return None

    def datasets(self):
        out = []
        if self.a.datasets:
            for d in self.a.datasets:
                if d == "synth":
                    p = self.synth_dataset()
                    if p:
                        out.append(("synthetic room", p, True))
                elif Path(d).is_dir():
                    out.append((Path(d).name, Path(d).resolve(), False))
                else:
                    self.note(f"dataset {d} not found, skipped")
            return out
        p = self.synth_dataset()
        if p:
            out.append(("synthetic room", p, True))
        for n in ("iclnuim_office_traj0", "tum_fr1_rpy"):
            d = ROOT.parent / "shared/datasets" / n
            if d.is_dir():
                out.append((n, d, False))
            else:
                self.note(f"{d} not found, dataset skipped")
        return out

    # --- vkmesh

    def fuse(self, tag, dataset, extra, voxel, frames, what):
        stats, mesh = self.out / f"{tag}.json", self.out / f"{tag}.ply"
        for f in (stats, mesh):
            f.unlink(missing_ok=True)  # never read a stale result of an earlier run
        cmd = [self.vkmesh, "fuse", dataset, "-q", "-o", mesh, "--stats", stats, "--voxel", voxel,
               "--trunc", self.a.trunc_voxels, "--max-depth", self.a.max_depth, "--device", self.a.device]
        if frames:
            cmd += ["--frames", frames]
        if self.features.get("analyse_mesh"):
            cmd += ["--analyse-mesh"]   # the baseline's vertex count, regularity and topology (null without it)
        rec = self.run(tag, cmd + extra, what)
        s = load_json(stats) if rec else None
        if rec and s is None:
            self.run.failures.append({"what": what, "cmd": rec["cmd"], "rc": 0,
                                      "stderr_tail": f"no stats JSON at {stats}", "log": rec["log"]})
        return {"cmd": rec["cmd"] if rec else None, "ok": s is not None, "stats": s, "mesh": str(mesh) if s else None,
                "seconds": rec["seconds"] if rec else None, "other_cpu_share": rec["other_cpu_share"] if rec else None}

    def dataset_entry(self, label, path, is_synth):
        a = self.a
        tag = path.name if not is_synth else "synth"
        frames = a.frames
        e = {"dataset": label, "path": str(path), "synthetic": is_synth, "vkmesh": {}, "open3d": None,
             "open3d_extract": None, "open3d_exact": None, "open3d_full": None, "eval": {}}
        frames_json = self.out / f"{tag}_frames.json"
        frames_json.unlink(missing_ok=True)
        fcmd = [self.vkmesh, "frames", path, "-o", frames_json, "--max-depth", a.max_depth]
        if frames:
            fcmd += ["--frames", frames]
        self.run(f"{tag}_frames", fcmd, f"{label}: frame list")
        fl = load_json(frames_json)
        e["frames"] = len(fl["frames"]) if fl else None

        # The default run is Table I's "ours". Refinement on and off are both needed (accuracy, irregular
        # shares): the stats say which one the default was (`refine`), and only the other is run explicitly;
        # where they do not say, both explicit variants run.
        e["vkmesh"]["incremental"] = self.fuse(f"{tag}_vkmesh_incremental", path, [], a.voxel, frames,
                                               f"{label}: vkmesh incremental (default)")
        default_refine = vk(e, "incremental", "refine")
        wanted = []
        if default_refine is not True:
            wanted.append(("refine", "--refine"))
        if default_refine is not False:
            wanted.append(("no_refine", "--no-refine"))
        wanted += [("lock_free", "--lock-free"), ("baseline", "--mode baseline")]
        for v, flag in wanted:
            feature = {"--refine": "refine", "--no-refine": "no_refine", "--lock-free": "lock_free"}.get(flag)
            if feature and not self.features[feature]:
                if self.features["vkmesh_runs"]:
                    self.note(f"vkmesh fuse has no {flag} in this build: variant '{v}' skipped")
                e["vkmesh"][v] = {"ok": False, "skipped": f"{flag} not in this build"}
                continue
            e["vkmesh"][v] = self.fuse(f"{tag}_vkmesh_{v}", path, flag.split(), a.voxel, frames, f"{label}: vkmesh {v}")
        if default_refine is None and get(e, "vkmesh.incremental.ok"):
            self.note("the stats have no `refine` field: refinement on/off taken from the explicit "
                      "--refine/--no-refine runs only")

        if fl and not a.no_open3d:
            peer = ["/usr/bin/python3", ROOT / "bench/open3d_peer_guarded.py", frames_json,
                    "--voxel", a.voxel, "--trunc-voxels", a.trunc_voxels]
            plain = self.out / f"{tag}_open3d.json"
            mesh_dir = self.out / f"{tag}_open3d_meshes"
            for f in (plain, mesh_dir / "open3d_vbg.ply", mesh_dir / "open3d_scalable.ply"):
                f.unlink(missing_ok=True)
            if self.run(f"{tag}_open3d", peer + ["--methods", "vbg,scalable", "-o", plain, "--mesh-out", mesh_dir],
                        f"{label}: Open3D VBG + ScalableTSDFVolume"):
                e["open3d"] = load_json(plain)
            n = e["frames"]
            every = max(2, math.ceil(n / a.extraction_points))
            ext = self.out / f"{tag}_open3d_extract_every{every}.json"
            ext.unlink(missing_ok=True)
            if self.run(f"{tag}_open3d_extract", peer + ["--methods", "vbg", "--extract-every", every, "-o", ext],
                        f"{label}: Open3D VBG with extraction every {every} frames"):
                e["open3d_extract"] = load_json(ext)
            if is_synth and a.exact_extraction:
                ex = self.out / f"{tag}_open3d_extract_every1.json"
                ex.unlink(missing_ok=True)
                if self.run(f"{tag}_open3d_exact", peer + ["--methods", "vbg", "--extract-every", 1, "-o", ex],
                            f"{label}: Open3D VBG with extraction after every frame"):
                    e["open3d_exact"] = load_json(ex)
            e["open3d_full"] = o3d_full_per_frame(e["open3d"], e["open3d_extract"], e["open3d_exact"])

        if is_synth:
            self.evaluate(e, tag, path, frames)
        return e

    def evaluate(self, e, tag, path, frames):
        if not self.features["eval"]:
            self.note("vkmesh has no `eval` subcommand yet: accuracy table skipped")
            return
        gt = path / "gt_points.ply"
        meshes = {}
        on, off = refine_runs(e)
        for v, state in ((on, "on"), (off, "off")):
            if v:
                default = " (default)" if v == "incremental" else ""
                meshes[f"vkmesh, refinement {state}{default}"] = e["vkmesh"][v].get("mesh")
        meshes["Open3D VBG"] = get(e, "open3d.methods.vbg.mesh_path")
        for label, mesh in meshes.items():
            if not mesh or not Path(mesh).is_file():
                e["eval"][label] = None
                continue
            out = self.out / f"{tag}_eval_{len(e['eval'])}.json"
            out.unlink(missing_ok=True)
            cmd = [self.vkmesh, "eval", mesh, "--gt", gt, "--dataset", path, "--json", out]
            if self.features["eval_frames"] and frames:
                cmd += ["--frames", frames]
            if self.features["eval_max_depth"]:
                cmd += ["--max-depth", self.a.max_depth]
            rec = self.run(f"{tag}_eval_{len(e['eval'])}", cmd, f"eval {label}")
            raw = load_json(out) if rec else None
            e["eval"][label] = {"cmd": rec["cmd"] if rec else None, "mesh": str(mesh), "raw": raw,
                                "summary": eval_summary(raw), "default": "(default)" in label}

    # --- resolution sweep

    def sweep(self):
        a = self.a
        ds = None
        if a.sweep_dataset:
            ds = Path(a.sweep_dataset)
        else:
            icl = ROOT.parent / "shared/datasets/iclnuim_office_traj0"
            ds = icl if icl.is_dir() else self.synth_dataset()
        if ds is None or not ds.is_dir():
            self.note("no dataset for the resolution sweep")
            return None
        voxels = sorted((float(v) for v in a.sweep_voxels.split(",")), reverse=True)
        res = {"dataset": ds.name, "path": str(ds), "frames": a.sweep_frames, "points": []}
        ref = None  # a successful run: its counts scaled by (v_ref / v)^2 size the next pools
        avail = mem_available_bytes()
        for v in voxels:
            extra = []
            cap = {"blocks": DEFAULT_BLOCKS, "vertices": DEFAULT_VERTICES, "chunks": DEFAULT_CHUNKS}
            if ref:
                scale = (ref["voxel"] / v) ** 2 * a.sweep_headroom
                cap["blocks"] = max(DEFAULT_BLOCKS, int(ref["blocks"] * scale))
                cap["vertices"] = max(DEFAULT_VERTICES, int(ref["vertices"] * scale))
                cap["chunks"] = max(DEFAULT_CHUNKS, int(ref["chunks"] * scale))
            elif v < 0.02:
                scale = (0.03 / v) ** 2
                cap = {k: int(x * scale) for k, x in cap.items()}
            need = cap["blocks"] * BLOCK_BYTES + cap["vertices"] * VERTEX_BYTES + cap["chunks"] * CHUNK_BYTES
            if avail and need > 0.6 * avail:
                f = 0.6 * avail / need
                cap = {k: int(x * f) for k, x in cap.items()}
                self.note(f"sweep {v * 1000:g} mm: pools cut to {f:.0%} of the estimate to fit 60% of "
                          f"available memory ({avail / 2**30:.1f} GiB)")
            for k in ("blocks", "vertices", "chunks"):
                if cap[k] != {"blocks": DEFAULT_BLOCKS, "vertices": DEFAULT_VERTICES, "chunks": DEFAULT_CHUNKS}[k]:
                    extra += [f"--{k}", cap[k]]
            tag = f"sweep_{ds.name}_{v * 1000:g}mm"
            r = self.fuse(tag, ds, extra, v, a.sweep_frames, f"sweep {v * 1000:g} mm")
            s = r["stats"]
            p = {"voxel": v, "ok": r["ok"], "cmd": r["cmd"], "capacities": cap, "seconds": r["seconds"],
                 "other_cpu_share": r["other_cpu_share"]}
            if s:
                p.update({"frames": get(s, "frames.integrated"), "blocks": get(s, "blocks.in_use"),
                          "vertices": get(s, "mesh.vertices"), "baseline_vertices": get(s, "mesh.baseline_vertices"),
                          "triangles": get(s, "mesh.triangles"), "ratio": get(s, "mesh.vertices_vs_baseline"),
                          "mesh_ms": get(s, "gpu_ms_per_frame.mesh_total.median"),
                          "whole_ms": get(s, "wall_ms_per_frame.median"),
                          "vertex_high_water": get(s, "heaps.vertices.high_water"),
                          "chunk_high_water": get(s, "heaps.triangle_chunks.high_water"),
                          "capacity_events": s.get("capacity_events"), "warnings": len(s.get("warnings") or [])})
                if any((s.get("capacity_events") or {}).values()):
                    self.note(f"sweep {v * 1000:g} mm hit a capacity limit: {s['capacity_events']}")
                # The finest successful run so far: the nearest voxel size scales best.
                ref = {"voxel": v, "blocks": p["blocks"] or 1,
                       "vertices": p["vertex_high_water"] or p["vertices"] or 1,
                       "chunks": p["chunk_high_water"] or p["triangles"] or 1}
            res["points"].append(p)
        return res
