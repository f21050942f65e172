// The picture the renderer returns: plain pixels, no Vulkan and no image library, so that io/png.h (the
// vkmesh_io library) can write it without the renderer linking OpenCV.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace vkmesh::render {

// An RGBA8 image, row-major, top row first.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<uint8_t> rgba;
    const uint8_t* pixel(int x, int y) const { return &rgba[(static_cast<size_t>(y) * width + x) * 4]; }
};

}  // namespace vkmesh::render
