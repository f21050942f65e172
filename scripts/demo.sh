#!/usr/bin/env bash
# The main job on the built-in default: render the synthetic room (120 frames of an orbit with Kinect-like
# noise, colour and exact ground truth), fuse it on the first suitable Vulkan device (lavapipe when there is no
# GPU) from its depth and colour alone: every camera pose after the first is tracked against the mesh fused so
# far (--track; the first frame's pose is the dataset's, which puts the map in the room's coordinates), and the
# tracked trajectory's error against the room's true poses is printed beside the mesh, a rendered picture of
# it and a JSON summary in out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
out=out/demo
mkdir -p "$out"
if [[ ! -f "$out/room/depth.txt" || $(wc -l < "$out/room/depth.txt") -lt 120 ]]; then
  build/vkmesh synth "$out/room" --frames 120 --noise
fi
build/vkmesh fuse "$out/room" --track --trajectory "$out/room_trajectory.txt" -o "$out/room_mesh.ply" \
  --stats "$out/room_stats.json" --voxel 0.02 "$@"
build/vkmesh render "$out/room_mesh.ply" -o "$out/room_mesh.png"
error=$(/usr/bin/python3 - "$out/room_stats.json" <<'EOF'
import json, sys
e = json.load(open(sys.argv[1]))["tracking"]["position_error_m"]
print("RMSE %.1f mm, largest %.1f mm over %d frames" % (e["rmse"] * 1000, e["max"] * 1000, e["frames"]))
EOF
)
echo "mesh: $out/room_mesh.ply   picture: $out/room_mesh.png   summary: $out/room_stats.json   ground truth: $out/room/gt_points.ply"
echo "trajectory: $out/room_trajectory.txt, tracked from depth and colour; against the true poses ($out/room/groundtruth.txt): $error"
