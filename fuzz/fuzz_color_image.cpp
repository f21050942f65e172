// Fuzz target: colour image decoding (Dataset::loadColor's path for every frame with colour): the PNG/JPEG
// header checks (the JPEG frame-header walk included), OpenCV's decoders (libpng, libjpeg) on what passes
// them, the type check and the BGR -> RGB conversion. An image that decodes must be RGB8 within the limits.
#include "fuzz_common.h"
#include "io/parsers.h"

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
        const vkmesh::ColorImage c = vkmesh::io::decodeColorImage(bytes, "rgb/000000.png");
        if (c.width <= 0 || c.height <= 0 || uint64_t(c.width) * c.height > vkmesh::io::kMaxDepthImagePixels ||
            c.rgb.size() != size_t(c.width) * c.height * 3)
            std::abort();
    });
    return 0;
}
