// libFuzzer's convention, FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION, as a switch the fuzz targets turn on at run time:
// parsers then skip the checks a fuzzer cannot pass by mutation (the .vkmap, .vkframes and MCAP checksums) so that it
// reaches what lies behind them, and cap chunk sizes lower (a gigabyte decompression bomb would only report a timeout).
// A switch rather than a compile definition so that one sanitized build (scripts/ci/10-sanitize-fuzz.sh) serves the
// test suite, which needs every check, and the fuzzers. It exists only where VKMESH_FUZZING_HOOKS is defined
// (CMakeLists.txt, VKMESH_BUILD_FUZZERS); everywhere else active() is a constant false and the checks always run.
#pragma once

namespace vkmesh::fuzzing {

#ifdef VKMESH_FUZZING_HOOKS
bool active();
void activate();  // called by every fuzz target (fuzz/fuzz_common.h), never by vkmesh itself
#else
constexpr bool active() { return false; }
#endif

}  // namespace vkmesh::fuzzing
