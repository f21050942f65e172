#include "api/exported_mesh.h"

#include <algorithm>

#include "core/mesh_analysis.h"
#include "core/refinement.h"
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

RunMesh meshOfRun(gpu::GpuVolume& volume, bool analyse) {
    RunMesh r;
    if (volume.config().meshMode != gpu::MeshMode::Incremental) {
        gpu::TriangleSoup soup = volume.extractBaselineMesh(&r.stageMs);
        r.mesh.positions = soup.vertices;
        for (uint32_t t = 0; t < soup.triangleCount(); ++t) r.mesh.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
        r.baselineVertices = soup.vertices.size();
        r.analysed = true;   // a soup has nothing more to analyse
        return r;
    }
    const gpu::ExportedMesh exported = volume.exportMesh(&r.stageMs);
    r.unreferencedVertices = exported.unreferencedVertices;
    r.mesh = toMesh(exported, volume.frameNumber());   // ages in the GPU's frame numbers, as createdFrame
    if (!analyse) return r;
    r.analysed = true;
    r.baselineVertices = volume.countBaselineVertices();
    // Regularity (what refinement improves) and cracks (what refinement must not open: edges with one triangle).
    r.sliverTriangleShare = triangleRegularity(r.mesh).sliverShare();
    const std::array<uint64_t, 256> types = volume.surfaceCubeTypes();
    uint64_t surface = 0, irregular = 0;
    for (int t = 0; t < 256; ++t) {
        surface += types[t];
        if (!isRegularType(t)) irregular += types[t];
    }
    r.irregularCubeShare = surface ? double(irregular) / double(surface) : 0.0;
    const TopologyReport topology = analyzeTopology(r.mesh);
    r.boundaryEdges = topology.boundaryEdges;
    r.nonManifoldEdges = topology.nonManifoldEdges;
    r.coincidentVertices = countDuplicatePositions(r.mesh);
    return r;
}

}  // namespace vkmesh
