#!/bin/bash
# Camera tracking (issue 22, docs/TRACKING.md): `vkmesh fuse --track` on the shared real sequences and the
# noisy synthetic room, trajectory error with bench/ate.py (TUM's ATE/RPE), the synthetic room's mesh with
# tracked poses against the one with the true poses (vkmesh eval: accuracy, completeness, F-score), and the
# tracker's time against fusion's and meshing's (the --stats JSON).
#
#   bench/track_bench.sh OUT_DIR [DATASETS_DIR] [--frames N] [extra fuse options...]
#   TRACK_OPTIONS="--track-solve gpu" bench/track_bench.sh OUT_DIR     # options for the tracked runs only
#   TRACK_OPTIONS="--no-loop-closure" bench/track_bench.sh OUT_DIR     # tracking alone (--track closes loops by default)
#
# DATASETS_DIR: ../shared/datasets by default (or $VKMESH_DATASETS); a sequence that is absent is skipped with
# a note. Writes OUT_DIR/<name>.{txt,ply,json,ate.json,log} and prints one summary line per run.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
out=${1:?usage: bench/track_bench.sh OUT_DIR [DATASETS_DIR] [fuse options...]}
shift
datasets=${VKMESH_DATASETS:-$here/../shared/datasets}
if [[ $# -gt 0 && -d "$1" ]]; then datasets=$1; shift; fi
vkmesh=${VKMESH_CLI:-$here/build/vkmesh}
python=/usr/bin/python3
mkdir -p "$out"

# name, folder, voxel, ate.py's --max-dt (frame-index timestamps need < 1)
run() {
    local name=$1 folder=$2 voxel=$3 maxdt=$4
    shift 4
    if [[ ! -d $folder ]]; then echo "$name: $folder is absent, skipped"; return; fi
    # shellcheck disable=SC2086  # TRACK_OPTIONS: words on purpose
    "$vkmesh" fuse "$folder" --track ${TRACK_OPTIONS:-} --voxel "$voxel" --trajectory "$out/$name.txt" -o "$out/$name.ply" \
        --stats "$out/$name.json" -q "$@" > "$out/$name.log" 2>&1 || { echo "$name: fuse failed, see $out/$name.log"; return; }
    $python "$here/bench/ate.py" "$folder/groundtruth.txt" "$out/$name.txt" --max-dt "$maxdt" --json "$out/$name.ate.json" > /dev/null
    $python - "$out/$name.json" "$out/$name.ate.json" "$name" "$voxel" <<'EOF'
import json, sys
s, a, name, voxel = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), sys.argv[3], sys.argv[4]
t, g = s["tracking"], s["gpu_ms_per_frame"]
fusion_mesh = sum(g[k]["median"] for k in ("allocate", "fuse", "mesh_total") if k in g and g[k]["median"] is not None)
# Host round trips of a tracked frame, its fusion included (one more submission unless it is tracking's own).
one = t.get("fused_in_tracking_submission", False)
trips = t['submissions_per_frame']['mean'] + (0 if one else 1)
print(f"{name}: {a['pairs']} frames, voxel {voxel} m: ATE RMSE {a['ate']['rmse']*100:.2f} cm (max {a['ate']['max']*100:.2f}), "
      f"RPE {a['rpe']['trans_rmse']*100:.2f} cm / {a['rpe']['rot_rmse_deg']:.2f} deg per frame; lost {t['lost_frames']}; "
      f"tracking {t['ms_per_frame']['median']:.1f} ms wall, {t['gpu_ms_per_frame']['median']:.1f} ms GPU (median), "
      f"{t['iterations']['mean']:.1f} iterations, {trips:.1f} round trips per frame with the fusion "
      f"(solved on the {t.get('solve', 'host')}); "
      f"fusion + meshing {fusion_mesh:.1f} ms GPU, {s['wall_ms_per_frame']['median']:.1f} ms wall (median"
      f"{'; one submission: the wall times are both the whole frame' if one else ''})")
EOF
}

run tum_fr1_rpy "$datasets/tum_fr1_rpy" 0.02 0.02 "$@"
run icl_office0 "$datasets/iclnuim_office_traj0" 0.02 0.5 "$@"

# The noisy synthetic room (exact ground truth): 300 frames of the orbit, tracked and with the true poses.
room="$out/room"
[[ -f $room/groundtruth.txt ]] || "$vkmesh" synth "$room" --frames 300 --noise > /dev/null
run synthetic_room "$room" 0.03 0.02 "$@"
"$vkmesh" fuse "$room" --voxel 0.03 -o "$out/synthetic_room_gt_poses.ply" -q "$@" > /dev/null 2>&1
for mesh in synthetic_room synthetic_room_gt_poses; do
    "$vkmesh" eval "$out/$mesh.ply" --gt "$room/gt_points.ply" --dataset "$room" --frame-stride 10 --json "$out/$mesh.eval.json" > /dev/null
done
$python - "$out/synthetic_room.eval.json" "$out/synthetic_room_gt_poses.eval.json" <<'EOF'
import json, sys
for label, path in (("tracked poses", sys.argv[1]), ("true poses   ", sys.argv[2])):
    e = json.load(open(path))
    scores = ", ".join(f"F@{s['threshold']*100:g}cm {s['fscore']:.4f}" for s in e["scores"])
    print(f"synthetic room, {label}: accuracy mean {e['accuracy_mean']*1000:.2f} mm, completeness mean "
          f"{e['completeness_mean']*1000:.2f} mm, {scores}")
EOF
