#!/usr/bin/python3
"""The paper's evaluation (Dong et al., ICRA 2018: Table I, Fig. 6a, the lock-free comparison, refinement)
as one command, with Open3D 0.16 beside it on the same frames.

    /usr/bin/python3 bench/paper_bench.py [--out DIR] [--quick] [--write-results]

For each dataset (vkmesh's synthetic room, generated once into the out folder; ICL-NUIM office traj0 and
TUM fr1/rpy from ../shared/datasets when present), voxel 3 cm, truncation 4 voxels, max depth 4 m:
  * vkmesh fuse in four variants, each with --stats: the default incremental run (Table I's "ours"), the
    same with refinement the other way (--refine or --no-refine, from the stats' `refine` field),
    --lock-free, and --mode baseline;
  * Open3D VoxelBlockGrid + ScalableTSDFVolume via bench/open3d_peer_guarded.py (open3d_peer.py plus
    work-arounds for two Open3D 0.16.1 bugs) on the frame list `vkmesh frames` writes;
  * a second VoxelBlockGrid run with --extract-every K, from which "integrate + full extraction every
    frame" is estimated (see estimate_extraction); on the synthetic room also measured exactly
    (--extract-every 1) to check the estimate;
  * on the synthetic room, `vkmesh eval` of vkmesh's meshes (refinement on/off) and Open3D VBG's against
    gt_points.ply.
Then a resolution sweep (3 cm .. 8 mm) of vertex counts ours vs baseline on one dataset, plotted like the
paper's Fig. 6a. Writes OUT/paper_bench.json (everything), OUT/paper_bench.md and OUT/vertex_sweep.png
(OUT: out/paper_bench, or out/paper_bench_quick with --quick), and prints the Markdown. --write-results puts
it into docs/RESULTS.md between <!-- paper-bench:begin --> and <!-- paper-bench:end --> and copies the plot
to docs/results/.

Every subprocess failure is reported (command, exit code, stderr tail) and the script goes on with the rest;
flags or stats fields the vkmesh build does not have yet are skipped with a note. Exit code 0 when all ran,
1 when something failed (the outputs are written either way).
"""
import argparse
import datetime
import json
import math
import os
import platform
import re
import resource
import shlex
import shutil
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BEGIN_MARK = "<!-- paper-bench:begin -->"
END_MARK = "<!-- paper-bench:end -->"
# Per-block cost on the GPU (TSDF sdf + weight, cube state, 3 edge slots: 24 B x 512 cubes) plus its
# share of the hash table and its owned-slot mask (192 B); vertices 32 B + owner/remap/free stack; chunks
# 60 B + stacks. Used only to size the sweep's pools and warn before asking for more memory than the
# machine has.
BLOCK_BYTES = 24 * 512 + 64 + 192
VERTEX_BYTES = 44
CHUNK_BYTES = 68
DEFAULT_BLOCKS, DEFAULT_VERTICES, DEFAULT_CHUNKS = 16384, 1 << 20, 1 << 19
BUSY_WARNING = 0.15
# Table I-shaped comparisons and what the project wants of them.
TARGETS = {
    "whole_vs_o3d_integrate": ("vkmesh whole frame / Open3D VBG integrate", "<=", 1.0),
    "o3d_full_vs_whole": ("Open3D VBG (integrate + extraction every frame) / vkmesh whole frame", ">=", 10.0),
    "vertices_vs_baseline": ("vertices ours / baseline", "<=", 0.2),
}


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


# ------------------------------------------------------------------------------------------------- output

def plot_sweep(sweep, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return "matplotlib missing (apt-get install -y --no-install-recommends python3-matplotlib): no plot"
    pts = [p for p in (sweep or {}).get("points", []) if p.get("ok") and p.get("vertices")]
    if not pts:
        return "no successful sweep point: no plot"
    pts.sort(key=lambda p: p["voxel"])
    labels = [f"{p['voxel'] * 1000:g} mm" if p["voxel"] < 0.01 else f"{p['voxel'] * 100:g} cm" for p in pts]
    x = list(range(len(pts)))
    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
    ours = [p["vertices"] for p in pts]
    base = [p["baseline_vertices"] for p in pts]
    ax.plot(x, base, "s-", color="#c05621", label="baseline (3 vertices per triangle)")
    ax.plot(x, ours, "o-", color="#2b6cb0", label="ours (shared vertices)")
    for i, p in enumerate(pts):
        if p["baseline_vertices"]:
            ax.annotate(f"{ours[i] / base[i]:.3f}x", (i, ours[i]), textcoords="offset points", xytext=(0, -14),
                        ha="center", fontsize=8, color="#2b6cb0")
        ax.annotate(f"{base[i]:,}", (i, base[i]), textcoords="offset points", xytext=(0, 6), ha="center", fontsize=7,
                    color="#c05621")
    ax.set_yscale("log")
    ax.set_xticks(x, labels)
    ax.set_xlabel("voxel (cube) size")
    ax.set_ylabel("vertices")
    ax.set_ylim(min(ours) / 3, max(base) * 3)
    ax.set_xlim(-0.5, len(pts) - 0.5)
    ax.set_title(f"Vertex count, {sweep['dataset']}, {pts[0].get('frames')} frames (cf. paper Fig. 6a)", fontsize=10)
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(axis="y", which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return None


def target_cell(key, value):
    if value is None:
        return "-"
    _, op, t = TARGETS[key]
    ok = value <= t if op == "<=" else value >= t
    return f"{value:.3g} ({'met' if ok else 'not met'})"


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


def markdown(r, figure_link=None):
    m = r["meta"]
    L = []
    title = "### Paper evaluation: `bench/paper_bench.py`" + (" (QUICK smoke run, not reference numbers)" if m["quick"] else "")
    L += [title, "",
          f"Command: `{m['command']}` ({m['date']}, total {m['runtime_s']:.0f} s). "
          f"Machine: `{m['hostname']}`, {m['cpus']} CPUs; Vulkan device: {m['device'] or 'unknown'}; "
          f"Open3D {m['open3d_version'] or '-'} (CPU, all cores). Voxel {m['voxel'] * 100:g} cm, truncation "
          f"{m['trunc_voxels']:g} voxels, max depth {m['max_depth']:g} m, "
          f"{'frames limited to ' + str(m['frames_limit']) if m['frames_limit'] else 'all frames'}. "
          "Times are medians over frames; vkmesh: GPU timestamps (meshing) and host wall time of a whole frame "
          "(upload, allocation, fusion, mesh update, fence wait; PNG decoding excluded), Open3D: `perf_counter` "
          "around its calls.", ""]

    # Table I
    states = {str(vk(e, "incremental", "refine")) for e in r["datasets"] if vk(e, "incremental", "refine") is not None}
    ours = "vkmesh default run" + (f" (refinement {'on' if states == {'True'} else 'off'})" if len(states) == 1 else "")
    L += [f"#### Table I (paper) shape, voxel {m['voxel'] * 100:g} cm", "", f"Ours = {ours}; lock-free = the same with `--lock-free`.", "",
          "| dataset | frames | meshing ms/frame (ours) | all ms/frame (ours) | vertices ours | baseline | ours / baseline "
          "| lock-free / lock-based meshing | Open3D VBG integrate ms | Open3D VBG integrate + extraction ms/frame "
          "| Open3D VBG vertices |",
          "|---|---|---|---|---|---|---|---|---|---|---|"]
    for e in r["datasets"]:
        inc = "incremental"
        mesh = vk(e, inc, "gpu_ms_per_frame.mesh_total.median")
        lf = vk(e, "lock_free", "gpu_ms_per_frame.mesh_total.median")
        L.append("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |".format(
            e["dataset"], vk(e, inc, "frames.integrated") or e.get("frames") or "-", fmt(mesh),
            fmt(vk(e, inc, "wall_ms_per_frame.median")), fmt(vk(e, inc, "mesh.vertices"), "d"),
            fmt(vk(e, inc, "mesh.baseline_vertices"), "d"), fmt(vk(e, inc, "mesh.vertices_vs_baseline"), ".3f"),
            fmt(ratio(lf, mesh), ".2f"), fmt(get(e, "open3d.methods.vbg.median_ms")),
            fmt(get(e, "open3d_full.median_ms"), ".1f"), fmt(get(e, "open3d.methods.vbg.vertices"), "d")))
    L += ["", "Targets:", "",
          "| dataset | " + " | ".join(f"{v[0]} (target {v[1]} {v[2]:g})" for v in TARGETS.values()) + " |",
          "|---|---|---|---|"]
    for e in r["datasets"]:
        t = e.get("targets", {})
        L.append(f"| {e['dataset']} | " + " | ".join(target_cell(k, t.get(k)) for k in TARGETS) + " |")

    # Details
    share_fields = [f for f in ("irregular_cube_share", "irregular_triangle_share", "sliver_triangle_share")
                    if any(get(run or {}, "stats.mesh." + f) is not None for e in r["datasets"] for run in e["vkmesh"].values())]
    share_names = {"irregular_cube_share": "irregular cubes", "irregular_triangle_share": "irregular triangles",
                   "sliver_triangle_share": "sliver triangles"}
    cols = ["dataset", "run", "refine", "meshing ms (median)", "meshing ms, last 10% frames (mean)", "alloc + fuse ms",
            "whole frame ms", "final extraction ms", "vertices", "triangles"] + [share_names[f] for f in share_fields] + \
           ["other CPU load"]
    L += ["", f"#### Every run, voxel {m['voxel'] * 100:g} cm", "", "| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    blank = " |" * (len(cols) - 3)
    labels = (("incremental", "vkmesh default (incremental)"), ("refine", "vkmesh --refine"),
              ("no_refine", "vkmesh --no-refine"), ("lock_free", "vkmesh --lock-free"),
              ("baseline", "vkmesh --mode baseline"))
    for e in r["datasets"]:
        for v, label in labels:
            if v not in e["vkmesh"]:
                continue
            run = e["vkmesh"][v]
            if run.get("skipped"):
                L.append(f"| {e['dataset']} | {label} | skipped: {run['skipped']} |{blank}")
                continue
            if not run.get("ok"):
                L.append(f"| {e['dataset']} | {label} | FAILED (see Failures) |{blank}")
                continue
            s = run["stats"]
            af = None
            if get(s, "gpu_ms_per_frame.allocate.median") is not None:
                af = get(s, "gpu_ms_per_frame.allocate.median") + (get(s, "gpu_ms_per_frame.fuse.median") or 0)
            export = get(s, "wall_ms_mesh_export") if v == "baseline" else None
            refine = get(s, "refine")
            refine = "-" if refine is None or v == "baseline" else \
                ("on, ε %g voxels" % get(s, "refine_epsilon_voxels") if refine and get(s, "refine_epsilon_voxels") is not None
                 else "on" if refine else "off")
            cells = [e["dataset"], label, refine, fmt(get(s, "gpu_ms_per_frame.mesh_total.median")),
                     fmt(get(s, "gpu_ms_mesh_last_10pct_frames.mean")), fmt(af), fmt(get(s, "wall_ms_per_frame.median")),
                     fmt(export, ".1f") + (" (marching cubes once, wall)" if export is not None else ""),
                     fmt(get(s, "mesh.vertices"), "d"), fmt(get(s, "mesh.triangles"), "d")]
            cells += [fmt(get(s, "mesh." + f), ".4f") if v != "baseline" else "-" for f in share_fields]
            cells.append(fmt(run.get("other_cpu_share"), ".0%"))
            L.append("| " + " | ".join(cells) + " |")
        for mth, label in (("vbg", "Open3D VoxelBlockGrid"), ("scalable", "Open3D ScalableTSDFVolume")):
            o = get(e, f"open3d.methods.{mth}")
            if not o:
                L.append(f"| {e['dataset']} | {label} | {'not run' if r['meta']['no_open3d'] else 'FAILED (see Failures)'} |{blank}")
                continue
            shares = [x for x in (get(e, "open3d.other_cpu_share_before"), get(e, "open3d.other_cpu_share_during"))
                      if x is not None]
            cells = [e["dataset"], label, "-", "-", "-", fmt(o["median_ms"]) + " (integrate)", "-",
                     fmt(o["extract_ms"], ".1f"), f"{o['vertices']} (welded)", str(o["triangles"])]
            cells += ["-"] * len(share_fields) + [fmt(max(shares) if shares else None, ".0%")]
            L.append("| " + " | ".join(cells) + " |")
    L += ["", "- *alloc + fuse*: GPU medians of the two stages; *whole frame*: host wall time of one frame (vkmesh) or "
          "the integrate calls (Open3D); *final extraction*: baseline marching cubes / Open3D `extract_triangle_mesh` "
          "once after the last frame.",
          "- " + ", ".join(f"*{share_names[f]}*: `mesh.{f}`" for f in share_fields) +
          " of the stats (paper §V.F; see docs/REFINEMENT.md)." if share_fields else
          "- The stats of this build have no irregular-share fields.",
          "- *other CPU load*: share of the machine's CPU time used by other processes during the run "
          f"(above {BUSY_WARNING:.0%} the timings are suspect; Open3D's OpenMP loops slow down 10-30x on a busy machine)."]

    # Open3D extraction every frame
    L += ["", "#### Open3D: integrate + full extraction every frame", "",
          "Extracting after every frame of a long sequence takes minutes, so `open3d_peer.py --extract-every K` "
          "times a full `extract_triangle_mesh` after every K-th frame (K = frames / "
          f"{r['meta']['extraction_points']}, rounded up) in a separate run; the extraction time after each "
          "frame is interpolated linearly between those points, from 0 ms at 0 frames, and added to that frame's "
          "integrate time from the plain run. On the synthetic room the script also extracts after every frame "
          "(`--extract-every 1`, same frames) to check the estimate: the last column is the estimate's error "
          "against that (positive: the estimate overstates Open3D's per-frame cost).", "",
          "| dataset | K | extraction points | mean extraction ms (estimated) | integrate + extraction ms/frame "
          "(median, mean) | exact (every frame): median, mean | estimate error (mean) |",
          "|---|---|---|---|---|---|---|"]
    for e in r["datasets"]:
        f = e.get("open3d_full")
        if not f:
            L.append(f"| {e['dataset']} | - | - | - | - | - | - |")
            continue
        pts = f["extraction_points"]
        k = pts[0]["after_frames"] if len(pts) > 1 else "-"
        ex = f.get("exact")
        L.append("| {} | {} | {} | {} | {}, {} | {} | {} |".format(
            e["dataset"], k, len(pts), fmt(f["extraction_ms_mean"], ".1f"), fmt(f["median_ms"], ".1f"),
            fmt(f["mean_ms"], ".1f"), f"{ex['median_ms']:.1f}, {ex['mean_ms']:.1f}" if ex else "-",
            fmt(100 * f["estimate_error_mean"], "+.1f") + " %" if "estimate_error_mean" in f else "-"))

    # Accuracy
    L += ["", "#### Accuracy on the synthetic room (`vkmesh eval` against `gt_points.ply`)", ""]
    evals = [(e["dataset"], lbl, v) for e in r["datasets"] for lbl, v in (e.get("eval") or {}).items()]
    raw = next((v["raw"] for _, _, v in evals if v and v.get("raw")), None)
    if raw:
        L += ["Accuracy and precision: mesh samples (by area, every {} mm) against {}; completeness and recall: {} "
              "({} of {} GT points, seen in {} frames), against the mesh samples. Distances capped at {} cm.".format(
                  fmt(1000 * get(raw, "options.sample_spacing", float("nan")), "g"),
                  get(raw, "options.precision_against", "?"), get(raw, "options.recall_of", "the seen GT points"),
                  get(raw, "gt_points_seen", "?"), get(raw, "gt_points", "?"), get(raw, "dataset.frames_evaluated", "?"),
                  fmt(100 * get(raw, "options.max_distance", float("nan")), "g")), ""]
    if not evals:
        L.append("Not measured: " + ("this vkmesh build has no `eval` subcommand." if not r["meta"]["features"]["eval"]
                                     else "no synthetic dataset."))
    else:
        th = ["1", "2", "5"]
        L += ["| mesh | accuracy mean (mm) | completeness mean (mm) | " +
              " | ".join(f"P / R / F @{t} cm" for t in th) + " |", "|---|---|---|" + "---|" * len(th)]
        for ds, lbl, v in evals:
            s = (v or {}).get("summary")
            if not s:
                L.append(f"| {lbl} | {'FAILED' if v else 'no mesh'} | | " + " | " * (len(th) - 1) + " |")
                continue
            cells = []
            for t in th:
                x = s["scores"].get(t)
                cells.append(" / ".join(fmt(x.get(k), ".3f") for k in ("precision", "recall", "fscore")) if x else "-")
            L.append("| {} | {} | {} | {} |".format(lbl, fmt(None if s["accuracy_mean"] is None else 1000 * s["accuracy_mean"], ".1f"),
                                                   fmt(None if s["completeness_mean"] is None else 1000 * s["completeness_mean"], ".1f"),
                                                   " | ".join(cells)))
        f_ours = get(r, "accuracy_target.vkmesh_f1cm")
        f_o3d = get(r, "accuracy_target.open3d_f1cm")
        if f_ours is not None and f_o3d is not None:
            L += ["", f"Target F@1cm vkmesh ≥ Open3D VBG: {f_ours:.3f} vs {f_o3d:.3f} "
                      f"({'met' if f_ours >= f_o3d else 'not met'})."]

    # Sweep
    sw = r.get("sweep")
    L += ["", "#### Vertex count over resolution (paper Fig. 6a)", ""]
    if not sw:
        L.append("Not run.")
    else:
        L += [f"{sw['dataset']}, first {sw['frames']} frames, vkmesh default (incremental) run per voxel size; the "
              "baseline count is the same run's TSDF meshed Chisel-style (3 vertices per triangle).", ""]
        if figure_link:
            L += [f"![vertex count ours vs baseline over voxel size]({figure_link})", ""]
        L += ["| voxel | frames | blocks | vertices ours | baseline | ours / baseline | triangles | meshing ms/frame "
              "| whole frame ms | pools (blocks / vertices / chunks) | run s |", "|---|---|---|---|---|---|---|---|---|---|---|"]
        for p in sw["points"]:
            c = p["capacities"]
            pools = f"{c['blocks']} / {c['vertices']} / {c['chunks']}"
            if not p["ok"]:
                L.append(f"| {p['voxel'] * 1000:g} mm | FAILED (see Failures) | | | | | | | | {pools} | {fmt(p['seconds'], '.0f')} |")
                continue
            L.append("| {:g} mm | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |".format(
                p["voxel"] * 1000, p["frames"], p["blocks"], p["vertices"], p["baseline_vertices"], fmt(p["ratio"], ".3f"),
                p["triangles"], fmt(p["mesh_ms"]), fmt(p["whole_ms"]), pools, fmt(p["seconds"], ".0f")))

    # Notes and failures
    L += ["", "#### Notes", ""] + [f"- {n}" for n in r["notes"]]
    # Runs under a second are left out: over such short intervals the share is mostly noise.
    busy = [x for x in r["runs"] if (x.get("other_cpu_share") or 0) > BUSY_WARNING and (x.get("seconds") or 0) >= 1]
    if busy:
        timed = [x for x in r["runs"] if (x.get("seconds") or 0) >= 1]
        L.append(f"- **{len(busy)} of {len(timed)} runs (of 1 s or more) had other processes using more than {BUSY_WARNING:.0%} of "
                 "the CPU** (their timings are not representative): " + ", ".join(x["name"] for x in busy) + ".")
    L += ["", "#### Failures", ""]
    if not r["failures"]:
        L.append("None.")
    for f in r["failures"]:
        L += [f"- {f['what']}: exit {f['rc']}, `{f['cmd']}`", "", "  ```", *("  " + x for x in f["stderr_tail"].splitlines()),
              "  ```"]
    return "\n".join(L) + "\n"


def write_results(path, md):
    text = path.read_text() if path.is_file() else ""
    block = f"{BEGIN_MARK}\n{md.rstrip()}\n{END_MARK}"
    b, e = text.find(BEGIN_MARK), text.find(END_MARK)
    if b != -1 and e > b:
        text = text[:b] + block + text[e + len(END_MARK):]
    else:
        text = text.rstrip("\n") + ("\n\n" if text else "") + block + "\n"
    tmp = path.with_name(path.name + ".paper_bench.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


# --------------------------------------------------------------------------------------------------- main

def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default=None,
                   help="output folder (default out/paper_bench, with --quick out/paper_bench_quick)")
    p.add_argument("--quick", action="store_true",
                   help="smoke test: 30 frames per dataset (synthetic room of 30 frames), sweep 3 cm and 1.5 cm only")
    p.add_argument("--write-results", action="store_true",
                   help="write the Markdown into docs/RESULTS.md between the paper-bench markers and the plot to "
                        "docs/results/vertex_sweep.png")
    p.add_argument("--results-file", default=str(ROOT / "docs/RESULTS.md"), help=argparse.SUPPRESS)
    p.add_argument("--figure", default=str(ROOT / "docs/results/vertex_sweep.png"),
                   help="where --write-results puts the plot (default docs/results/vertex_sweep.png)")
    p.add_argument("--vkmesh", default=str(ROOT / "build/vkmesh"))
    p.add_argument("--device", type=int, default=-1, help="vkmesh --device")
    p.add_argument("--datasets", nargs="+", metavar="DIR",
                   help="instead of the default three; 'synth' stands for the generated synthetic room")
    p.add_argument("--frames", type=int, default=None, help="frames per dataset (default: all; --quick: 30)")
    p.add_argument("--voxel", type=float, default=0.03)
    p.add_argument("--trunc-voxels", type=float, default=4.0)
    p.add_argument("--max-depth", type=float, default=4.0)
    p.add_argument("--synth-frames", type=int, default=None, help="synthetic room frames (default 120; --quick: 30)")
    p.add_argument("--synth-width", type=int, default=640)
    p.add_argument("--synth-height", type=int, default=480)
    p.add_argument("--extraction-points", type=int, default=20,
                   help="Open3D extractions per sequence for the per-frame extraction estimate (default 20)")
    p.add_argument("--no-exact-extraction", dest="exact_extraction", action="store_false",
                   help="skip the every-frame Open3D extraction on the synthetic room (the estimate's check)")
    p.add_argument("--no-open3d", action="store_true", help="skip Open3D")
    p.add_argument("--sweep-dataset", help="dataset of the resolution sweep (default ICL office, else the synthetic room)")
    p.add_argument("--sweep-voxels", default=None, help="metres, comma-separated (default 0.03,0.02,0.015,0.01,0.008; "
                                                        "--quick: 0.03,0.015)")
    p.add_argument("--sweep-frames", type=int, default=None, help="frames of the sweep (default 60; --quick: 30)")
    p.add_argument("--sweep-headroom", type=float, default=2.0,
                   help="pool sizes at a finer voxel = counts of the previous one x (ratio of voxel sizes)^2 x this")
    p.add_argument("--no-sweep", action="store_true")
    p.add_argument("--timeout", type=int, default=900, help="seconds before any one subprocess is killed")
    p.add_argument("--from-json", metavar="PATH",
                   help="run nothing: render the Markdown of an earlier run's paper_bench.json (and with "
                        "--write-results put it into docs/RESULTS.md, the plot from next to the JSON)")
    a = p.parse_args(argv)
    if a.out is None:
        a.out = str(ROOT / ("out/paper_bench_quick" if a.quick else "out/paper_bench"))
    if a.frames is None:
        a.frames = 30 if a.quick else 0
    if a.synth_frames is None:
        a.synth_frames = 30 if a.quick else 120
    if a.sweep_voxels is None:
        a.sweep_voxels = "0.03,0.015" if a.quick else "0.03,0.02,0.015,0.01,0.008"
    if a.sweep_frames is None:
        a.sweep_frames = 30 if a.quick else 60
    return a


def render_only(a):
    src = Path(a.from_json)
    r = json.loads(src.read_text())
    fig_out = src.parent / "vertex_sweep.png"
    link = None
    if a.write_results and fig_out.is_file():
        fig = Path(a.figure)
        fig.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(fig_out, fig)
        link = os.path.relpath(fig, Path(a.results_file).parent)
    md = markdown(r, link if a.write_results else fig_out.name if fig_out.is_file() else None)
    if a.write_results:
        write_results(Path(a.results_file), md)
        print(f"wrote {a.results_file} (between {BEGIN_MARK} and {END_MARK})", file=sys.stderr)
    print(md)
    return 0


def main(argv=None):
    t0 = time.perf_counter()
    a = parse_args(argv)
    if a.from_json:
        return render_only(a)
    b = Bench(a)
    r = {"meta": {"command": shlex.join([Path(sys.executable).as_posix(), "bench/paper_bench.py"] + sys.argv[1:]),
                  "date": datetime.datetime.now().isoformat(timespec="seconds"), "hostname": socket.gethostname(),
                  "platform": platform.platform(), "cpus": os.cpu_count(), "quick": a.quick, "voxel": a.voxel,
                  "trunc_voxels": a.trunc_voxels, "max_depth": a.max_depth, "frames_limit": a.frames,
                  "extraction_points": a.extraction_points, "no_open3d": a.no_open3d, "features": b.features,
                  "vkmesh": a.vkmesh},
         "datasets": []}
    for label, path, is_synth in b.datasets():
        e = b.dataset_entry(label, path, is_synth)
        inc = get(e, "vkmesh.incremental.stats") or {}
        whole = get(inc, "wall_ms_per_frame.median")
        e["targets"] = {
            "whole_vs_o3d_integrate": ratio(whole, get(e, "open3d.methods.vbg.median_ms")),
            "o3d_full_vs_whole": ratio(get(e, "open3d_full.median_ms"), whole),
            "vertices_vs_baseline": get(inc, "mesh.vertices_vs_baseline"),
        }
        r["datasets"].append(e)
        if e.get("eval"):
            ours = next((x for x in e["eval"].values() if x and x.get("default")), None)
            f1 = lambda x: get((x or {}).get("summary") or {}, "scores.1.fscore")
            r["accuracy_target"] = {"vkmesh_f1cm": f1(ours), "open3d_f1cm": f1(e["eval"].get("Open3D VBG"))}
    r["sweep"] = None if a.no_sweep else b.sweep()

    devices = [get(e, f"vkmesh.{v}.stats.device") for e in r["datasets"] for v in e["vkmesh"]]
    r["meta"]["device"] = next((d for d in devices if d), None)
    r["meta"]["open3d_version"] = next((get(e, "open3d.open3d_version") for e in r["datasets"] if e.get("open3d")), None)
    if any(get(e, "open3d.vbg_guard") for e in r["datasets"]):
        b.note("Open3D runs go through bench/open3d_peer_guarded.py: a dummy block far away takes hash slot 0, "
               "which sidesteps Open3D 0.16.1's off-by-one assert in VoxelBlockGrid.extract_triangle_mesh "
               "(isl-org/Open3D#7535; it aborted 3 of 6 identical runs on the synthetic room), and an extraction "
               "with nothing to extract counts as 0 vertices instead of raising")
    r["notes"], r["failures"], r["runs"] = b.notes, b.run.failures, b.run.records

    fig_out = b.out / "vertex_sweep.png"
    fig_out.unlink(missing_ok=True)
    if r["sweep"]:
        msg = plot_sweep(r["sweep"], fig_out)
        if msg:
            b.note(msg)
    r["meta"]["runtime_s"] = time.perf_counter() - t0

    results_file = Path(a.results_file)
    link = None
    if a.write_results and fig_out.is_file():
        fig = Path(a.figure)
        fig.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(fig_out, fig)
        link = os.path.relpath(fig, results_file.parent)
    md = markdown(r, link if a.write_results else fig_out.name if fig_out.is_file() else None)
    (b.out / "paper_bench.md").write_text(md)
    (b.out / "paper_bench.json").write_text(json.dumps(r, indent=1, default=str))
    if a.write_results:
        write_results(results_file, md)
        print(f"wrote {results_file} (between {BEGIN_MARK} and {END_MARK})", file=sys.stderr)
    print(md)
    print(f"paper_bench: {r['meta']['runtime_s']:.0f} s, {len(r['failures'])} failures; {b.out / 'paper_bench.json'}",
          file=sys.stderr)
    return 1 if r["failures"] else 0


if __name__ == "__main__":
    sys.exit(main())
