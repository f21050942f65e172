#!/usr/bin/env bash
# CI job: the GPU suite on the block hash's 32-bit path (docs/HASH.md), as on a device without 64-bit atomics
# or 64-bit integers (Apple GPUs, many mobile GPUs). VKMESH_PRETEND_MISSING makes vkmesh treat both features as
# absent on lavapipe: every compute shader runs in its @hash32 build and the 64-bit features are not enabled,
# so the validation layer reports any shader that still uses a 64-bit type. Same tests, same expectations:
# the results must be identical to the main run. Reuses build/ (the main run's); about 2-3 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
scripts/install_deps.sh
scripts/build.sh
cd build
VKMESH_PRETEND_MISSING=shaderBufferInt64Atomics,shaderInt64 VKMESH_VALIDATION=1 ctest -L gpu --output-on-failure -j"$(nproc)"
