#!/usr/bin/env bash
# The main job on the built-in default: render the synthetic room (60 frames with Kinect-like noise and
# exact ground truth), fuse it on the first suitable Vulkan device (lavapipe when there is no GPU), and
# write the mesh, a rendered picture of it and a JSON summary to out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
out=out/demo
mkdir -p "$out"
if [[ ! -f "$out/room/depth.txt" ]]; then
  build/vkmesh synth "$out/room" --frames 60 --noise
fi
build/vkmesh fuse "$out/room" -o "$out/room_mesh.ply" --stats "$out/room_stats.json" --voxel 0.02 "$@"
build/vkmesh render "$out/room_mesh.ply" -o "$out/room_mesh.png"
echo "mesh: $out/room_mesh.ply   picture: $out/room_mesh.png   summary: $out/room_stats.json   ground truth: $out/room/gt_points.ply"
