#!/usr/bin/env bash
# Builds vkmesh and runs the whole test suite. GPU tests run on the first suitable Vulkan device
# (lavapipe in CI) with the Khronos validation layer, including synchronization validation, and fail
# on any validation message. Real-data tests use ../shared/datasets (or $VKMESH_DATASETS) and say
# so when they skip.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
cd build
VKMESH_VALIDATION=1 ctest --output-on-failure -j"$(nproc)" "$@"
