# The output of bench/paper_bench.py: the Markdown (Table I shape, every run, Open3D extraction every frame,
# accuracy, the sweep), the Fig. 6a-like vertex plot, and writing the Markdown between the markers of docs/RESULTS.md.
import os

from paper_runs import fmt, get, ratio, vk

BEGIN_MARK = "<!-- paper-bench:begin -->"
END_MARK = "<!-- paper-bench:end -->"
BUSY_WARNING = 0.15
# Table I-shaped comparisons and what the project wants of them.
TARGETS = {
    "whole_vs_o3d_integrate": ("vkmesh whole frame / Open3D VBG integrate", "<=", 1.0),
    "o3d_full_vs_whole": ("Open3D VBG (integrate + extraction every frame) / vkmesh whole frame", ">=", 10.0),
    "vertices_vs_baseline": ("vertices ours / baseline", "<=", 0.2),
}


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
