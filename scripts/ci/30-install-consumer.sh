#!/usr/bin/env bash
# CI job: vkmesh as an installed package. `cmake --install`s the main suite's Release build (build/, tests
# built too, so the check that no test is installed has something to catch) into a temporary prefix, checks
# what was installed (no tests, no paths into this checkout, the data files, the Python package importable
# from the prefix), then builds examples/consumer against it with find_package(vkmesh) and runs it on
# lavapipe with validation on, and checks that the installed CLI finds its data relative to itself.
set -euo pipefail
cd "$(dirname "$0")/../.."
scripts/install_deps.sh

src="$PWD"
prefix="$(mktemp -d /tmp/vkmesh-install.XXXXXX)"
trap 'rm -rf "$prefix"' EXIT
jobs="$(nproc)"

# A second full Release build without tests took ~5 of CI's minutes; configuring one is enough to catch a
# library target that needs the tests' CMake code.
cmake -S . -B build-install -DCMAKE_BUILD_TYPE=Release -DVKMESH_BUILD_TESTS=OFF >/dev/null
scripts/build.sh
cmake --install build --prefix "$prefix"

echo "30-install-consumer: checking the installed tree in $prefix"
# Tests must never be installed (tests/ has no install rules; this catches one added by mistake).
if grep -E '/(test_[^/]*|tests/[^/]*|libgtest[^/]*)$' build/install_manifest.txt; then
  echo "error: the install step installed test files (above)" >&2
  exit 1
fi
# The package must be relocatable: no text file (CMake files, headers) may name this checkout or its build
# directories. Binaries are skipped (-I).
if grep -rIl -F -e "$src" "$prefix"; then
  echo "error: installed files (above) hold absolute paths into the source/build tree $src:" >&2
  grep -rIn -F -e "$src" "$prefix" | head -20 >&2
  exit 1
fi
for f in include/vkmesh/vkmesh.h include/vkmesh/shared_layout.h bin/vkmesh share/vkmesh/cameras/tum_fr1/camera.json; do
  [[ -e "$prefix/$f" ]] || { echo "error: $f was not installed" >&2; exit 1; }
done
config="$(find "$prefix" -name vkmeshConfig.cmake)"
[[ -n "$config" ]] || { echo "error: vkmeshConfig.cmake was not installed" >&2; exit 1; }
# The Python package (built by default; install_deps.sh installs what it needs), in lib/python3.X/dist-packages
# as Debian's python3 looks for it under /usr and /usr/local: imported from the prefix, not from the build tree.
package="$(find "$prefix" -path '*/dist-packages/vkmesh/__init__.py')"
[[ -n "$package" ]] || { echo "error: the vkmesh Python package was not installed" >&2; exit 1; }
(cd / && PYTHONPATH="$(dirname "$(dirname "$package")")" /usr/bin/python3 -c "
import vkmesh
assert vkmesh.__file__ == '$package', vkmesh.__file__
assert any(d.suitable for d in vkmesh.devices())
")

# The consumer sees the package only through CMAKE_PREFIX_PATH, never this source tree.
rm -rf build-consumer
cmake -S examples/consumer -B build-consumer -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build build-consumer -j"$jobs"
VKMESH_VALIDATION=1 build-consumer/vkmesh_consumer
"$prefix/bin/vkmesh" --help >/dev/null
# The installed CLI finds its data (camera presets) relative to itself, in $prefix/share/vkmesh: a TUM folder
# without a camera.json gets the installed fr1 preset, altered here so that it cannot be mistaken for the
# source tree's copy.
seq="$prefix/check/rgbd_dataset_freiburg1_check"
"$prefix/bin/vkmesh" synth "$seq" --frames 2 2>/dev/null
rm "$seq/camera.json"
sed -i 's/"fx": 517.3/"fx": 517.25/' "$prefix/share/vkmesh/cameras/tum_fr1/camera.json"
"$prefix/bin/vkmesh" frames "$seq" -o "$prefix/check/frames.json" 2>/dev/null
grep -q '"fx": 517.25' "$prefix/check/frames.json" || {
  echo "error: the installed vkmesh did not read its camera preset from $prefix/share/vkmesh" >&2
  exit 1
}
echo "30-install-consumer: OK"
