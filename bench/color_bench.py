#!/usr/bin/python3
"""Colour side by side: vkmesh against Open3D's VoxelBlockGrid with a `color` attribute, on the same frames,
voxel size and truncation, every mesh scored by `vkmesh eval` with the same colour metrics.

For each dataset:
  1. `vkmesh frames` writes the frame list (depth, colour, pose per frame);
  2. bench/open3d_peer_guarded.py fuses it as `vbg` (depth only) and `vbg_color` (colour attribute), so the
     cost of colour in Open3D's integrate is measured on the same run, and writes both meshes;
  3. `vkmesh fuse` writes vkmesh's mesh (with vertex colours once the GPU fusion has them; until then its
     colour columns stay empty) -- skipped with --no-vkmesh, e.g. on a machine without a Vulkan device;
  4. `vkmesh eval MESH --dataset D --color-every K [--gt gt_points.ply]` scores every mesh that has
     colour: MAE per channel (0-255) and PSNR against every Kth input colour image, and against the
     ground-truth colours of a synthetic sequence (a folder holding gt_points.ply).
Writes color_bench.json and prints a Markdown table.

    /usr/bin/python3 bench/color_bench.py --datasets out/synth_room ../shared/datasets/tum_fr1_rpy --frames 60
"""
import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run(cmd, **kw):
    print("+", " ".join(str(c) for c in cmd), file=sys.stderr, flush=True)
    return subprocess.run([str(c) for c in cmd], check=True, **kw)


def has_colors(ply):
    """Whether a PLY's vertices have red/green/blue (reads the header only)."""
    with open(ply, "rb") as f:
        header = b""
        while not header.endswith(b"end_header\n") and len(header) < 65536:
            line = f.readline()
            if not line:
                break
            header += line
    return b"property uchar red" in header or b"property float red" in header


def evaluate(args, mesh, dataset, gt, out_json, color=True):
    """vkmesh eval's JSON for `mesh`: colour against the frames, and against the GT (plus geometry) if any."""
    cmd = [args.vkmesh, "eval", mesh, "--dataset", dataset, "--max-depth", args.max_depth, "--json", out_json]
    if color:
        cmd += ["--color-every", args.color_every]
    if args.frames:
        cmd += ["--frames", args.frames]
    if gt:
        cmd += ["--gt", gt, "--frame-stride", args.color_every]
    run(cmd, stdout=subprocess.DEVNULL)
    return json.loads(Path(out_json).read_text())


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--datasets", nargs="+", required=True, help="dataset folders (with colour images)")
    p.add_argument("--voxel", type=float, default=0.02)
    p.add_argument("--trunc-voxels", type=float, default=4.0)
    p.add_argument("--max-depth", type=float, default=4.0)
    p.add_argument("--frames", type=int, default=0, help="frames per dataset (0 = all)")
    p.add_argument("--color-every", type=int, default=10, help="compare colour with every Kth input frame")
    p.add_argument("--vkmesh", default=str(ROOT / "build/vkmesh"))
    p.add_argument("--device", type=int, default=-1)
    p.add_argument("--no-vkmesh", action="store_true", help="do not run vkmesh fuse (Open3D and eval only)")
    p.add_argument("--threads", type=int, default=0, help="Open3D threads (0 = its own choice)")
    p.add_argument("--out", default=str(ROOT / "out/color_bench"))
    args = p.parse_args()

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = {"voxel": args.voxel, "trunc_voxels": args.trunc_voxels, "max_depth": args.max_depth,
               "color_every": args.color_every, "datasets": []}
    for ds in args.datasets:
        name = Path(ds).name
        if not Path(ds).is_dir():
            print(f"skipping {ds}: not found", file=sys.stderr)
            continue
        gt = Path(ds) / "gt_points.ply"
        gt = str(gt) if gt.is_file() else None
        common = ["--max-depth", args.max_depth] + (["--frames", args.frames] if args.frames else [])
        frames_json = out / f"{name}_frames.json"
        run([args.vkmesh, "frames", ds, "-o", frames_json] + common)
        if not json.loads(frames_json.read_text()).get("has_color"):
            print(f"skipping {ds}: no colour images", file=sys.stderr)
            continue
        peer_json = out / f"{name}_open3d.json"
        peer = ["/usr/bin/python3", ROOT / "bench/open3d_peer_guarded.py", frames_json, "--voxel", args.voxel,
                "--trunc-voxels", args.trunc_voxels, "--methods", "vbg,vbg_color", "--mesh-out", out / name,
                "-o", peer_json]
        if args.threads:
            peer += ["--threads", args.threads]
        run(peer, stdout=subprocess.DEVNULL)
        o3d = json.loads(peer_json.read_text())
        entry = {"dataset": name, "gt": gt, "rows": []}
        for method in ("vbg", "vbg_color"):
            m = o3d["methods"][method]
            row = {"method": "Open3D " + method, "integrate_median_ms": m["median_ms"],
                   "vertices": m["vertices"], "mesh": m.get("mesh_path")}
            # The grey vbg mesh has only geometry to score, which needs a GT.
            if row["mesh"] and (method == "vbg_color" or gt):
                row["eval"] = evaluate(args, row["mesh"], ds, gt, out / f"{name}_eval_{method}.json",
                                       color=method == "vbg_color")
            entry["rows"].append(row)
        # vkmesh twice, depth only (--no-color) and with colour, side by side in one run: the cost of colour
        # is the ratio of the two whole-frame times.
        for label, extra in ([] if args.no_vkmesh else [("vkmesh --no-color", ["--no-color"]), ("vkmesh", [])]):
            tag = "vkmesh" + ("_nocolor" if extra else "")
            mesh, stats = out / name / f"{tag}.ply", out / f"{name}_{tag}_stats.json"
            run([args.vkmesh, "fuse", ds, "-q", "--voxel", args.voxel, "--trunc", args.trunc_voxels, "--device",
                 args.device, "-o", mesh, "--stats", stats] + extra + common, stdout=subprocess.DEVNULL)
            st = json.loads(stats.read_text())
            # Whole frame (upload, allocation, fusion, incremental mesh, fence), the closest to Open3D's
            # integrate that vkmesh reports; the fusion alone is in stats gpu_ms_per_frame.
            row = {"method": label, "vertices": st["mesh"]["vertices"], "mesh": str(mesh), "stats": st,
                   "integrate_median_ms": st["wall_ms_per_frame"]["median"], "has_color": has_colors(mesh)}
            # The depth-only mesh is scored on geometry when there is a GT.
            if row["has_color"] or gt:
                row["eval"] = evaluate(args, mesh, ds, gt, out / f"{name}_eval_{tag}.json",
                                       color=row["has_color"])
            entry["rows"].append(row)
        results["datasets"].append(entry)

    (out / "color_bench.json").write_text(json.dumps(results, indent=1))
    print(markdown(results))


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def markdown(r):
    L = [f"voxel {r['voxel']} m, truncation {r['trunc_voxels']} voxels, colour vs every {r['color_every']}th frame "
         "(MAE per channel 0-255, PSNR dB; `vkmesh eval`)", "",
         "| dataset | method | integrate median ms | colour vs frames MAE r/g/b | PSNR | colour vs GT MAE r/g/b | PSNR | F@2cm |",
         "|---|---|---:|---|---:|---|---:|---:|"]
    for e in r["datasets"]:
        for row in e["rows"]:
            ev = row.get("eval") or {}
            fr, gt = ev.get("color_vs_frames") or {}, ev.get("color_vs_gt") or {}
            f2 = next((s["fscore"] for s in ev.get("scores", []) if abs(s["threshold"] - 0.02) < 1e-9), None)
            mae = lambda c: "-" if not c else "%.1f / %.1f / %.1f" % (c["mae_red"], c["mae_green"], c["mae_blue"])
            psnr = lambda c: "-" if not c else ("inf" if c["psnr"] is None else "%.2f" % c["psnr"])
            L.append(f"| {e['dataset']} | {row['method']} | {fmt(row['integrate_median_ms'], '.2f')} | {mae(fr)} | "
                     f"{psnr(fr)} | {mae(gt)} | {psnr(gt)} | {fmt(f2, '.4f')} |")
    L += ["", "integrate: Open3D compute_unique_block_coordinates + integrate (vbg: depth only, vbg_color: with "
          "the colour attribute); vkmesh: wall time of a whole frame (allocation, fusion, mesh)."]
    return "\n".join(L)


if __name__ == "__main__":
    main()
