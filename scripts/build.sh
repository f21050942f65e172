#!/usr/bin/env bash
# Configures and builds vkmesh (Release) into build/. Extra arguments go to the CMake configure step.
# A new build/ uses Ninja where it is installed (scripts/install_deps.sh installs it): it compiles a program's files
# while the libraries it links are still being built, where Make builds target after target; an existing build/
# keeps the generator it was configured with.
set -euo pipefail
cd "$(dirname "$0")/.."
generator=()
if [[ ! -f build/CMakeCache.txt ]] && command -v ninja >/dev/null; then generator=(-G Ninja); fi
cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j"$(nproc)"
