#include "core/mesh_delta.h"

#include <algorithm>
#include <string>

#include "core/voxel_color.h"

namespace vkmesh {

size_t MeshDelta::count(DeltaKind kind) const {
    size_t n = 0;
    for (const auto& r : vertices) n += deltaKind(r.idKind) == kind;
    for (const auto& r : triangles) n += deltaKind(r.idKind) == kind;
    return n;
}

void MeshReplica::apply(const MeshDelta& delta) {
    const std::string where = "mesh delta of frame " + std::to_string(delta.frame);
    if (delta.frame <= lastFrame_)
        throw Error(where + " comes after frame " + std::to_string(lastFrame_) + ": frames must increase");
    // Removals first: an id removed and added in the same frame was reused.
    for (const auto& r : delta.triangles)
        if (deltaKind(r.idKind) == DeltaKind::Removed && !triangles_.erase(deltaId(r.idKind)))
            throw Error(where + " removes triangle " + std::to_string(deltaId(r.idKind)) + ", which does not exist");
    for (const auto& r : delta.vertices)
        if (deltaKind(r.idKind) == DeltaKind::Removed && !vertices_.erase(deltaId(r.idKind)))
            throw Error(where + " removes vertex " + std::to_string(deltaId(r.idKind)) + ", which does not exist");
    for (const auto& r : delta.vertices) {
        DeltaKind kind = deltaKind(r.idKind);
        uint32_t id = deltaId(r.idKind);
        if (kind == DeltaKind::Removed) continue;
        if (kind != DeltaKind::Added && kind != DeltaKind::Changed)
            throw Error(where + " has a vertex record of unknown kind " + std::to_string(uint32_t(kind)));
        if (kind == DeltaKind::Changed && !vertices_.count(id))
            throw Error(where + " changes vertex " + std::to_string(id) + ", which does not exist");
        vertices_[id] = {{r.px, r.py, r.pz}, {r.nx, r.ny, r.nz}, r.createdFrame, r.color};
    }
    for (const auto& r : delta.triangles) {
        DeltaKind kind = deltaKind(r.idKind);
        if (kind == DeltaKind::Removed) continue;
        if (kind != DeltaKind::Added)
            throw Error(where + " has a triangle record of kind " + std::to_string(uint32_t(kind)) + " (only added/removed exist)");
        triangles_[deltaId(r.idKind)] = {r.v0, r.v1, r.v2};
    }
    // Every triangle must stand on live vertices once the frame is complete.
    for (const auto& [id, t] : triangles_)
        for (uint32_t v : t)
            if (!vertices_.count(v))
                throw Error(where + ": triangle " + std::to_string(id) + " uses vertex " + std::to_string(v) + ", which does not exist");
    lastFrame_ = delta.frame;
}

Mesh MeshReplica::toMesh() const {
    std::vector<uint32_t> vertexIds;
    vertexIds.reserve(vertices_.size());
    for (const auto& [id, v] : vertices_) vertexIds.push_back(id);
    std::sort(vertexIds.begin(), vertexIds.end());
    std::unordered_map<uint32_t, uint32_t> dense;
    Mesh mesh;
    for (uint32_t id : vertexIds) {
        const VertexData& v = vertices_.at(id);
        dense[id] = uint32_t(mesh.positions.size());
        mesh.positions.push_back(v.position);
        mesh.normals.push_back(v.normal);
        mesh.vertexAge.push_back(lastFrame_ >= v.createdFrame ? lastFrame_ - v.createdFrame : 0);
        mesh.colors.push_back(vertexHasColor(v.color) ? vertexColorRgb(v.color) : std::array<uint8_t, 3>{128, 128, 128});
    }
    // As toMesh(ExportedMesh): colours only when some vertex has one.
    if (std::none_of(vertexIds.begin(), vertexIds.end(), [&](uint32_t id) { return vertexHasColor(vertices_.at(id).color); }))
        mesh.colors.clear();
    std::vector<uint32_t> triangleIds;
    for (const auto& [id, t] : triangles_) triangleIds.push_back(id);
    std::sort(triangleIds.begin(), triangleIds.end());
    for (uint32_t id : triangleIds) {
        const auto& t = triangles_.at(id);
        mesh.triangles.push_back({dense.at(t[0]), dense.at(t[1]), dense.at(t[2])});
    }
    return mesh;
}

}  // namespace vkmesh
