// The one conversion of the GPU's compacted mesh (gpu::ExportedMesh, from GpuVolume::exportMesh or
// Reconstructor::downloadMesh) into a host Mesh (io/ply.h) for saving, evaluating, drawing or comparing.
#pragma once

#include <cstdint>
#include <optional>

#include "gpu/gpu_volume.h"
#include "io/ply.h"

namespace vkmesh {

// Positions, normals, colours (when any vertex has one; grey for those without) and triangles in the export's order. With the current frame number (the number of
// frames integrated), also each vertex's age: currentFrame - createdFrame (PLY's `age` property).
Mesh toMesh(const gpu::ExportedMesh& exported, std::optional<uint32_t> currentFrame = std::nullopt);

}  // namespace vkmesh
