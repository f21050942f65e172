#!/usr/bin/env bash
# Packs the standalone GPU benchmark (bench/gpubench) for a bare Linux machine that has a GPU driver and nothing
# else: builds vkmesh_gpubench in build/ (reusing it; configures it when absent) and writes
#   build/gpubench-pack/          vkmesh_gpubench, lib/libvulkan.so.1 (this system's Vulkan loader),
#                                 lib/libzstd.so.1 (this system's zstd: the Mapper's frame store),
#                                 glibc/ (this system's glibc, used only where the host's is older than the
#                                 binary needs), run.sh, README.md, BUILD_INFO
#   build/vkmesh-gpubench.tar.gz  the same folder as vkmesh-gpubench/
# The binary links libstdc++ and libgcc statically, so it needs only glibc, libvulkan.so.1 and libzstd.so.1 (it
# drives vkmesh::Mapper, which links the frame store's zstd); run.sh puts lib/ on LD_LIBRARY_PATH. This script
# fails if it needs anything else. No OpenCV, no dataset: the benchmark renders its synthetic room in memory.
# Usage: scripts/pack_gpubench.sh   (BUILD_DIR=dir to build elsewhere than build/)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build}
pack=$build/gpubench-pack
tarball=$build/vkmesh-gpubench.tar.gz
max_bytes=$((40 * 1024 * 1024))

[[ -f $build/CMakeCache.txt ]] || cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --target vkmesh_gpubench -j"$(nproc)"
binary=$build/vkmesh_gpubench

# What the binary needs: glibc's libraries, the Vulkan loader and zstd, nothing else (libstdc++ linked statically).
needed=$(readelf -d "$binary" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
for lib in $needed; do
  case $lib in
    libvulkan.so.1 | libzstd.so.1 | libc.so.6 | libm.so.6 | ld-linux-x86-64.so.2 | libpthread.so.0 | libdl.so.2 | librt.so.1) ;;
    *) echo "pack_gpubench: $binary needs $lib, which the pack does not carry (only glibc, libvulkan.so.1 and libzstd.so.1)" >&2
       exit 1 ;;
  esac
done
# Where this system resolves them (ldd prints "name => path (address)").
resolved() { ldd "$binary" | awk -v name="$1" '$1 == name && $3 ~ /^\// { print $3 }'; }
loader=$(resolved libvulkan.so.1)
libc=$(resolved libc.so.6)
[[ -n $loader && -n $libc ]] || { echo "pack_gpubench: ldd does not resolve libvulkan.so.1 and libc.so.6 for $binary" >&2; exit 1; }
zstd=""
if grep -qx libzstd.so.1 <<<"$needed"; then
  zstd=$(resolved libzstd.so.1)
  [[ -n $zstd ]] || { echo "pack_gpubench: ldd does not resolve libzstd.so.1 for $binary" >&2; exit 1; }
fi
libdir=$(dirname "$libc")
interp=$(readelf -l "$binary" | sed -n 's/.*Requesting program interpreter: \(.*\)\]/\1/p')

rm -rf "$pack" "$tarball"
mkdir -p "$pack/lib" "$pack/glibc"
cp "$binary" "$pack/vkmesh_gpubench"
strip --strip-unneeded "$pack/vkmesh_gpubench"
cp -L "$loader" "$pack/lib/libvulkan.so.1"
# zstd (the Mapper's frame store) as the loader: from lib/, which run.sh puts on LD_LIBRARY_PATH.
[[ -z $zstd ]] || cp -L "$zstd" "$pack/lib/libzstd.so.1"
# glibc as a fallback for a host whose glibc is older than the binary's symbol versions (run.sh --glibc): the
# dynamic linker runs the binary with these; the compatibility stubs (libdl, libpthread, librt) come along
# because a GPU driver built for an old glibc links them, and they must match this libc.
cp -L "$interp" "$pack/glibc/ld-linux-x86-64.so.2"
for lib in libc.so.6 libm.so.6 libdl.so.2 libpthread.so.0 librt.so.1; do cp -L "$libdir/$lib" "$pack/glibc/$lib"; done
cp bench/gpubench/run.sh "$pack/run.sh"
cp bench/gpubench/README.md "$pack/README.md"
chmod +x "$pack/run.sh" "$pack/vkmesh_gpubench" "$pack/glibc/ld-linux-x86-64.so.2"

# The newest glibc symbol version the binary or a library of lib/ asks for: run.sh names it if the host lacks it.
glibc_needed=$(objdump -T "$pack/vkmesh_gpubench" "$pack"/lib/*.so.1 | grep -o 'GLIBC_[0-9.]*' | sed 's/GLIBC_//' | sort -uV | tail -n1)
commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
dirty=$(git status --porcelain 2>/dev/null | grep -q . && echo " (uncommitted changes)" || true)
{
  echo "vkmesh commit: $commit$dirty"
  echo "packed: $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(. /etc/os-release 2>/dev/null && echo "$PRETTY_NAME" || uname -s)"
  echo "vulkan loader: $(basename "$(readlink -f "$loader")")"
  [[ -z $zstd ]] || echo "zstd: $(basename "$(readlink -f "$zstd")")"
  echo "glibc needed: $glibc_needed (bundled: $(basename "$(readlink -f "$libc")") from $(ldd --version | head -n1))"
} >"$pack/BUILD_INFO"

tar -C "$build" --transform 's,^gpubench-pack,vkmesh-gpubench,' -czf "$tarball" gpubench-pack
bytes=$(stat -c %s "$tarball")
unpacked=$(du -sb "$pack" | cut -f1)
echo "pack_gpubench: $tarball: $((bytes / 1024)) KiB ($((unpacked / 1024)) KiB unpacked); folder $pack"
cat "$pack/BUILD_INFO"
if ((bytes > max_bytes)); then
  echo "pack_gpubench: the tarball is over $((max_bytes / 1024 / 1024)) MiB" >&2
  exit 1
fi
