// Claim (docs/MESH.md, pass 1; shaders_comp/claim_vertices/mesh_claim.comp): every edge a dirty cube's new type needs
// gets a vertex from the heap, block by block or in the lock-free parity passes.
#include "cpu/reference_mesh_internal.h"

#include <algorithm>
#include <set>

namespace vkmesh::cpu {

using namespace mesh_detail;
using gpu::VOXELS_PER_BLOCK;

// Block by block (the default order), or in the 4 parity passes of the lock-free variant, each over all of D.
// Within one lock-free pass no two cubes may look at the same edge slot (counted: lockFreeSharedSlots).
void ReferenceMesher::claimVertices(std::vector<DirtyBlock>& dirty, MeshFrameStats& stats, uint32_t frameNumber) {
    if (!options_.lockFree) {
        for (DirtyBlock& b : dirty)
            for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube)
                if (b.retype.test(cube)) claimCube(b, cube, stats, frameNumber);
        return;
    }
    const MarchingCubesTables& tables = marchingCubesTables();
    for (const auto& pass : kParityPasses) {
        std::set<uint64_t> slotsSeen;  // (owner block index, cube, axis) of the slots this pass looked at
        for (DirtyBlock& b : dirty) {
            for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
                if (!b.retype.test(cube)) continue;
                const int parity = globalParity(b.coord, cube);
                if (parity != pass[0] && parity != pass[1]) continue;
                const uint32_t mask = tables.edgeMask[b.newType[cube]];
                for (int e = 0; e < kCubeEdges; ++e) {
                    if (!((mask >> e) & 1)) continue;
                    const DirtyBlock::Slot slot = b.edgeSlot(cube, e);
                    if (!slotsSeen.insert(globalEdgeId(*slot.state, slot.cube, slot.axis)).second)
                        ++stats.lockFreeSharedSlots;
                }
                claimCube(b, cube, stats, frameNumber);
            }
        }
    }
}

// Claim (docs/MESH.md, pass 1) for one cube: every edge of its new type without a vertex gets one from the heap.
void ReferenceMesher::claimCube(DirtyBlock& b, uint32_t cube, MeshFrameStats& stats, uint32_t frameNumber) {
    const uint32_t mask = marchingCubesTables().edgeMask[b.newType[cube]];
    for (int e = 0; e < kCubeEdges; ++e) {
        if (!((mask >> e) & 1)) continue;
        const DirtyBlock::Slot slot = b.edgeSlot(cube, e);
        if (slot.vertex() != gpu::EMPTY_SLOT) continue;
        if (freeVertices_.empty()) {  // the slot stays EMPTY; triangles on it become INVALID
            ++stats.vertexExhausted;
            continue;
        }
        const uint32_t v = freeVertices_.back();
        freeVertices_.pop_back();
        vertexHighWater_ = std::max(vertexHighWater_, liveVertices());
        gpu::Vertex& vertex = vertices_[v];
        vertex = gpu::Vertex{};
        vertex.refcount = 0;
        vertex.createdFrame = frameNumber;
        vertexOwner_[v] = globalEdgeId(*slot.state, slot.cube, slot.axis);
        slot.vertex() = v;
        newVertices_.push_back(v);
        gcCandidates_.push_back(v);  // freed at the end of the frame if no triangle takes it
        ++stats.verticesAllocated;
    }
}

}  // namespace vkmesh::cpu
