// The one conversion of the GPU's compacted mesh (gpu::ExportedMesh, from GpuVolume::exportMesh or
// Reconstructor::downloadMesh) into a host Mesh (io/ply.h) for saving, evaluating, drawing or comparing.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gpu/gpu_volume.h"
#include "core/mesh.h"

namespace vkmesh {

// Positions, normals, colours (when any vertex has one; grey for those without) and triangles in the export's order. With the current frame number (the number of
// frames integrated), also each vertex's age: currentFrame - createdFrame (PLY's `age` property).
Mesh toMesh(const gpu::ExportedMesh& exported, std::optional<uint32_t> currentFrame = std::nullopt);

// The mesh at the end of a run, with what `vkmesh fuse --stats` says of it: the persistent shared-vertex mesh
// compacted on the GPU (ages in the GPU's frame numbers), or in baseline mode the marching-cubes soup. With
// `analyse` (what the paper's evaluation reads, `fuse --analyse-mesh`): the baseline's vertex count measured on the
// same TSDF (the paper's memory comparison), and the shared-vertex mesh's regularity and topology; they cost a GPU
// pass over every block and two passes over the mesh on the host, so a plain run leaves them out.
struct RunMesh {
    Mesh mesh;
    bool analysed = false;
    size_t baselineVertices = 0;
    uint32_t unreferencedVertices = 0;
    double sliverTriangleShare = 0;    // smallest angle < 10 degrees
    double irregularCubeShare = 0;     // surface cubes whose type is not one of the six half-cube types
    size_t boundaryEdges = 0, nonManifoldEdges = 0;   // of the shared-vertex mesh (a soup has no shared edges)
    size_t coincidentVertices = 0;     // vertices at exactly the position of another (0 by design)
    std::vector<std::pair<std::string, double>> stageMs;   // GPU ms of the extraction's stages
};
RunMesh meshOfRun(gpu::GpuVolume& volume, bool analyse);

}  // namespace vkmesh
