#!/bin/bash
# Two builds of vkmesh side by side on the same sequences: fusion's cost (wall and GPU ms per frame, medians) and
# accuracy (the synthetic room's F-score against its ground truth, colour error against every 10th input frame),
# runs alternating A B A B so that the machine's drift hits both alike. Used for issue 29 (exact fusion against
# the float running average it replaced: docs/RESULTS.md "Map correction").
#
#   bench/fusion_ab.sh OUT_DIR CLI_A CLI_B [--rounds 2] [--frames 150] [--voxel 0.02]
#
# Sequences: ../shared/datasets (or $VKMESH_DATASETS) TUM fr1/rpy and ICL-NUIM office traj0 (skipped with a note
# when absent), and the noisy synthetic room with colour, written by CLI_B into OUT_DIR/room.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
out=${1:?usage: bench/fusion_ab.sh OUT_DIR CLI_A CLI_B [--rounds N] [--frames N] [--voxel M]}
a=${2:?CLI_A}
b=${3:?CLI_B}
shift 3
rounds=2 frames=150 voxel=0.02
while [[ $# -gt 0 ]]; do
    case $1 in
        --rounds) rounds=$2; shift 2 ;;
        --frames) frames=$2; shift 2 ;;
        --voxel) voxel=$2; shift 2 ;;
        *) echo "unknown option $1" >&2; exit 2 ;;
    esac
done
datasets=${VKMESH_DATASETS:-$here/../shared/datasets}
mkdir -p "$out"
[[ -d $out/room ]] || "$b" synth "$out/room" --frames 60 --noise --color-noise 4 > /dev/null

names=() folders=()
for pair in "tum_fr1_rpy:$datasets/tum_fr1_rpy" "iclnuim_office_traj0:$datasets/iclnuim_office_traj0" "room:$out/room"; do
    name=${pair%%:*} folder=${pair#*:}
    if [[ -d $folder ]]; then names+=("$name"); folders+=("$folder"); else echo "$name: $folder is absent, skipped"; fi
done

for ((r = 1; r <= rounds; ++r)); do
    for i in "${!names[@]}"; do
        for side in A B; do
            cli=$a; [[ $side == B ]] && cli=$b
            base=$out/${names[$i]}.$side.$r
            "$cli" fuse "${folders[$i]}" --frames "$frames" --voxel "$voxel" -o "$base.ply" --stats "$base.json" -q > "$base.log" 2>&1
        done
    done
done
# Accuracy of the last round's meshes (B's eval for both: the same scoring).
for i in "${!names[@]}"; do
    for side in A B; do
        base=$out/${names[$i]}.$side.$rounds
        extra=()
        [[ ${names[$i]} == room ]] && extra=(--gt "${folders[$i]}/gt_points.ply")
        "$b" eval "$base.ply" --dataset "${folders[$i]}" --frames "$frames" --color-every 10 "${extra[@]}" --json "$base.eval.json" \
            > "$base.eval.log" 2>&1 || echo "${names[$i]} $side: eval failed, see $base.eval.log"
    done
done
/usr/bin/python3 - "$out" "$rounds" "${names[@]}" <<'EOF'
import json, statistics, sys
out, rounds, names = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
def load(path):
    try:
        return json.load(open(path))
    except (OSError, ValueError):
        return {}
print("| sequence | build | wall ms/frame (median per round) | GPU ms fuse | triangles | F@1cm | F@2cm | colour MAE r/g/b | PSNR |")
print("|---|---|---|---:|---:|---:|---:|---|---:|")
for name in names:
    for side in ("A", "B"):
        walls = [load(f"{out}/{name}.{side}.{r}.json").get("wall_ms_per_frame", {}).get("median") for r in range(1, rounds + 1)]
        s = load(f"{out}/{name}.{side}.{rounds}.json")
        e = load(f"{out}/{name}.{side}.{rounds}.eval.json")
        fuse = s.get("gpu_ms_per_frame", {}).get("fuse", {}).get("median")
        scores = {round(x["threshold"], 3): x.get("fscore") for x in e.get("scores", [])}
        c = e.get("color_vs_frames") or {}
        mae = [c.get(k) for k in ("mae_red", "mae_green", "mae_blue")] if c else None
        fmt = lambda v, d=2: "-" if v is None else (f"{v:.{d}f}" if isinstance(v, float) else str(v))
        print(f"| {name} | {side} | {' / '.join(fmt(w) for w in walls)} | {fmt(fuse)} | {s.get('mesh', {}).get('triangles', '-')} | "
              f"{fmt(scores.get(0.01), 4)} | {fmt(scores.get(0.02), 4)} | {'-' if not mae else ' / '.join(fmt(m) for m in mae)} | "
              f"{fmt(c.get('psnr'))} |")
EOF
