#!/usr/bin/env bash
# Refinement on (the default) against --no-refine (docs/REFINEMENT.md; docs/RESULTS.md, "Mesh quality", "Refinement").
# For each dataset: vkmesh fuse twice with --stats at 3 cm, then a table of what refinement changes:
# irregular cube share, sliver share, boundary edges (the mesh must not crack), vertices at the position of
# another (none, refined or not: docs/REFINEMENT.md "Vertices"), meshing and fusion GPU ms
# (medians over frames), and on the synthetic room `vkmesh eval` against its ground truth (accuracy, F@1cm).
# Usage: bench/refine_bench.sh [OUT_DIR]   (VKMESH=build/vkmesh, DATASETS=../shared/datasets, FRAMES=all)
set -euo pipefail
cd "$(dirname "$0")/.."
VKMESH=${VKMESH:-build/vkmesh}
DATASETS=${DATASETS:-../shared/datasets}
OUT=${1:-/tmp/refine_bench}
mkdir -p "$OUT"
frames=()
[ -n "${FRAMES:-}" ] && frames=(--frames "$FRAMES")
[ -f "$OUT/room/gt_points.ply" ] || "$VKMESH" synth "$OUT/room" --frames 120 --noise >/dev/null

run() {  # tag dataset flag
    "$VKMESH" fuse "$2" -q -o "$OUT/$1.ply" --stats "$OUT/$1.json" --analyse-mesh --voxel 0.03 --max-depth 4 "${frames[@]}" $3
}
for d in room "$DATASETS/iclnuim_office_traj0" "$DATASETS/tum_fr1_rpy"; do
    name=$(basename "$d")
    path=$d
    [ "$d" = room ] && path=$OUT/room
    run "${name}_refined" "$path" ""
    run "${name}_unrefined" "$path" --no-refine
done
for v in refined unrefined; do
    "$VKMESH" eval "$OUT/room_$v.ply" --gt "$OUT/room/gt_points.ply" --dataset "$OUT/room" --max-depth 4 \
        --json "$OUT/room_${v}_eval.json" >/dev/null
done

python3 - "$OUT" <<'PY'
import json, sys, pathlib
out = pathlib.Path(sys.argv[1])
def get(d, path):
    for k in path.split("."):
        d = d.get(k) if isinstance(d, dict) else None
    return d
print("| dataset | refine | irregular cubes | sliver triangles | boundary edges | coincident vertices | vertices | triangles | meshing ms (median) | fuse ms (median) | accuracy mean (mm) | F@1cm |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for name in ["room", "iclnuim_office_traj0", "tum_fr1_rpy"]:
    for v in ["unrefined", "refined"]:
        s = json.loads((out / f"{name}_{v}.json").read_text())
        acc, f1 = "-", "-"
        ev = out / f"{name}_{v}_eval.json"
        if ev.exists():
            e = json.loads(ev.read_text())
            acc = f"{1000 * e['accuracy_mean']:.2f}"
            f = [t for t in e["scores"] if abs(t["threshold"] - 0.01) < 1e-6]
            f1 = f"{f[0]['fscore']:.3f}" if f else "?"
        print(f"| {name} | {'on' if s['refine'] else 'off'} | {s['mesh']['irregular_cube_share']:.4f} | "
              f"{s['mesh']['sliver_triangle_share']:.4f} | {s['mesh']['boundary_edges']} | {s['mesh'].get('coincident_vertices', '-')} | {s['mesh']['vertices']} | "
              f"{s['mesh']['triangles']} | {get(s, 'gpu_ms_per_frame.mesh_total.median'):.2f} | "
              f"{get(s, 'gpu_ms_per_frame.fuse.median'):.2f} | {acc} | {f1} |")
PY
