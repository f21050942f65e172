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
import os
import platform
import shlex
import shutil
import socket
import sys
import time
from pathlib import Path

# The runs are in paper_runs.py, the Markdown and the plot in paper_tables.py, beside this script.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paper_runs import ROOT, Bench, get, ratio  # noqa: E402
from paper_tables import BEGIN_MARK, END_MARK, markdown, plot_sweep, write_results  # noqa: E402


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
