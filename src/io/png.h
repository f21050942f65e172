// PNG writing (OpenCV imgcodecs), part of the vkmesh_io library: the GPU core and the renderer hand over
// plain pixels and never link an image library. PNG reading is in dataset.cpp (Dataset::loadDepth).
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/types.h"
#include "core/image.h"

namespace vkmesh::io {

// A 16-bit single-channel PNG of `pixels` (width x height, row-major, top row first): raw depth units as
// in TUM RGB-D. Throws Error naming the file when the sizes disagree or it cannot be written.
void writeDepthPng(const std::filesystem::path& path, int width, int height, const std::vector<uint16_t>& pixels);

// An 8-bit RGB PNG of the renderer's RGBA image (alpha dropped). Throws Error naming the file for an empty
// or inconsistent image or one that cannot be written.
void writePng(const std::filesystem::path& path, const Image& image);

// An 8-bit RGB PNG of a colour image. Throws Error naming the file for an empty or inconsistent image or one
// that cannot be written.
void writeColorPng(const std::filesystem::path& path, const ColorImage& image);

}  // namespace vkmesh::io
