// Fuzz target: depth image loading, the path every frame of every layout goes through: the PNG header
// checks, OpenCV's decoder (libpng) on what passes them, the type check, then the conversion to metres.
// An image that decodes must be 16-bit single-channel within the size limits, and its metres finite.
#include "fuzz_common.h"
#include "io/parsers.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include <opencv2/core/utility.hpp>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const bool once = [] {
        cv::setNumThreads(0);  // no worker threads: one input at a time, reproducibly
        return true;
    }();
    (void)once;
    vkmesh::fuzz::expectOnlyVkmeshErrors([&] {
        const std::string_view bytes(reinterpret_cast<const char*>(data), size);
        cv::Mat raw = vkmesh::io::decodeDepthPng(bytes, "depth/000000.png");
        if (raw.type() != CV_16UC1 || raw.empty() || uint64_t(raw.cols) * raw.rows > vkmesh::io::kMaxDepthImagePixels)
            std::abort();
        vkmesh::DepthImage d = vkmesh::io::rawDepthToMeters(raw, 5000.0, uint16_t(65535), 4.0f);
        if (d.meters.size() != size_t(d.width) * d.height) std::abort();
        for (float m : d.meters)
            if (!std::isfinite(m) || m < 0 || m > 4.0f) std::abort();
    });
    return 0;
}
