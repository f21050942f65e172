#!/usr/bin/env bash
# Per-stage GPU ms of two vkmesh builds side by side, alternating (the machines are shared: compare within
# one run only). Usage: bench/stage_ab.sh BEFORE_VKMESH AFTER_VKMESH [OUT_DIR] [REPETITIONS]
# e.g. build the old commit in a worktree (git worktree add ../before 228d1d1; cmake -S ../before -B
# ../before/build -DVKMESH_BUILD_TESTS=OFF; cmake --build ../before/build --target vkmesh_cli) and run
#   bench/stage_ab.sh ../before/build/vkmesh build/vkmesh out/stage_ab
# Datasets: ../shared/datasets (or $VKMESH_DATASETS), ICL-NUIM office traj0 and TUM fr1/rpy, 3 cm, 100 frames.
# Prints one table per dataset: the median GPU ms per frame of every stage, each repetition, and after/before.
set -euo pipefail
before=$1 after=$2 out=${3:-out/stage_ab} reps=${4:-2}
datasets=${VKMESH_DATASETS:-$(dirname "$0")/../../shared/datasets}
mkdir -p "$out"
for rep in $(seq 1 "$reps"); do
  for ds in iclnuim_office_traj0 tum_fr1_rpy; do
    for side in before after; do
      bin=$before; [[ $side == after ]] && bin=$after
      "$bin" fuse "$datasets/$ds" -o "$out/$side.ply" --voxel 0.03 --frames 100 --stats "$out/${ds}_${side}_r$rep.json" -q >/dev/null
    done
  done
done
python3 - "$out" "$reps" <<'PY'
import json, statistics, sys
out, reps = sys.argv[1], int(sys.argv[2])
stages = ['allocate', 'fuse', 'mesh_mark', 'mesh_claim', 'mesh_update', 'mesh_triangulate', 'mesh_gc', 'mesh_total']
for ds in ['iclnuim_office_traj0', 'tum_fr1_rpy']:
    runs = {s: [json.load(open(f'{out}/{ds}_{s}_r{r}.json')) for r in range(1, reps + 1)] for s in ('before', 'after')}
    print(f'\n{ds}: triangles before {runs["before"][0]["mesh"]["triangles"]}, after {runs["after"][0]["mesh"]["triangles"]}')
    print('| stage | before | after | after/before |\n|---|---|---|---|')
    rows = [(st, lambda d, st=st: d['gpu_ms_per_frame'][st]['median']) for st in stages]
    rows.append(('wall ms/frame', lambda d: d['wall_ms_per_frame']['median']))
    for name, get in rows:
        b = [get(d) for d in runs['before']]
        a = [get(d) for d in runs['after']]
        print(f'| {name} | {" / ".join(f"{x:.2f}" for x in b)} | {" / ".join(f"{x:.2f}" for x in a)} | '
              f'{statistics.mean(a) / statistics.mean(b):.2f} |')
PY
