#!/usr/bin/env bash
# CI job: sanitizers and fuzzing (issue 5).
#  (a) builds vkmesh with clang under AddressSanitizer + UndefinedBehaviorSanitizer (build-asan,
#      RelWithDebInfo, tests on; any report aborts the test) and runs every CPU test plus the GPU tests
#      that cover fusion, the incremental mesh, mesh export, the library's frame loop (Mapper) and saving and
#      loading maps, with their bad input, on lavapipe;
#  (b) builds the libFuzzer targets of fuzz/ (in the same build-asan: the dataset, PLY, binary glTF, .vkmap and .vkframes readers, the viewer's wire format and page commands, the ROS 1 bag and MCAP containers and the ROS message decoders) and runs each from its seed corpus in
#      fuzz/corpus/<target>/ for FUZZ_SECONDS (default 10) seconds, one target per core at a time. Any crash, sanitizer report, leak,
#      timeout, out-of-memory or uncaught non-vkmesh exception fails the job; the input that caused it is
#      kept as build-asan/findings/<target>/crash-* (or leak-, timeout-, oom-) to reproduce with
#      `build-asan/fuzz/<target> <file>`.
# One clang build for both (VKMESH_BUILD_FUZZERS=ON adds coverage to the readers' files; the fuzz targets turn the
# parsers' fuzzing mode on at run time, core/fuzzing.h): the libraries are compiled once, not twice.
# Needs clang, libclang-rt-14-dev (the sanitizer and libFuzzer runtimes) and llvm-symbolizer; installs them.
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$SECONDS
jobs=$(nproc)
fuzz_seconds=${FUZZ_SECONDS:-10}

scripts/install_deps.sh --sanitize

# llvm-symbolizer turns the addresses of a report into file:line; Debian installs it versioned.
symbolizer=$(command -v llvm-symbolizer || command -v llvm-symbolizer-14 || true)
if [[ -n "$symbolizer" ]]; then export ASAN_SYMBOLIZER_PATH="$symbolizer"; fi
# halt_on_error: the first report fails the test (with -fno-sanitize-recover=all for UBSan too).
# Leak detection stays on: the Vulkan loader and lavapipe run uninstrumented but free what vkmesh's
# destroy calls release, and a leak in vkmesh is a bug this job should catch.
export ASAN_OPTIONS="halt_on_error=1:abort_on_error=1:detect_stack_use_after_return=1:strict_string_checks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"

sanitize="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"

# --- (a) the test suite under ASan + UBSan ---
echo "sanitize: building build-asan (clang, $sanitize)"
# -gline-tables-only: reports keep file:line, and the build is lighter than with full debug info. -O2 as
# before: at -O1 the build saved ~1.5 minutes but the CLI tests ran twice as long under ASan (measured).
generator=()   # Ninja for a new build-asan, as scripts/build.sh does for build/
if [[ ! -f build-asan/CMakeCache.txt ]]; then generator=(-G Ninja); fi
cmake -S . -B build-asan "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
  -DCMAKE_CXX_FLAGS="$sanitize" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DVKMESH_BUILD_VIEWER=OFF -DVKMESH_BUILD_PYTHON=OFF -DVKMESH_BUILD_FUZZERS=ON -DVKMESH_TESTS_BUILD_CLI=OFF >/dev/null
# No viewer: none of the tests below serves a page, and Boost.Beast's server is the longest file to compile under
# ASan (the viewer's wire format is fuzzed below). No CLI (VKMESH_TESTS_BUILD_CLI=OFF): it only parses options and
# drives the library's frame loop (vkmesh::Mapper), which test_mapper and test_map_file run here; its 15 files were
# ~2 minutes of this build and its tests ~1.5 minutes under ASan. The CLI's own bad-input tests run in the main suite.
# Only what is run below: every CPU test program and the GPU programs of the selected tests.
targets=(test_fusion test_incremental_mesh test_color test_mapper test_map_file)
for f in tests/cpu/test_*.cpp; do targets+=("$(basename "$f" .cpp)"); done
cmake --build build-asan -j"$jobs" --target "${targets[@]}" vkmesh_fuzzers
echo "sanitize: build-asan (tests and fuzzers) built after $((SECONDS - start)) s"

# GPU tests under ASan are slow on lavapipe (~8x their plain time); these cover the GPU paths that handle host
# memory the most: fusion against the CPU reference, the incremental mesh and its rebuild, colour, exporting, the
# Mapper's given, skipped, tracked and lost frames, the Reconstructor's save and load, and maps that cannot be
# loaded (saving and fusing the rest after loading, 43 s here, runs in the main suite; the parsers' own
# corrupt-file and bad-pose cases are CPU tests, all run here). The whole suite
# runs without sanitizers in scripts/test.sh. No validation layer here: that suite runs it too, and it is
# slow under ASan. (Determinism and the lock-free claim path, 2 minutes under ASan, are host-side the same
# code as the tests kept; they run in the main suite and under GPU-AV.)
gpu_tests='(GpuTest\.(FusedTsdfMatchesReference|EmptyVolumeExportsAnEmptyMesh|VertexColoursMatchReferenceMesherAndRebuild|MapsThatCannotBeLoadedAreClearErrors|ReconstructorSavesAndLoads)|Refinement/IncrementalTest\.IncrementalMeshEqualsRebuildFromScratch/false|MapperTest\..*)( .*)?$'
# CPU tests left out under ASan: the longest runs of the CPU reference mesher (1-2 minutes each under ASan,
# together a third of the job's test time), variants with more frames, noise or another epsilon of tests that
# run here in their short form (RefinementOnASlantedPlane, IncrementalEqualsFromScratch, ...): the same code,
# longer (RefinementHalvesIrregularity...: the noisier slanted plane's run on another plane, 2 minutes under ASan and
# the last test to finish; the sphere's and the torus's closed meshes: the mesher's code on other shapes, 30-35 s each;
# the lock-free claim order against the plain one, 35 s, and the tile slabs against the pixels' bands on 8 noisy
# frames at 2 strides, 29 s, whose tile code the short ReferenceAllocation.TileSlabs* tests run here: the two longest
# left, 2026-12-07, both of src/cpu/, the reference that the GPU tests compare against, which vkmesh itself never runs).
# They run in the main suite.
cpu_slow='^(ReferenceMesher\.(SphereSeenFromAllAroundIsClosedWithChiTwo|TorusSeenFromAllAroundIsClosedWithChiZero|RefinementOnASlantedPlaneNoisier|RefinementHalvesIrregularityOnANoisyNearlyFlatPlane|RefinementOnASlantedPlaneNoisierQuarterVoxel|RefinementOnASlantedPlaneQuarterVoxel|RefinementKeepsTheInvariantsEveryFrame|RevisitingKeepsTheHeapsBounded|LockFreeOrderGivesTheSameMesh)|ReferenceVolume\.FlippedCornersAndRetypeSetWithRefinementAndMinWeight|ReferenceAllocation\.TileSlabsCoverThePixelsBands)$'
echo "sanitize: running the CPU tests and the selected GPU tests"
(
  cd build-asan
  # EvalCli.*: the CPU tests that run the CLI, not built here.
  ctest --output-on-failure -j"$jobs" -L '^cpu$' -E "$cpu_slow|^EvalCli\\."
  # detect_leaks=0 for the GPU tests only: LeakSanitizer reports ~35-250 KB per process allocated from
  # "<unknown module>" frames, i.e. by lavapipe/LLVM code that the Vulkan loader has dlclose()d by exit;
  # no frame is in vkmesh, and an unloaded module cannot be matched by a suppression. The CPU tests above
  # keep leak detection on.
  ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" ctest --output-on-failure -j"$jobs" -L '^gpu$' -R "^($gpu_tests)"
)
echo "sanitize: tests passed after $((SECONDS - start)) s"

# --- (b) the fuzzers (built above, in build-asan) ---

# One fuzzer per core at a time: each is single-threaded, so the 13 targets x FUZZ_SECONDS take half the time on
# the 2-core CI machine, each still fuzzing for its full FUZZ_SECONDS.
fuzz_one() {
  local target=$1 corpus=$2
  local work=build-asan/corpus-work/$target        # new coverage goes here, the seed corpus stays as committed
  local findings=build-asan/findings/$target
  rm -rf "$work" "$findings"
  mkdir -p "$work" "$findings"
  # -timeout: one input taking 10 s is a hang; -rss_limit_mb also caps single allocations (malloc_limit).
  local rc=0
  build-asan/fuzz/"$target" -max_total_time="$fuzz_seconds" -rss_limit_mb=2048 -timeout=10 \
    -print_final_stats=1 -artifact_prefix="$findings/" "$work" "$corpus" >"build-asan/findings/$target.log" 2>&1 || rc=$?
  echo "$rc" >"build-asan/findings/$target.rc"
}
fuzz_targets=()
for corpus in fuzz/corpus/*/; do
  target=$(basename "$corpus")
  fuzz_targets+=("$target")
  while (( $(jobs -rp | wc -l) >= jobs )); do wait -n || true; done
  fuzz_one "$target" "$corpus" &
done
wait
status=0
for target in "${fuzz_targets[@]}"; do
  log=build-asan/findings/$target.log
  if [[ $(cat "build-asan/findings/$target.rc" 2>/dev/null) == 0 ]]; then
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    echo "fuzz: $target: $runs inputs in ${fuzz_seconds} s, no finding"
  else
    status=1
    echo "fuzz: $target FAILED; the report (tail of $log):"
    tail -n 60 "$log"
    ls -l "build-asan/findings/$target"
  fi
done
if (( status != 0 )); then
  echo "fuzz: findings above; reproduce with build-asan/fuzz/<target> build-asan/findings/<target>/<file>"
  exit 1
fi
echo "sanitize-fuzz: done in $((SECONDS - start)) s"
