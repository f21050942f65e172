// Garbage collection (docs/MESH.md, pass 4; shaders_comp/mesh_gc/free_vertices.comp, free_chunks.comp): the frame's
// candidates still without a triangle go back to the vertex heap, released chunks to the chunk heap.
#include "cpu/reference_mesh_internal.h"

namespace vkmesh::cpu {

using namespace mesh_detail;
using gpu::VOXELS_PER_BLOCK;

void ReferenceMesher::collectGarbage(MeshFrameStats& stats) {
    for (uint32_t v : gcCandidates_) {
        gpu::Vertex& vertex = vertices_[v];
        if (vertex.refcount != 0) continue;  // taken again, or already freed (a vertex can be a candidate twice)
        vertex.refcount = gpu::DEAD_REFCOUNT;
        BlockMeshState& owner = *blockByIndex_[vertexOwner_[v] / SLOTS_PER_BLOCK];
        owner.edgeVertex[vertexOwner_[v] % SLOTS_PER_BLOCK] = gpu::EMPTY_SLOT;
        vertexOwner_[v] = NO_OWNER;
        freeVertices_.push_back(v);
        ++stats.verticesFreed;
    }
    for (uint32_t c : releasedChunks_) {
        freeChunks_.push_back(c);
        ++stats.chunksFreed;
    }
    gcCandidates_.clear();
    releasedChunks_.clear();
}

}  // namespace vkmesh::cpu
