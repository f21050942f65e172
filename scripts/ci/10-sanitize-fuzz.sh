#!/usr/bin/env bash
# CI job: sanitizers and fuzzing (issue 5).
#  (a) builds vkmesh with clang under AddressSanitizer + UndefinedBehaviorSanitizer (build-asan,
#      RelWithDebInfo, tests on; any report aborts the test) and runs every CPU test plus the GPU tests
#      that cover fusion, the incremental mesh, mesh export and the CLI's handling of bad input, on lavapipe;
#  (b) builds the libFuzzer targets of fuzz/ (build-fuzz: the dataset, PLY, binary glTF, .vkmap and .vkframes readers, the viewer's wire format and page commands, the ROS 1 bag and MCAP containers and the ROS message decoders) and runs each from its seed corpus in
#      fuzz/corpus/<target>/ for FUZZ_SECONDS (default 15) seconds, one target per core at a time. Any crash, sanitizer report, leak,
#      timeout, out-of-memory or uncaught non-vkmesh exception fails the job; the input that caused it is
#      kept as build-fuzz/findings/<target>/crash-* (or leak-, timeout-, oom-) to reproduce with
#      `build-fuzz/fuzz/<target> <file>`.
# Needs clang, libclang-rt-14-dev (the sanitizer and libFuzzer runtimes) and llvm-symbolizer; installs them.
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$SECONDS
jobs=$(nproc)
fuzz_seconds=${FUZZ_SECONDS:-15}

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
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
  -DCMAKE_CXX_FLAGS="$sanitize" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DVKMESH_BUILD_VIEWER=OFF -DVKMESH_BUILD_PYTHON=OFF >/dev/null
# No viewer: none of the tests below serves a page, and Boost.Beast's server is the longest file to compile under
# ASan (the viewer's wire format is fuzzed below; the CLI without a viewer, as embedders build it, is built here).
# Only what is run below: the CLI, every CPU test program and the GPU programs of the selected tests
# (the render and refinement programs are left out to keep the job's build short on 2 cores).
targets=(vkmesh_cli test_fusion test_incremental_mesh test_cli)
for f in tests/cpu/test_*.cpp; do targets+=("$(basename "$f" .cpp)"); done
cmake --build build-asan -j"$jobs" --target "${targets[@]}"
echo "sanitize: build-asan built after $((SECONDS - start)) s"

# GPU tests under ASan are slow on lavapipe (a CLI test ~8x its plain time); these cover the GPU paths that
# handle host memory the most: fusion against the CPU reference, the incremental mesh and its rebuild,
# colour, fusing, exporting and saving/loading a map through the CLI (SaveLoad... runs `fuse` three times), and the
# CLI's bad-input handling (HostileDatasets...: bad camera files, a first frame of the wrong type, a later frame
# skipped; the parsers' own corrupt-file and bad-pose cases are CPU tests, all run here). The whole suite
# runs without sanitizers in scripts/test.sh. No validation layer here: that suite runs it too, and it is
# slow under ASan. (Determinism and the lock-free claim path, 2 minutes under ASan, are host-side the same
# code as the tests kept; they run in the main suite and under GPU-AV.)
gpu_tests='(GpuTest\.(FusedTsdfMatchesReference|EmptyVolumeExportsAnEmptyMesh|VertexColoursMatchReferenceMesherAndRebuild)|Refinement/IncrementalTest\.IncrementalMeshEqualsRebuildFromScratch/false)( .*)?$'
cli_tests='Cli\.(SaveLoadAndFirstFrameResumeTheRun|HostileDatasetsAreClearErrors)$'
# CPU tests left out under ASan: the longest runs of the CPU reference mesher (1-2 minutes each under ASan,
# together a third of the job's test time), variants with more frames, noise or another epsilon of tests that
# run here in their short form (RefinementOnASlantedPlane, IncrementalEqualsFromScratch, ...): the same code,
# longer (RefinementHalvesIrregularity...: the noisier slanted plane's run on another plane, 2 minutes under ASan and
# the last test to finish). They run in the main suite.
cpu_slow='^(ReferenceMesher\.(RefinementOnASlantedPlaneNoisier|RefinementHalvesIrregularityOnANoisyNearlyFlatPlane|RefinementOnASlantedPlaneNoisierQuarterVoxel|RefinementOnASlantedPlaneQuarterVoxel|RefinementKeepsTheInvariantsEveryFrame|RevisitingKeepsTheHeapsBounded)|ReferenceVolume\.FlippedCornersAndRetypeSetWithRefinementAndMinWeight)$'
echo "sanitize: running the CPU tests and the selected GPU tests"
(
  cd build-asan
  ctest --output-on-failure -j"$jobs" -L '^cpu$' -E "$cpu_slow"
  # detect_leaks=0 for the GPU tests only: LeakSanitizer reports ~35-250 KB per process allocated from
  # "<unknown module>" frames, i.e. by lavapipe/LLVM code that the Vulkan loader has dlclose()d by exit;
  # no frame is in vkmesh, and an unloaded module cannot be matched by a suppression. The CPU tests above
  # keep leak detection on.
  ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" ctest --output-on-failure -j"$jobs" -L '^gpu$' -R "^($gpu_tests|$cli_tests)"
)
echo "sanitize: tests passed after $((SECONDS - start)) s"

# --- (b) the fuzzers ---
echo "fuzz: building build-fuzz"
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" \
  -DVKMESH_BUILD_TESTS=OFF -DVKMESH_BUILD_FUZZERS=ON >/dev/null
cmake --build build-fuzz -j"$jobs" --target vkmesh_fuzzers
echo "fuzz: built after $((SECONDS - start)) s"

# One fuzzer per core at a time: each is single-threaded, so the 13 targets x FUZZ_SECONDS take half the time on
# the 2-core CI machine, each still fuzzing for its full FUZZ_SECONDS.
fuzz_one() {
  local target=$1 corpus=$2
  local work=build-fuzz/corpus-work/$target        # new coverage goes here, the seed corpus stays as committed
  local findings=build-fuzz/findings/$target
  rm -rf "$work" "$findings"
  mkdir -p "$work" "$findings"
  # -timeout: one input taking 10 s is a hang; -rss_limit_mb also caps single allocations (malloc_limit).
  local rc=0
  build-fuzz/fuzz/"$target" -max_total_time="$fuzz_seconds" -rss_limit_mb=2048 -timeout=10 \
    -print_final_stats=1 -artifact_prefix="$findings/" "$work" "$corpus" >"build-fuzz/findings/$target.log" 2>&1 || rc=$?
  echo "$rc" >"build-fuzz/findings/$target.rc"
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
  log=build-fuzz/findings/$target.log
  if [[ $(cat "build-fuzz/findings/$target.rc" 2>/dev/null) == 0 ]]; then
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    echo "fuzz: $target: $runs inputs in ${fuzz_seconds} s, no finding"
  else
    status=1
    echo "fuzz: $target FAILED; the report (tail of $log):"
    tail -n 60 "$log"
    ls -l "build-fuzz/findings/$target"
  fi
done
if (( status != 0 )); then
  echo "fuzz: findings above; reproduce with build-fuzz/fuzz/<target> build-fuzz/findings/<target>/<file>"
  exit 1
fi
echo "sanitize-fuzz: done in $((SECONDS - start)) s"
