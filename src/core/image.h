// A picture as plain pixels: what the renderer returns and io/png.h writes, with no Vulkan and no image library,
// so that neither side depends on the other.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace vkmesh {

// An RGBA8 image, row-major, top row first.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<uint8_t> rgba;
    const uint8_t* pixel(int x, int y) const { return &rgba[(static_cast<size_t>(y) * width + x) * 4]; }
};

}  // namespace vkmesh
