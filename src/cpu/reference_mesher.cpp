// The CPU reference mesher's state and the order of a frame's passes; each pass is in its own file:
// reference_mesh_dirty.cpp, _claim.cpp, _vertices.cpp, _triangulate.cpp, _gc.cpp (and _invariants.cpp).
#include "cpu/reference_mesh_internal.h"

#include "core/refinement.h"
#include "core/voxel_color.h"

namespace vkmesh::cpu {

using namespace mesh_detail;
using gpu::VOXELS_PER_BLOCK;

ReferenceMesher::ReferenceMesher(const VolumeParams& params, float minMeshWeight, uint32_t vertexCapacity,
                                 uint32_t chunkCapacity, const MesherOptions& options)
    : params_(params),
      minMeshWeight_(minMeshWeight),
      options_(options),
      refineEpsilon_(options.refineEpsilon ? *options.refineEpsilon : defaultRefineEpsilon(params.voxelSize)),
      vertexCapacity_(vertexCapacity),
      chunkCapacity_(chunkCapacity) {
    if (vertexCapacity == 0 || chunkCapacity == 0) throw Error("ReferenceMesher: heap capacities must be positive");
    if (chunkCapacity > kMaxChunkCapacity)
        throw Error("ReferenceMesher: chunk capacity " + std::to_string(chunkCapacity) + " exceeds " +
                    std::to_string(kMaxChunkCapacity) + " (the chunk index + 1 must fit in 23 bits of a cube state)");
    gpu::Vertex dead{};
    dead.refcount = gpu::DEAD_REFCOUNT;
    vertices_.assign(vertexCapacity, dead);
    vertexOwner_.assign(vertexCapacity, NO_OWNER);
    chunkTriangles_.resize(chunkCapacity);
    for (auto& chunk : chunkTriangles_) chunk.fill(gpu::INVALID_INDEX);
    // Stacks with their top at the back: index 0 is popped first.
    freeVertices_.resize(vertexCapacity);
    for (uint32_t i = 0; i < vertexCapacity; ++i) freeVertices_[i] = vertexCapacity - 1 - i;
    freeChunks_.resize(chunkCapacity);
    for (uint32_t i = 0; i < chunkCapacity; ++i) freeChunks_[i] = chunkCapacity - 1 - i;
}

void ReferenceMesher::createBlockStates(const ReferenceVolume& volume) {
    // A block the volume freed (recycling) has no meshing signs left: all outside, as recycle_free leaves them.
    for (auto& [coord, state] : blocks_)
        if (!volume.blocks().count(coord)) state.meshInside.reset();
    for (const auto& [coord, block] : volume.blocks()) {
        auto [it, inserted] = blocks_.try_emplace(coord);
        if (!inserted) continue;
        BlockMeshState& state = it->second;
        state.cubeState.fill(0);
        state.edgeVertex.fill(gpu::EMPTY_SLOT);
        state.coord = coord;
        state.index = uint32_t(blockByIndex_.size());
        blockByIndex_.push_back(&state);
    }
}

MeshFrameStats ReferenceMesher::updateAll(const ReferenceVolume& volume, uint32_t frameNumber) {
    std::vector<BlockCoord> all;
    all.reserve(volume.blocks().size());
    for (const auto& [coord, block] : volume.blocks()) all.push_back(coord);
    return update(volume, all, frameNumber, RetypeScope::AllCubes);
}

MeshFrameStats ReferenceMesher::update(const ReferenceVolume& volume, const std::vector<BlockCoord>& touched,
                                       uint32_t frameNumber, RetypeScope scope) {
    if (scope == RetypeScope::FlippedCorners) {
        if (volume.minMeshWeight() != minMeshWeight_)
            throw Error("ReferenceMesher: the volume flags corners at minMeshWeight " +
                        std::to_string(volume.minMeshWeight()) + ", the mesher meshes at " + std::to_string(minMeshWeight_));
    }
    MeshFrameStats stats;
    createBlockStates(volume);
    gcCandidates_.clear();
    releasedChunks_.clear();
    newVertices_.clear();

    // 0. Dirty marking: D, the cubes of D to re-evaluate, and their new types.
    std::vector<DirtyBlock> dirty = markDirty(volume, touched, scope, stats);
    chooseTypes(volume, dirty);
    // 1. Claim.
    claimVertices(dirty, stats, frameNumber);
    // 2. Update vertex positions and normals.
    updateVertices(volume, dirty, stats);
    // 3. Triangulate.
    for (DirtyBlock& b : dirty) triangulate(b, stats);
    // 4. Collect garbage.
    collectGarbage(stats);
    return stats;
}

uint32_t ReferenceMesher::incompleteCubes() const {
    uint32_t count = 0;
    for (const auto& [coord, state] : blocks_)
        for (uint32_t cubeState : state.cubeState)
            if (cubeState & gpu::CUBE_INCOMPLETE) ++count;
    return count;
}

Mesh ReferenceMesher::exportMesh(uint32_t currentFrame) const {
    Mesh mesh;
    std::vector<uint32_t> dense(vertexCapacity_, gpu::INVALID_INDEX);
    for (uint32_t v = 0; v < vertexCapacity_; ++v) {
        const gpu::Vertex& vertex = vertices_[v];
        if (vertex.refcount == gpu::DEAD_REFCOUNT || vertex.refcount == 0) continue;
        dense[v] = uint32_t(mesh.positions.size());
        mesh.positions.emplace_back(vertex.px, vertex.py, vertex.pz);
        mesh.normals.emplace_back(vertex.nx, vertex.ny, vertex.nz);
        mesh.vertexAge.push_back(currentFrame - vertex.createdFrame);
        mesh.colors.push_back(vertexHasColor(vertex.color) ? vertexColorRgb(vertex.color) : std::array<uint8_t, 3>{128, 128, 128});
    }
    // The GPU export's rule (api/exported_mesh.cpp): colours only when some vertex has one.
    bool anyColor = false;
    for (uint32_t v = 0; v < vertexCapacity_ && !anyColor; ++v)
        anyColor = vertices_[v].refcount != gpu::DEAD_REFCOUNT && vertices_[v].refcount != 0 && vertexHasColor(vertices_[v].color);
    if (!anyColor) mesh.colors.clear();
    for (const auto& [coord, state] : blocks_) {
        for (uint32_t cube = 0; cube < VOXELS_PER_BLOCK; ++cube) {
            const uint32_t chunk = state.cubeState[cube] >> gpu::CUBE_CHUNK_SHIFT;
            if (!chunk) continue;
            const auto& tris = chunkTriangles_[chunk - 1];
            for (int k = 0; k < int(gpu::TRIANGLES_PER_CHUNK); ++k)
                if (tris[3 * k] != gpu::INVALID_INDEX)
                    mesh.triangles.push_back({dense[tris[3 * k]], dense[tris[3 * k + 1]], dense[tris[3 * k + 2]]});
        }
    }
    return mesh;
}

}  // namespace vkmesh::cpu
