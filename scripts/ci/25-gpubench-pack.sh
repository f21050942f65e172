#!/usr/bin/env bash
# CI job: the standalone GPU benchmark pack (bench/gpubench, scripts/pack_gpubench.sh) as a bare machine would
# get it. Packs it (reusing the main suite's build/), checks its size, extracts the tarball into a temporary
# folder and checks there that
#   (a) every library the binary needs, apart from glibc's, resolves into the pack (ldd with the
#       LD_LIBRARY_PATH run.sh sets): libvulkan.so.1 and libzstd.so.1 (the Mapper's frame store) come from its
#       lib/, and the binary needs nothing but glibc, libvulkan.so.1 and libzstd.so.1;
#   (b) `env -i PATH=/usr/bin:/bin HOME=/tmp ./run.sh --quick` runs on lavapipe, the driver coming from the
#       system as an NVIDIA one would, with the pack's loader, and writes JSON with both voxel sizes timed;
#   (c) the pack's own glibc works (run.sh --glibc bundled), as used on a host whose glibc is too old;
#   (d) run.sh finds an NVIDIA-style driver: in a private mount namespace (unshare -m, root) a tmpfs over
#       /usr/local holds lavapipe's library as /usr/local/nvidia/lib64/libGLX_nvidia.so.0, first with no
#       manifest (run.sh must write one), then with a manifest in /usr/local/nvidia/share/vulkan/icd.d that
#       names the library without a folder (run.sh must put the folder on LD_LIBRARY_PATH). Skipped with a
#       note where unshare is not allowed.
# About 30 s on 2 cores when build/ is up to date.
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$SECONDS
scripts/install_deps.sh
scripts/pack_gpubench.sh

fail() { echo "25-gpubench-pack: $*" >&2; exit 1; }
tarball=build/vkmesh-gpubench.tar.gz
bytes=$(stat -c %s "$tarball")
((bytes < 40 * 1024 * 1024)) || fail "$tarball is $bytes bytes, over 40 MiB"
echo "25-gpubench-pack: $tarball is $((bytes / 1024)) KiB"

tmp=$(mktemp -d /tmp/vkmesh-gpubench-ci.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
tar -xzf "$tarball" -C "$tmp"
pack=$tmp/vkmesh-gpubench
clean=(env -i PATH=/usr/bin:/bin HOME=/tmp)

# --- (a) libraries ---
deps=$("${clean[@]}" LD_LIBRARY_PATH="$pack/lib" ldd "$pack/vkmesh_gpubench")
echo "$deps"
grep -q 'not found' <<<"$deps" && fail "a library of the binary is not found (above)"
while read -r name arrow path _; do
  case $name in
    linux-vdso.so.* | /lib*/ld-linux-* | libc.so.6 | libm.so.6 | libpthread.so.0 | libdl.so.2 | librt.so.1) ;;   # glibc
    *) [[ $arrow == "=>" && $path == "$pack/"* ]] || fail "$name resolves to '$path', not into the pack" ;;
  esac
done <<<"$deps"
grep -q "libvulkan.so.1 => $pack/lib/libvulkan.so.1" <<<"$deps" || fail "libvulkan.so.1 does not come from the pack"
grep -q "libzstd.so.1 => $pack/lib/libzstd.so.1" <<<"$deps" || fail "libzstd.so.1 does not come from the pack"
needed=$(readelf -d "$pack/vkmesh_gpubench" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
for lib in $needed; do
  case $lib in
    libvulkan.so.1 | libzstd.so.1 | libc.so.6 | libm.so.6 | ld-linux-x86-64.so.2 | libpthread.so.0 | libdl.so.2 | librt.so.1) ;;
    *) fail "the binary needs $lib: nothing but glibc, libvulkan.so.1 and libzstd.so.1 is allowed" ;;
  esac
done

# --- (b) a clean environment on lavapipe ---
check_json() {   # FILE VOXEL...: every voxel size has a timed run with per-stage medians
  local json=$1 voxel
  shift
  [[ -s $json ]] || fail "no $json"
  grep -q "\"loader_path\": \"$pack/lib/libvulkan.so.1\"" "$json" || fail "$json: the loader was not the pack's"
  for voxel in "$@"; do
    grep -Eq "\"voxel_size\": $voxel,?$" "$json" || fail "$json: no run at voxel $voxel"
  done
  grep -q '"mesh_total": {' "$json" || fail "$json: no meshing times"
  grep -q '"dispatches_per_frame": {' "$json" || fail "$json: no pass count"
  grep -q '"median": null' "$json" && fail "$json: a stage without times"
  return 0
}
(cd "$pack" && "${clean[@]}" ./run.sh --quick) || fail "run.sh --quick failed in a clean environment"
check_json "$pack/results/gpubench.json" 0.03 0.01
grep -q 'no NVIDIA driver found' "$pack/results/gpubench.txt" || fail "run.sh did not say that it found no NVIDIA driver"
echo "25-gpubench-pack: clean-environment run passed after $((SECONDS - start)) s"

# --- (c) the pack's glibc ---
(cd "$pack" && "${clean[@]}" ./run.sh --quick --glibc bundled --voxel 0.03 --frames 1 --out "$tmp/bundled") ||
  fail "run.sh --glibc bundled failed"
check_json "$tmp/bundled/gpubench.json" 0.03
grep -q '"glibc": "' "$tmp/bundled/gpubench.json" || fail "no glibc version in the JSON"

# --- (d) finding an NVIDIA-style driver ---
lvp=/usr/lib/x86_64-linux-gnu/libvulkan_lvp.so
if [[ ! -e $lvp ]]; then
  echo "25-gpubench-pack: (d) skipped: no $lvp"
elif ! unshare -m mount -t tmpfs vkmesh-ci-probe /usr/local 2>/dev/null; then
  echo "25-gpubench-pack: (d) skipped: no private mount namespace with a tmpfs over /usr/local here (unshare -m)"
else
  unshare -m bash -euo pipefail -c '
    pack=$1 tmp=$2 lvp=$3
    mount -t tmpfs vkmesh-ci /usr/local
    mkdir -p /usr/local/nvidia/lib64
    ln -s "$lvp" /usr/local/nvidia/lib64/libGLX_nvidia.so.0
    cd "$pack"
    env -i PATH=/usr/bin:/bin HOME=/tmp ./run.sh --quick --voxel 0.03 --frames 1 --out "$tmp/written"
    mkdir -p /usr/local/nvidia/share/vulkan/icd.d
    printf "{\"file_format_version\": \"1.0.0\", \"ICD\": {\"library_path\": \"libGLX_nvidia.so.0\", \"api_version\": \"1.3.0\"}}\n" \
      >/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
    env -i PATH=/usr/bin:/bin HOME=/tmp ./run.sh --quick --voxel 0.03 --frames 1 --out "$tmp/found"
  ' _ "$pack" "$tmp" "$lvp" || fail "run.sh with an NVIDIA-style driver failed"
  grep -q 'manifest: /tmp/.*/nvidia_icd.json (written for /usr/local/nvidia/lib64/libGLX_nvidia.so.0' "$tmp/written/gpubench.txt" ||
    fail "run.sh did not write a manifest for /usr/local/nvidia/lib64/libGLX_nvidia.so.0"
  grep -q 'manifest: /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json (found in' "$tmp/found/gpubench.txt" ||
    fail "run.sh did not use the manifest in /usr/local/nvidia/share/vulkan/icd.d"
  for run in written found; do
    check_json "$tmp/$run/gpubench.json" 0.03
    grep -q '"VK_DRIVER_FILES": "' "$tmp/$run/gpubench.json" || fail "$run: VK_DRIVER_FILES was not set"
  done
  echo "25-gpubench-pack: NVIDIA-style driver found both ways"
fi
echo "25-gpubench-pack: OK after $((SECONDS - start)) s"
