#include "api/exported_mesh.h"

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
    return mesh;
}

}  // namespace vkmesh
