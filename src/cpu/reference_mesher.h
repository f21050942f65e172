// The CPU reference of the incremental shared-vertex mesh (docs/MESH.md, after Dong et al., ICRA 2018):
// one persistent mesh beside the TSDF, updated in place every frame over the dirty blocks only. Every
// vertex sits on exactly one cube edge and belongs to the cube whose corner 0 is the edge's low end; a cube
// keeps the MC type its triangles were built from and rebuilds them only when that type changes. A frame
// re-evaluates only the cubes around the corners fusion flipped (ReferenceVolume::retypeCubes()) and the
// INCOMPLETE ones, as the GPU does; optionally with mesh refinement (docs/REFINEMENT.md: the type built is
// refineType(stored type, MC type, corners, epsilon)) and in the lock-free claim order.
//
// Serial and plain on purpose: it states what the GPU stages (shaders_comp/mesh_*.comp) compute, and the
// tests compare the two (same triangles as position triples, same vertex count). Positions use exactly the
// float operations of ReferenceVolume::extractBaselineMesh, so they equal the baseline's bit for bit.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <set>
#include <optional>
#include <string>
#include <vector>

#include "cpu/reference_block.h"
#include "cpu/reference_volume.h"
#include "core/mesh.h"
#include "shared_layout.h"

namespace vkmesh::cpu {

// What one update did. Counts are over the frame's passes.
struct MeshFrameStats {
    uint32_t dirtyBlocks = 0;        // |D|
    uint32_t cubesListed = 0;        // cubes of D visited by claim and triangulate (the GPU's retype list)
    uint32_t cubesRetyped = 0;       // cubes whose triangles were rebuilt (type changed, or INCOMPLETE)
    uint32_t verticesAllocated = 0;  // claim: vertices taken from the heap
    uint32_t verticesFreed = 0;      // garbage collection: vertices given back
    uint32_t trianglesCreated = 0;
    uint32_t trianglesReleased = 0;
    uint32_t trianglesInvalid = 0;   // triangles not created (an edge without a vertex, or no chunk)
    uint32_t vertexExhausted = 0;    // claims the vertex heap could not serve (the slot stays EMPTY)
    uint32_t chunkExhausted = 0;     // cubes that needed a chunk the chunk heap could not give
    uint32_t chunksAllocated = 0;
    uint32_t chunksFreed = 0;
    // Vertices claimed this frame whose owner cube lies in a block outside D: the per-cube update pass over D
    // does not visit them, so the update pass also positions every vertex allocated this frame (see update()).
    uint32_t newVerticesOutsideDirty = 0;
    // Lock-free claim order only: edge slots looked at by two cubes of the same parity pass (a race on the
    // GPU's plain read-and-write claim). Always 0 by construction; counted to show it.
    uint32_t lockFreeSharedSlots = 0;
};

// The mesh state of one block, created (all slots EMPTY, every cube state 0) the first time the block exists in
// the volume.
struct BlockMeshState {
    // Per cube (index x + 8 (y + 8 z)), the GPU's cube state: the MC type its triangles were built from
    // (CUBE_TYPE_MASK), CUBE_INCOMPLETE, and its triangle chunk + 1 from bit CUBE_CHUNK_SHIFT on (0 = none).
    std::array<uint32_t, gpu::VOXELS_PER_BLOCK> cubeState{};
    // Per cube and axis (index cube * 3 + axis): the vertex on the edge leaving the cube's corner 0 along that
    // axis, or EMPTY_SLOT.
    std::array<uint32_t, gpu::VOXELS_PER_BLOCK * 3> edgeVertex{};
    // With refinement, per corner: inside for meshing (refinedCornerInside), as last decided; the GPU's mesh signs.
    CubeMask meshInside;
    BlockCoord coord{};
    uint32_t index = 0;  // creation order: the block number in global edge ids (block * 512 + cube) * 3 + axis
};

// Options of the mesher beyond its heap sizes (docs/REFINEMENT.md).
struct MesherOptions {
    bool refine = false;                 // mesh refinement (paper §V.F; GpuVolumeConfig has it on by default): claim and triangulate use refinedCubeType()
    std::optional<float> refineEpsilon;  // metres; default defaultRefineEpsilon(voxelSize) = half a voxel
    // The lock-free claim order (paper §V.C): 4 passes, one per parity class {000,111}, {001,110}, {010,101},
    // {100,011} of the cube's global position (x&1, y&1, z&1). Serially it only changes the order of claims
    // (so which heap index a vertex gets), never the mesh.
    bool lockFree = false;
};

// Which cubes of D one update() re-evaluates (claim + triangulate).
enum class RetypeScope {
    // The GPU's rule: the cubes of volume.retypeCubes() (the 8 cubes around every corner the last integrate()
    // flipped), with refinement the 8 cubes around every corner whose meshing sign changed, and the INCOMPLETE
    // cubes of D. Requires update() after every integrate().
    FlippedCorners,
    // Every cube of D (a from-scratch rebuild: updateAll()).
    AllCubes,
};

class ReferenceMesher {
public:
    // The state words, slots and heaps are the GPU's (shared_layout.h): EMPTY_SLOT, INVALID_INDEX,
    // DEAD_REFCOUNT, CUBE_*, TRIANGLES_PER_CHUNK, CHUNK_WORDS and gpu::Vertex.
    static constexpr uint32_t kMaxChunkCapacity = (1u << (32 - gpu::CUBE_CHUNK_SHIFT)) - 1;  // chunk + 1 must fit

    // Throws Error for a zero capacity or a chunk capacity above kMaxChunkCapacity.
    explicit ReferenceMesher(const VolumeParams& params, float minMeshWeight = 1.0f,
                             uint32_t vertexCapacity = 1u << 20, uint32_t chunkCapacity = 1u << 20,
                             const MesherOptions& options = {});

    // One frame of docs/MESH.md on the TSDF as it is now; `touched` = the blocks the frame fused
    // (volume.lastTouched()), `frameNumber` goes into new vertices' createdFrame. With the default scope, the
    // cubes re-evaluated are the volume's retypeCubes() and the INCOMPLETE cubes of D; then the volume must
    // have this mesher's minMeshWeight (throws Error otherwise: its flipped corners would not be the ones this
    // mesher needs).
    MeshFrameStats update(const ReferenceVolume& volume, const std::vector<BlockCoord>& touched, uint32_t frameNumber,
                          RetypeScope scope = RetypeScope::FlippedCorners);
    // Every block of the volume dirty and every cube re-evaluated: on a fresh mesher, the from-scratch extraction.
    MeshFrameStats updateAll(const ReferenceVolume& volume, uint32_t frameNumber);

    const MesherOptions& options() const { return options_; }
    float refineEpsilon() const { return refineEpsilon_; }  // metres, the default resolved

    // Dense copy: the live vertices (refcount > 0) in heap order with positions, normals and
    // vertexAge = currentFrame - createdFrame; the live triangles (blocks in coordinate order, then cubes).
    Mesh exportMesh(uint32_t currentFrame) const;

    // Violated invariants, empty when all hold: refcount = number of live triangles using the vertex and > 0 for
    // every live vertex; owner slot points back (and every filled slot points to a live vertex it owns);
    // live + free = capacity for both heaps; every live chunk belongs to exactly one cube; a complete cube's
    // triangles are exactly its type's triangles on its current edge vertices.
    std::vector<std::string> checkInvariants() const;

    uint32_t liveVertices() const { return vertexCapacity_ - uint32_t(freeVertices_.size()); }
    uint32_t vertexHighWater() const { return vertexHighWater_; }  // most live vertices at any time
    uint32_t liveChunks() const { return chunkCapacity_ - uint32_t(freeChunks_.size()); }
    uint32_t chunkHighWater() const { return chunkHighWater_; }
    uint32_t incompleteCubes() const;  // cubes marked INCOMPLETE (rebuilt when next dirty)
    uint32_t vertexCapacity() const { return vertexCapacity_; }
    uint32_t chunkCapacity() const { return chunkCapacity_; }

    const std::map<BlockCoord, BlockMeshState>& blockStates() const { return blocks_; }
    const gpu::Vertex& vertex(uint32_t v) const { return vertices_.at(v); }

private:
    struct DirtyBlock;
    // A block and its 7 neighbours in +x, +y, +z (indexed like cube corners; null where not allocated).
    using TsdfBlocks = std::array<const ReferenceBlock*, 8>;

    // The passes of update(), each in its own file (reference_mesh_<pass>.cpp).
    void createBlockStates(const ReferenceVolume& volume);
    // Dirty marking (reference_mesh_dirty.cpp): D, the cubes to re-evaluate and their new types.
    std::vector<DirtyBlock> markDirty(const ReferenceVolume& volume, const std::vector<BlockCoord>& touched,
                                      RetypeScope scope, MeshFrameStats& stats);
    // With refinement: re-decides every corner of D's meshing sign and marks the 8 cubes around each that changed.
    // Returns the corners (global grid positions) whose meshing sign changed.
    std::set<std::array<int, 3>> decideMeshSigns(const ReferenceVolume& volume, std::vector<DirtyBlock>& dirty) const;
    void chooseTypes(const ReferenceVolume& volume, std::vector<DirtyBlock>& dirty) const;
    // Claim (reference_mesh_claim.cpp).
    void claimVertices(std::vector<DirtyBlock>& dirty, MeshFrameStats& stats, uint32_t frameNumber);
    void claimCube(DirtyBlock& block, uint32_t cube, MeshFrameStats& stats, uint32_t frameNumber);
    // Vertex update (reference_mesh_vertices.cpp).
    void updateVertices(const ReferenceVolume& volume, std::vector<DirtyBlock>& dirty, MeshFrameStats& stats);
    void updateVertex(const TsdfBlocks& tsdf, const BlockMeshState& owner, uint32_t cube, int axis);
    // Triangulation (reference_mesh_triangulate.cpp).
    void triangulate(DirtyBlock& block, MeshFrameStats& stats);
    void releaseReference(uint32_t v);
    // Garbage collection (reference_mesh_gc.cpp).
    void collectGarbage(MeshFrameStats& stats);

    VolumeParams params_;
    float minMeshWeight_;
    MesherOptions options_;
    float refineEpsilon_;
    uint32_t vertexCapacity_, chunkCapacity_;

    std::map<BlockCoord, BlockMeshState> blocks_;
    std::vector<BlockMeshState*> blockByIndex_;  // BlockMeshState::index -> state

    std::vector<gpu::Vertex> vertices_;
    std::vector<uint64_t> vertexOwner_;         // global edge id of the slot holding the vertex
    std::vector<uint32_t> freeVertices_;        // stack, top at the back
    std::vector<std::array<uint32_t, gpu::CHUNK_WORDS>> chunkTriangles_;  // 3 vertex indices per triangle
    std::vector<uint32_t> freeChunks_;          // stack, top at the back
    uint32_t vertexHighWater_ = 0, chunkHighWater_ = 0;

    // Per frame: garbage-collection candidates, chunks to give back, vertices allocated this frame.
    std::vector<uint32_t> gcCandidates_, releasedChunks_, newVertices_;
};

}  // namespace vkmesh::cpu
