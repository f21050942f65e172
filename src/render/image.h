// The renderer's picture: vkmesh::Image (core/image.h), by its renderer name.
#pragma once

#include "core/image.h"

namespace vkmesh::render {

using Image = vkmesh::Image;

}  // namespace vkmesh::render
