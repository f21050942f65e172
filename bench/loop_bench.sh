#!/usr/bin/env bash
# Loop closure and relocalisation (docs/LOOP_CLOSURE.md) on the synthetic sequences made for them: the gallery
# (tracking drifts; with and without loop closure, --no-loop-closure), the twin places (a false loop) and the room's revisit path
# with 10 jumps cut into laps 2 and 3 (kidnapping). Prints the trajectory errors, the loop decisions, the
# relocalisations and the loop closer's milliseconds per stage. The shared sequences: bench/track_bench.sh with
# TRACK_OPTIONS="--loop-closure".
#   bench/loop_bench.sh OUT_DIR
set -euo pipefail
out=${1:?usage: bench/loop_bench.sh OUT_DIR}
here=$(cd "$(dirname "$0")/.." && pwd)
vkmesh=${VKMESH_CLI:-$here/build/vkmesh}
python=/usr/bin/python3
mkdir -p "$out"

[[ -f $out/gallery/groundtruth.txt ]] || "$vkmesh" synth "$out/gallery" --scene gallery --path gallery-loop --frames 300 --noise \
    --width 320 --height 240 --gt-spacing 0.05 > /dev/null
[[ -f $out/twins/groundtruth.txt ]] || "$vkmesh" synth "$out/twins" --scene twins --path twin-visit --frames 200 --noise \
    --width 320 --height 240 --gt-spacing 0.05 > /dev/null
if [[ ! -f $out/kidnap/groundtruth.txt ]]; then
    "$vkmesh" synth "$out/kidnap" --frames 180 --path revisit --noise --width 320 --height 240 > /dev/null
    # frames 0-55, then 4 of every 12 from frame 60 on: 10 jumps to places lap 1 saw (as the test does)
    awk '/^#/ {print; next} {if (n < 56 || (n >= 60 && (n - 60) % 12 < 4)) print; n++}' "$out/kidnap/depth.txt" > "$out/kidnap/depth.tmp"
    mv "$out/kidnap/depth.tmp" "$out/kidnap/depth.txt"
fi

run() {   # name folder [options]
    local name=$1 folder=$2
    shift 2
    "$vkmesh" fuse "$folder" --track --voxel 0.03 --trajectory "$out/$name.txt" --stats "$out/$name.json" -o "$out/$name.ply" -q "$@" \
        > "$out/$name.log" 2>&1 || { echo "$name: fuse failed, see $out/$name.log"; return; }
    $python "$here/bench/ate.py" "$folder/groundtruth.txt" "$out/$name.txt" --json "$out/$name.ate.json" > /dev/null
    $python - "$out/$name.json" "$out/$name.ate.json" "$name" <<'PY'
import json, sys
s, a, name = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), sys.argv[3]
t, l = s["tracking"], s["loop_closure"]
line = (f"{name}: {a['pairs']} frames: ATE RMSE {a['ate']['rmse']*100:.2f} cm (max {a['ate']['max']*100:.2f}); unaligned error max "
        f"{t['position_error_m']['max']*100:.1f} cm online; lost {t['lost_frames']}, tentative {t.get('tentative_frames', 0)}; tracking {t['ms_per_frame']['median']:.1f} ms wall (median)")
if l.get("enabled"):
    ms = ", ".join(f"{k} {v['mean']:.2f} ms x {v['count']}" for k, v in sorted(l["ms"].items()) if v["count"])
    line += (f"\n  loop closure: {l['keyframes']} keyframes; loops detected {l['loops_detected']}, accepted {l['loops_accepted']}, "
             f"consistent {l['loops_consistent']}, rejected {l['loops_rejected']} {l['rejected_by']}; relocalised "
             f"{l['relocalisations']} of {l['lost_frames']} lost frames; {l['frames_refused']} frames re-fused; final unaligned error max "
             f"{l['position_error_m']['max']*100:.1f} cm\n  per stage (mean x count): {ms}")
print(line)
PY
}

run gallery "$out/gallery" --no-loop-closure
run gallery_loops "$out/gallery" --loop-closure
run twins_loops "$out/twins" --loop-closure --trajectory-online "$out/twins_online.txt"
run kidnap "$out/kidnap" --no-loop-closure
run kidnap_loops "$out/kidnap" --loop-closure --trajectory-online "$out/kidnap_online.txt"
# Kidnapping: each jump's first fused frame, its error against the truth (online pose: where it was relocalised).
$python - "$out/kidnap_loops.json" "$out/kidnap_online.txt" "$out/kidnap/groundtruth.txt" <<'PY'
import json, sys, math
import numpy as np
s = json.load(open(sys.argv[1]))
online = np.loadtxt(sys.argv[2]); truth = {round(r[0], 6): r[1:] for r in np.loadtxt(sys.argv[3])}
# Not fused: lost, or tentative (tracked from a relocalisation not yet confirmed)
lost = {e["frame"] for e in s["tracking"]["lost"]} | {v["frame"] for v in s["tracking"].get("per_frame", []) if v["status"] == "tentative"}
def angle(q1, q2):
    return math.degrees(2 * math.acos(min(1.0, abs(float(np.dot(q1 / np.linalg.norm(q1), q2 / np.linalg.norm(q2)))))))
ok = 0
for jump in range(56, 96, 4):
    for f in range(jump, jump + 4):
        if f in lost: continue
        g = truth[round(online[f][0], 6)]
        metres, degrees = np.linalg.norm(online[f][1:4] - g[:3]), angle(online[f][4:8], g[3:7])
        ok += metres < 0.05 and degrees < 5
        print(f"  jump at frame {jump}: fused again at frame {f} ({f - jump} later), {metres*100:.1f} cm, {degrees:.2f} degrees off")
        break
print(f"kidnapping: {ok} of 10 jumps relocalised within 5 frames, 5 cm and 5 degrees")
PY
