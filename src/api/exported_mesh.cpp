#include "api/exported_mesh.h"

#include <algorithm>

#include "core/voxel_color.h"

namespace vkmesh {

Mesh toMesh(const gpu::ExportedMesh& exported, std::optional<uint32_t> currentFrame) {
    Mesh mesh;
    mesh.positions.reserve(exported.vertices.size());
    mesh.normals.reserve(exported.vertices.size());
    for (const gpu::Vertex& v : exported.vertices) {
        mesh.positions.emplace_back(v.px, v.py, v.pz);
        mesh.normals.emplace_back(v.nx, v.ny, v.nz);
        if (currentFrame) mesh.vertexAge.push_back(*currentFrame - v.createdFrame);
    }
    mesh.triangles = exported.triangles;
    // Colours when the volume fused any (alpha 255); a vertex whose corners never saw colour is grey.
    if (std::any_of(exported.vertices.begin(), exported.vertices.end(), [](const gpu::Vertex& v) { return vertexHasColor(v.color); })) {
        mesh.colors.reserve(exported.vertices.size());
        for (const gpu::Vertex& v : exported.vertices)
            mesh.colors.push_back(vertexHasColor(v.color) ? vertexColorRgb(v.color) : std::array<uint8_t, 3>{128, 128, 128});
    }
    return mesh;
}

}  // namespace vkmesh
