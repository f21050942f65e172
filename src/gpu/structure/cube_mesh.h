// Component: the cube mesh, the paper's persistent shared-vertex mesh (docs/MESH.md). Per cube of every pool
// block: its MC type, INCOMPLETE flag and triangle chunk (cube state), and the vertex on each of the 3 edges
// it owns (one array per axis, so that each stays within one storage-buffer binding), and per block the
// owned-slot mask (one bit per edge slot that holds a vertex, 192 B: what the vertex update visits). The vertex heap
// (Vertex, owner edge, free stack) and the triangle-chunk heap (5 triangles per chunk, free stack); the tops
// and high-water marks are in Counters. GLSL: shaders_comp/structure/cube_mesh.glsl.
#pragma once

#include <array>

#include "core/map_format.h"
#include "gpu/structure/component.h"
#include "gpu/structure/counter_buffer.h"
#include "gpu/layout.h"

namespace vkmesh::gpu {

// The raw mesh state, for tests of its invariants.
struct MeshStateSnapshot {
    std::vector<Vertex> vertices;                 // the whole heap; refcount DEAD_REFCOUNT when free
    std::vector<uint32_t> vertexOwner;
    std::vector<std::array<uint32_t, 3>> liveTriangles;   // raw heap indices
    std::vector<uint32_t> edgeVertex;             // per cube and axis of every pool block
    std::vector<uint32_t> ownedSlots;             // OWNED_SLOT_WORDS per pool block (cube_mesh.glsl)
    Counters counters{};
};

class CubeMesh {
public:
    CubeMesh(const vk::Context& context, const vk::BindingTable& table, uint32_t blockCapacity, uint32_t vertexCapacity,
             uint32_t chunkCapacity, CounterBuffer& counters);

    uint32_t vertexCapacity() const { return vertexCapacity_; }
    uint32_t chunkCapacity() const { return chunkCapacity_; }
    const vk::Buffer& cubeStates() const { return cubeState_; }
    const vk::Buffer& vertices() const { return vertices_; }
    const vk::Buffer& chunkTriangles() const { return chunkTriangles_; }

    // Throws the mesh away (not the TSDF): every cube empty, every vertex and chunk free.
    void reset(CounterBuffer& counters);
    // Between frames: per-cube arrays (and owned-slot masks) for a larger block pool (new cubes empty).
    void growCubes(uint32_t blockCapacity);
    // Between frames: larger heaps; the mesh is kept (copied on the GPU), the new entries go on the free
    // stacks under the old ones (so every live entry stays below the high-water mark).
    void growHeaps(uint32_t vertexCapacity, uint32_t chunkCapacity, CounterBuffer& counters);

    MeshStateSnapshot download(const Counters& counters) const;
    // How many cubes carry triangles of each MC type (the stored, possibly refined, type).
    std::array<uint64_t, 256> surfaceCubeTypes() const;
    void pools(std::vector<PoolInfo>& out) const {
        listPools(out, {&cubeState_, &edgeVertex_[0], &edgeVertex_[1], &edgeVertex_[2], &ownedSlots_, &vertices_, &vertexOwner_,
                        &vertexFree_, &chunkTriangles_, &chunkFree_});
    }

    // Cube state + 3 edge slots per cube, + the owned-slot mask.
    static constexpr uint64_t kBytesPerBlock = 4ull * 4 * VOXELS_PER_BLOCK + 4ull * OWNED_SLOT_WORDS;

    // Map files (docs/MAPFILE.md): the per-cube arrays (one section each, like BlockStore's), the vertex heap,
    // owners and chunks below their free stacks' untouched runs, and the free stacks. The owned-slot masks are
    // not saved: load rebuilds them from the edge slots.
    static const std::vector<uint32_t> kCornerTags;   // cube state, edge slots x, y, z
    void save(map::MapData& map, const std::vector<uint32_t>& blocks, const Counters& k) const;
    // Into a mesh just created (capacities >= the map's); sets the free-stack tops in the counters.
    void load(const map::MapData& map, const std::vector<uint32_t>& blocks, CounterBuffer& counters);

private:
    const vk::Context& context_;
    const vk::BindingTable& table_;
    uint32_t blockCapacity_, vertexCapacity_, chunkCapacity_;
    vk::Buffer cubeState_;
    std::array<vk::Buffer, 3> edgeVertex_;
    vk::Buffer ownedSlots_;
    vk::Buffer vertices_, vertexOwner_, vertexFree_, chunkTriangles_, chunkFree_;
};

}  // namespace vkmesh::gpu
