#!/usr/bin/env bash
# CI job: lavapipe run two other ways than the main suite (docs/PORTABILITY.md).
#  (a) a small device: the GPU test suite, with validation, on 4-lane subgroups AND the block hash's
#      32-bit path at once, as on a mobile GPU without 64-bit atomics (the two were separate jobs; one run
#      of the suite instead of two keeps CI under its time goal, and the two settings touch different code:
#      subgroup operations in the compaction/prefix passes, atomics in the hash). Left out (skip_4lane below,
#      35 tests, 34-41 % of this run's time): the tests whose subject is the CLI (test_cli, GpuTest.Cli*: options,
#      files, output formats, reports) or the recordings' containers (test_recordings_fuse), which drive the
#      library's stages through `vkmesh` processes, and test_loop_closure, whose GPU tests track (they draw, and
#      skip here) and whose other tests run on the host only. The rest dispatches every shader build the whole
#      suite does here (the same 74 of shaders_gen_all/, measured with scripts/ci/tools/dispatch_log.c, 2026-12-07).
#      - LP_NATIVE_VECTOR_WIDTH=128 makes lavapipe's subgroups 4 wide instead of 8, so no shader may assume a
#        subgroup size. The tests that draw skip themselves there (a lavapipe heap overflow, reproduced without
#        vkmesh in docs/PORTABILITY.md).
#      - VKMESH_PRETEND_MISSING makes vkmesh treat shaderBufferInt64Atomics and shaderInt64 as absent
#        (docs/HASH.md): every compute shader runs in its @hash32 build and the 64-bit features are not
#        enabled, so the validation layer reports any shader that still uses a 64-bit type. Same tests, same
#        expectations as the main run.
#      - ... and unifiedMemory: the host writes a frame's images into a staging buffer that a copy takes to the
#        device, as on a discrete GPU, where the main run writes them in place (docs/PORTABILITY.md).
#  (b) GPU-assisted validation (the Khronos layer instruments every shader and checks each buffer access and
#      descriptor at run time) on a subset of the GPU tests that dispatches every compute shader of
#      shaders_comp/; under GPU-AV a test runs 3-5x slower on lavapipe, and the first ones to use a shader ~60x
#      (lavapipe compiles the instrumented shaders; later runs find them in Mesa's shader cache), so not the
#      whole suite. The job checks that the subset still dispatches every shader (an LD_PRELOAD shim,
#      scripts/ci/tools/dispatch_log.c, records the dispatched shaders) and fails naming any left out.
# Any validation message fails a test (the fixtures fail on what the layer's messenger received; GPU-AV
# reports through the same messenger). Uses the main suite's Release build in build/ (scripts/build.sh is
# a no-op when scripts/test.sh has just built it): nothing here needs other compiler flags.
# Usage: scripts/ci/20-portability.sh [4lane|gpu-av]   (default: both)
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$SECONDS
jobs=$(nproc)
parts=${1:-all}
case "$parts" in all|4lane|gpu-av) ;; *) echo "usage: $0 [4lane|gpu-av]" >&2; exit 2 ;; esac

scripts/install_deps.sh
scripts/build.sh
echo "portability: build up to date after $((SECONDS - start)) s"

# --- (a) 4-lane subgroups ---
if [[ $parts == all || $parts == 4lane ]]; then
  # The variable must really change the subgroup size (a newer Mesa could rename it).
  size=$(LP_NATIVE_VECTOR_WIDTH=128 vulkaninfo 2>/dev/null | sed -n 's/^[[:space:]]*subgroupSize[[:space:]]*= *//p' | head -n1)
  if [[ $size != 4 ]]; then
    echo "portability: LP_NATIVE_VECTOR_WIDTH=128 gives subgroupSize '${size}', not 4: the 4-lane run would test nothing" >&2
    exit 1
  fi
  echo "portability: GPU tests with 4-lane subgroups (LP_NATIVE_VECTOR_WIDTH=128, subgroupSize 4) on the 32-bit hash path, inputs staged"
  skip_4lane='^(Cli\.|GpuTest\.Cli|RecordingsFuse\.|RandomFerns\.|FrameRegistration\.|PoseGraph\.|LoopCloser\.|LoopClosure\.|RealLoopClosure\.)'
  (cd build && LP_NATIVE_VECTOR_WIDTH=128 VKMESH_PRETEND_MISSING=shaderBufferInt64Atomics,shaderInt64,unifiedMemory \
     VKMESH_VALIDATION=1 ctest -L '^gpu$' -E "$skip_4lane" --output-on-failure -j"$jobs")
  echo "portability: 4-lane, 32-bit-hash run passed after $((SECONDS - start)) s"
fi

# --- (b) GPU-assisted validation ---
if [[ $parts == all || $parts == gpu-av ]]; then
  # Together these dispatch every compute shader (checked below); each is also the test of one area:
  gpu_av_tests=(
    GpuTest.FusedTsdfMatchesReference                          # allocation + fusion against the CPU reference
    PixelStride/AllocationTest.MatchesReferenceAndCountersConserve/Stride1Tiles  # allocation by tiles (allocate_tiles)
    GpuTest.AllocationByTilesCoversObliqueWallsAndEmptyTilesLikeTheReference  # tiles: planes with g < 0, empty tiles
    GpuTest.BaselineMeshMatchesReference                       # baseline marching cubes (mesh_baseline)
    Refinement/IncrementalTest.IncrementalMeshEqualsRebuildFromScratch/true  # incremental mesh, mark-all-dirty rebuild, export
    GpuTest.VertexColoursMatchReferenceMesherAndRebuild        # colour: fused corner colours, vertex colours
    GpuTest.OwnedSlotMasksHoldExactlyTheOccupiedSlots          # owned-slot masks: claims, GC, recycling, growth, map load, rebuild
    GpuTest.RecyclingWithLockFreeClaims                        # lock-free claims, recycling, hash rebuild (rehash_*)
    GpuTest.RefinementOnASlantedPlaneKeepsTheMeshWhole         # refinement per corner (retype passes), against unrefined
    MeshDeltas.FollowHeapExhaustionGrowthAndRecycling          # deltas (diff_*, plan_deltas), heap growth, pending dirty
    OwnDevice.PublishedMeshEqualsTheExportAndSurvivesARebuild  # published mesh: export to draw-ready buffers
    GpuTest.TinyCapacitiesGrowToTheMeshOfAmpleOnes             # every capacity grows (rebound buffers), deferred frames
    BothAtomicPaths/PathTest.HashUnderContentionInsertLookupRemoveRebuildGrow/Int64Atomics  # the hash alone (test_hash_access)
    BothAtomicPaths/PathTest.HashUnderContentionInsertLookupRemoveRebuildGrow/Atomics32     # ... and its 32-bit build
    Tracking.IcpSumsMatchCpuReference                          # tracking: filter, pyramids, model maps, ICP sums (track_*)
    Tracking.GpuSolvedStepMatchesTheHostSolve                  # tracking's GPU-solved mode (track_icp_solve)
    SolvedOn/TrackingModes.JumpPastTheBoundIsRejectedAndTrackingPicksUpAgain/Gpu  # loss on the GPU (track_decide), fusion in tracking's submission, a skipped frame
    DeintegrationTest.GpuMatchesTheCpuReferenceBitForBit       # de-integration: lookup-only allocation, fusion backwards, free_emptied
    GpuTest.ABudgetBelowWhatTheViewReachesKeepsWhatItReachesAndSaysSoOnce  # paging out and in (page_*), against the unpaged map
  )
  # Parameterized tests are named "Suite/Test.Name/Param  # GetParam() = ..." by gtest_discover_tests: a name
  # ends at the end of the string or at a space.
  regex="^($(IFS='|'; echo "${gpu_av_tests[*]}" | sed 's/\./\\./g'))(\$| )"
  # A renamed test would otherwise drop out silently (ctest -R runs what matches, even nothing).
  found=$(cd build && ctest -N -R "$regex" | sed -n 's/^Total Tests: //p')
  if [[ $found != "${#gpu_av_tests[@]}" ]]; then
    echo "portability: ${found:-0} of the ${#gpu_av_tests[@]} GPU-AV tests exist; missing:" >&2
    listed=$(cd build && ctest -N)
    for t in "${gpu_av_tests[@]}"; do grep -qF " $t" <<<"$listed" || echo "  $t" >&2; done
    exit 1
  fi

  tools=build/ci-tools
  mkdir -p "$tools"
  gcc -shared -fPIC -O2 -Wall -Wextra -Werror -o "$tools/dispatch_log.so" scripts/ci/tools/dispatch_log.c -ldl
  gcc -DDISPATCH_LOG_HASH_FILES -O2 -Wall -Wextra -Werror -o "$tools/spv_hash" scripts/ci/tools/dispatch_log.c -ldl -lpthread
  log=$PWD/$tools/gpu_av_dispatches.txt
  rm -f "$log"

  echo "portability: ${#gpu_av_tests[@]} GPU tests under GPU-assisted validation"
  (cd build && LD_PRELOAD="$PWD/ci-tools/dispatch_log.so" VKMESH_DISPATCH_LOG="$log" \
     VK_LAYER_ENABLES=VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_EXT VKMESH_VALIDATION=1 \
     ctest -R "$regex" --output-on-failure -j"$jobs" --timeout 900)

  # Every compute shader, shaders_comp/**/<name>.comp, compiled to build/shaders_gen_all/<name>.spv
  # (cmake/EmbedShaders.cmake), must have been dispatched by the tests above.
  spv=()
  declare -A source_of
  while read -r comp; do
    name=$(basename "$comp" .comp)
    if [[ ! -f build/shaders_gen_all/$name.spv ]]; then
      echo "portability: no build/shaders_gen_all/$name.spv for $comp: the coverage check needs updating" >&2
      exit 1
    fi
    spv+=("build/shaders_gen_all/$name.spv")
    source_of[build/shaders_gen_all/$name.spv]=$comp
  done < <(find shaders_comp -name '*.comp' | sort)
  if grep -q '^overflow' "$log" 2>/dev/null; then
    echo "portability: dispatch_log.c's tables overflowed; raise kMaxEntries" >&2
    exit 1
  fi
  hashes=$("$tools/spv_hash" "${spv[@]}")
  missing=()
  while read -r hash file; do
    grep -q "^$hash " "$log" 2>/dev/null || missing+=("${source_of[$file]}")
  done <<<"$hashes"
  if (( ${#missing[@]} )); then
    echo "portability: the GPU-AV tests did not dispatch ${#missing[@]} of ${#spv[@]} compute shaders; add a test that does:" >&2
    printf '  %s\n' "${missing[@]}" >&2
    exit 1
  fi
  echo "portability: GPU-AV run passed, all ${#spv[@]} compute shaders dispatched, after $((SECONDS - start)) s"
fi
echo "portability: done in $((SECONDS - start)) s"
