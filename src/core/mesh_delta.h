// Mesh deltas: what one frame changed in the persistent mesh (docs/DELTAS.md), and a replica that a
// remote viewer keeps up to date by applying them. Vertex ids are heap indices and triangle ids are
// chunk slots: stable while the vertex or triangle lives, reused after it is removed.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "core/types.h"
#include "core/mesh.h"
#include "shared_layout.h"   // the delta records (their sizes are checked in gpu/layout.h)

namespace vkmesh {

enum class DeltaKind : uint32_t {
    Added = gpu::DELTA_ADDED,      // a new vertex/triangle under this id (replaces what the id held, if anything)
    Changed = gpu::DELTA_CHANGED,  // vertices only: new position, normal and/or colour
    Removed = gpu::DELTA_REMOVED,
};

inline DeltaKind deltaKind(uint32_t idKind) { return DeltaKind(idKind >> gpu::DELTA_KIND_SHIFT); }
inline uint32_t deltaId(uint32_t idKind) { return idKind & gpu::DELTA_ID_MASK; }

// One frame's changes, records in no particular order; at most one record per id and list.
struct MeshDelta {
    uint32_t frame = 0;                                 // frame number (1 = first integrated frame)
    std::vector<gpu::DeltaVertexRecord> vertices;       // Added/Changed carry position, normal, createdFrame, colour
    std::vector<gpu::DeltaTriangleRecord> triangles;    // Added carry the 3 vertex ids
    size_t count(DeltaKind kind) const;                 // vertices + triangles of that kind
};

// The mesh as a viewer that only ever saw the deltas knows it.
class MeshReplica {
public:
    struct VertexData {
        Eigen::Vector3f position, normal;
        uint32_t createdFrame = 0;
        uint32_t color = 0;   // gpu::Vertex::color (alpha 0: none)
    };

    // Applies one frame: removals first, then additions and changes. Throws Error naming the frame and
    // the id when the delta does not fit the replica (removing or changing an unknown id, a triangle
    // referencing a vertex that does not exist once the whole frame is applied, frames out of order).
    void apply(const MeshDelta& delta);
    size_t vertexCount() const { return vertices_.size(); }
    size_t triangleCount() const { return triangles_.size(); }
    uint32_t lastFrame() const { return lastFrame_; }
    // Dense copy (vertices ordered by id, triangles by id) with normals, vertex ages (lastFrame - created) and
    // colours (as toMesh(ExportedMesh) gives them).
    Mesh toMesh() const;

private:
    std::unordered_map<uint32_t, VertexData> vertices_;
    std::unordered_map<uint32_t, std::array<uint32_t, 3>> triangles_;
    uint32_t lastFrame_ = 0;
};

}  // namespace vkmesh
