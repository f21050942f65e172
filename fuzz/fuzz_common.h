// Shared by the fuzz targets: run one parser on the input and treat vkmesh::Error as the expected outcome
// for bad input. Anything else that escapes (std::exception, cv::Exception, nlohmann's exceptions) is a
// bug in src/io and aborts, so that libFuzzer records the input as a crash.
#pragma once

#include "core/fuzzing.h"
#include "core/types.h"

#include <cstdio>
#include <cstdlib>
#include <exception>

namespace vkmesh::fuzz {

template <typename F>
void expectOnlyVkmeshErrors(F&& f) {
    fuzzing::activate();  // skip the checksums a mutation cannot forge (core/fuzzing.h)
    try {
        f();
    } catch (const vkmesh::Error&) {
        // Bad input reported the way vkmesh reports it: fine.
    } catch (const std::exception& e) {
        std::fprintf(stderr, "uncaught non-vkmesh exception: %s\n", e.what());
        std::abort();
    } catch (...) {
        std::fprintf(stderr, "uncaught exception of unknown type\n");
        std::abort();
    }
}

}  // namespace vkmesh::fuzz
