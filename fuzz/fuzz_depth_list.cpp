// Fuzz target: the depth-frame index parsers, TUM depth.txt ("timestamp path") and associations.txt
// (pairs side by side, the depth pair found by its path). Timestamps they return must be finite: a NaN
// would break the sort and the pose association after them.
#include "fuzz_common.h"
#include "io/parsers.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    for (bool associations : {false, true}) {
        vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
            std::istringstream in(text);
            auto frames = associations ? vkmesh::io::parseAssociations(in, "associations.txt", "/seq")
                                       : vkmesh::io::parseDepthList(in, "depth.txt", "/seq");
            for (const auto& f : frames)
                if (!std::isfinite(f.timestamp) || f.line == 0) std::abort();
        });
    }
    return 0;
}
