#!/usr/bin/env bash
# Installs the Debian 12 packages vkmesh needs to build, test and run on lavapipe (software Vulkan).
# Installs only what is missing; uses sudo when not root. Pass --bench to add Open3D for the peer
# benchmark (and the Python module's Open3D example), --sanitize to add clang with its sanitizer and
# libFuzzer runtimes (libclang-rt-14-dev holds libclang_rt.fuzzer/asan/ubsan) and llvm-symbolizer for
# readable reports (scripts/ci/10-sanitize-fuzz.sh).
set -euo pipefail

packages=(
  cmake g++ make ninja-build pkg-config
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools glslang-tools spirv-tools
  libeigen3-dev libopencv-core-dev libopencv-imgcodecs-dev libcli11-dev nlohmann-json3-dev libgtest-dev
  # relocalisation by ORB features and PnP on the colour image (src/slam/feature_relocaliser.h)
  libopencv-features2d-dev libopencv-calib3d-dev
  # the frame store (core/frame_store.h): lossless compression of the fused frames
  libzstd-dev
  # recordings (src/io/recordings/: ROS 1 bag chunks in bz2 and lz4, rosbag2's SQLite storage), and the Python
  # modules their tests write fixtures with (tests/support/recording_writers.py)
  liblz4-dev libbz2-dev libsqlite3-dev
  python3-rosbag python3-sensor-msgs python3-geometry-msgs python3-tf2-msgs python3-std-msgs python3-zstandard python3-lz4
  # (tests/support/make_recordings.py reads the synthetic folders' PNGs with PIL)
  python3-pil
  # loop closure's pose graph (src/slam/pose_graph.h)
  libceres-dev
  # the Python module (python/, docs/PYTHON.md) and its tests
  python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest
  # batch reconstruction on Dask (python3 -m vkmesh.batch, docs/SCALING.md) and its tests
  python3-distributed
  # the browser viewer (docs/VIEWER.md): Boost.Beast (header-only) for its server, three.js r111 embedded in its
  # page, and Chromium for its tests (headless, SwiftShader WebGL; ctest label browser)
  libboost-dev libjs-three chromium
  # `pip install .` into a virtual environment (docs/PYTHON.md; scripts/ci/40-pip-venv.sh): venv brings pip along,
  # and the build backend is in the source tree (python/build_backend), so nothing else
  python3-venv
  # mesh files (docs/MESH_FILES.md): binary glTF written with tinygltf (header-only), --simplify with meshoptimizer
  libtinygltf-dev libmeshoptimizer-dev
)
# The Khronos glTF Validator (tests/cpu/test_gltf.cpp) is an npm package: node and npm from Debian unless an npm is
# already there (a NodeSource nodejs ships its own npm and conflicts with Debian's npm package).
if ! command -v npm >/dev/null 2>&1; then packages+=(nodejs npm); fi
for arg in "$@"; do
  case "$arg" in
    --bench) packages+=(python3-open3d) ;;
    --sanitize) packages+=(clang libclang-rt-14-dev llvm-14) ;;
    *) echo "install_deps.sh: unknown option $arg" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
sudo=""
if (( EUID != 0 )); then sudo="sudo"; fi
if (( ${#missing[@]} > 0 )); then
  echo "vkmesh: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -q
  $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# gltf-validator, globally (the tests find it through `npm root -g`). Not in Debian, so from the npm registry: without
# a network this only warns, and the validator test skips saying how to install it.
if command -v npm >/dev/null 2>&1 && ! [[ -f "$(npm root -g 2>/dev/null)/gltf-validator/package.json" ]]; then
  echo "vkmesh: installing the Khronos glTF Validator (npm install -g gltf-validator)" >&2
  $sudo npm install -g --no-fund --no-audit gltf-validator >&2 ||
    echo "vkmesh: warning: could not install gltf-validator (no network?); the glTF validator test will skip" >&2
fi
