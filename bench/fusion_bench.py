#!/usr/bin/env python3
"""vkmesh (on its default Vulkan device) against Open3D 0.16 on the same frames, voxel size and
truncation, all in one run, so the ratios are measured side by side:
  1. allocation + fusion per frame (vkmesh --mode baseline, once per allocation stride) vs Open3D
     VoxelBlockGrid compute_unique_block_coordinates + integrate (and ScalableTSDFVolume.integrate);
  2. the incremental shared-vertex mesh (vkmesh default) per frame vs Open3D's full extraction at the
     end of the sequence, and vertex counts ours / baseline / Open3D.

For each dataset: `vkmesh frames` writes the exact frame list, `vkmesh fuse --stats` runs, and
bench/open3d_peer.py runs the Open3D methods on that list. Writes a JSON with everything and prints
Markdown tables (docs/RESULTS.md quotes them).

Run with /usr/bin/python3 after `scripts/install_deps.sh --bench` and `scripts/build.sh`:
    /usr/bin/python3 bench/fusion_bench.py --out out/bench
"""
import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run(cmd, **kw):
    print("+", " ".join(str(c) for c in cmd), file=sys.stderr, flush=True)
    return subprocess.run([str(c) for c in cmd], check=True, **kw)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--datasets", nargs="+",
                   default=[str(ROOT.parent / "shared/datasets/iclnuim_office_traj0"),
                            str(ROOT.parent / "shared/datasets/tum_fr1_rpy")])
    p.add_argument("--voxel", type=float, default=0.03)
    p.add_argument("--trunc-voxels", type=float, default=4.0)
    p.add_argument("--max-depth", type=float, default=4.0)
    p.add_argument("--frames", type=int, default=0, help="frames per dataset (0 = all)")
    p.add_argument("--strides", default="1,2,4", help="vkmesh allocation strides to run")
    p.add_argument("--methods", default="vbg,scalable", help="Open3D methods")
    p.add_argument("--vkmesh", default=str(ROOT / "build/vkmesh"))
    p.add_argument("--device", type=int, default=-1)
    p.add_argument("--out", default=str(ROOT / "out/bench"))
    args = p.parse_args()

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = {"date": datetime.datetime.now().isoformat(timespec="seconds"), "machine": platform.node(),
               "cpus": os.cpu_count(), "voxel": args.voxel, "trunc_voxels": args.trunc_voxels,
               "max_depth": args.max_depth, "datasets": []}
    for ds in args.datasets:
        name = Path(ds).name
        if not Path(ds).is_dir():
            print(f"skipping {ds}: not found", file=sys.stderr)
            continue
        frames_json = out / f"{name}_frames.json"
        common = ["--max-depth", args.max_depth] + (["--frames", args.frames] if args.frames else [])
        run([args.vkmesh, "frames", ds, "-o", frames_json] + common)
        entry = {"dataset": name, "vkmesh": {}, "incremental": None, "open3d": None}
        fuse = [args.vkmesh, "fuse", ds, "-q", "--voxel", args.voxel, "--trunc", args.trunc_voxels,
                "--device", args.device] + common
        for stride in args.strides.split(","):
            stats = out / f"{name}_vkmesh_baseline_s{stride}.json"
            run(fuse + ["--mode", "baseline", "--alloc-stride", stride, "-o", out / f"{name}_vkmesh_baseline_s{stride}.ply",
                        "--stats", stats], stdout=subprocess.DEVNULL)
            entry["vkmesh"][stride] = json.loads(stats.read_text())
        stats = out / f"{name}_vkmesh_incremental.json"
        run(fuse + ["-o", out / f"{name}_vkmesh_incremental.ply", "--stats", stats, "--analyse-mesh"], stdout=subprocess.DEVNULL)
        entry["incremental"] = json.loads(stats.read_text())
        peer = out / f"{name}_open3d.json"
        run(["/usr/bin/python3", ROOT / "bench/open3d_peer_guarded.py", frames_json, "--voxel", args.voxel,
             "--trunc-voxels", args.trunc_voxels, "--methods", args.methods, "-o", peer], stdout=subprocess.DEVNULL)
        entry["open3d"] = json.loads(peer.read_text())
        results["datasets"].append(entry)

    (out / "fusion_bench.json").write_text(json.dumps(results, indent=1))
    print(markdown(results))


def markdown(r):
    lines = [f"Voxel {r['voxel'] * 100:g} cm, truncation {r['trunc_voxels']:g} voxels, max depth {r['max_depth']:g} m; "
             f"{r['date']}, {r['cpus']} CPUs.", "",
             "| dataset | frames | method | alloc ms | fuse ms | per frame ms (median) | ratio to Open3D VBG | blocks | baseline vertices | triangles |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for e in r["datasets"]:
        o3d = e["open3d"]["methods"]
        vbg = o3d.get("vbg", {}).get("median_ms")
        for stride, s in e["vkmesh"].items():
            g = s["gpu_ms_per_frame"]
            wall = s["wall_ms_per_frame"]["median"]
            ratio = f"{wall / vbg:.2f}x" if vbg else "-"
            lines.append(f"| {e['dataset']} | {s['frames']['integrated']} | vkmesh, stride {stride} ({s['device'].split(' (')[0]}) | "
                         f"{g['allocate']['median']:.2f} | {g['fuse']['median']:.2f} | {wall:.2f} | {ratio} | "
                         f"{s['blocks']['in_use']} | {s['mesh']['vertices']} | {s['mesh']['triangles']} |")
        for m, v in o3d.items():
            lines.append(f"| {e['dataset']} | {e['open3d']['num_frames']} | Open3D {e['open3d']['open3d_version']} {m} | "
                         f"- | - | {v['median_ms']:.2f} | {v['median_ms'] / vbg:.2f}x | {v['blocks'] if v['blocks'] is not None else '-'} | "
                         f"{v['vertices']} (welded) | {v['triangles']} |")
    lines += ["", "Incremental shared-vertex mesh (vkmesh default, allocation stride 2) vs Open3D's full extraction:", "",
              "| dataset | frames | vkmesh mesh ms/frame (median) | ... last 10% of frames (mean) | Open3D VBG extract_triangle_mesh ms (end) | ratio | vkmesh whole frame ms | vertices ours | baseline | Open3D VBG | ours / baseline | ours / Open3D | triangles ours / Open3D |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for e in r["datasets"]:
        s = e["incremental"]
        vbg = e["open3d"]["methods"].get("vbg")
        mesh = s["gpu_ms_per_frame"]["mesh_total"]["median"]
        tail = s["gpu_ms_mesh_last_10pct_frames"]["mean"]
        ours, base = s["mesh"]["vertices"], s["mesh"]["baseline_vertices"]
        lines.append(f"| {e['dataset']} | {s['frames']['integrated']} | {mesh:.2f} | {tail:.2f} | {vbg['extract_ms']:.1f} | "
                     f"{tail / vbg['extract_ms']:.2f}x | {s['wall_ms_per_frame']['median']:.2f} | {ours} | {base} | {vbg['vertices']} | "
                     f"{ours / base:.3f} | {ours / vbg['vertices']:.3f} | {s['mesh']['triangles']} / {vbg['triangles']} |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
