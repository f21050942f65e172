// Internal to the CPU reference mesher (src/cpu/reference_mesh*.cpp): the neighbourhood arithmetic its passes
// share, and the dirty block they work on. Installed with the other headers but no API: only those files
// include it.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <stdexcept>

#include "core/marching_cubes.h"
#include "cpu/reference_mesher.h"

namespace vkmesh::cpu::mesh_detail {

// Edge slots per block: one per cube and axis; a global edge id is (block * VOXELS_PER_BLOCK + cube) * 3 + axis.
inline constexpr uint32_t SLOTS_PER_BLOCK = gpu::VOXELS_PER_BLOCK * 3;
// The vertex owner of a vertex on the free stack (no edge).
inline constexpr uint64_t NO_OWNER = ~uint64_t(0);
static_assert(gpu::CHUNK_WORDS == 3 * gpu::TRIANGLES_PER_CHUNK, "a chunk holds 3 vertex indices per triangle");

inline BlockCoord plus(const BlockCoord& c, const std::array<int, 3>& o) { return {c[0] + o[0], c[1] + o[1], c[2] + o[2]}; }

// A point given in the local cube coordinates of a block, each in [0, 8]: which of the block's +x/+y/+z
// neighbourhood it falls into (numbered like cube corners: bit k set = one block further along axis k) and
// its cube index there.
struct Wrapped {
    int neighbour;
    uint32_t cube;
};
inline Wrapped wrap(const std::array<int, 3>& g) {
    const int side = int(gpu::BLOCK_SIDE);
    return {(g[0] / side) | ((g[1] / side) << 1) | ((g[2] / side) << 2),
            localIndex(g[0] % side, g[1] % side, g[2] % side)};
}

// A block and its 7 neighbours in +x, +y, +z, indexed like cube corners: everything a cube of the block reads.
inline std::array<const ReferenceBlock*, 8> tsdfNeighbourhood(const ReferenceVolume& volume, const BlockCoord& coord) {
    std::array<const ReferenceBlock*, 8> out{};
    for (int i = 0; i < 8; ++i) {
        auto it = volume.blocks().find(plus(coord, cornerOffset(i)));
        out[i] = it == volume.blocks().end() ? nullptr : &it->second;
    }
    return out;
}

// The 8 TSDF corners of one cube.
struct CubeCorners {
    float d[8] = {};
    uint32_t color[8] = {};  // colour words (0 = none)
    bool exists[8] = {};   // the corner's block is allocated
    bool observed = true;  // all 8 exist and have weight >= minMeshWeight
};

inline CubeCorners readCorners(const std::array<const ReferenceBlock*, 8>& n, uint32_t cube, float minMeshWeight) {
    CubeCorners out;
    const auto local = localCoords(cube);
    for (int c = 0; c < 8; ++c) {
        const auto o = cornerOffset(c);
        const Wrapped w = wrap({local[0] + o[0], local[1] + o[1], local[2] + o[2]});
        const ReferenceBlock* block = n[w.neighbour];
        if (!block) {
            out.observed = false;
            continue;
        }
        out.exists[c] = true;
        out.d[c] = block->sdf[w.cube];
        out.color[c] = block->color[w.cube];
        if (block->weight[w.cube] < minMeshWeight) out.observed = false;
    }
    return out;
}

inline uint64_t globalEdgeId(const BlockMeshState& state, uint32_t cube, int axis) {
    return uint64_t(state.index) * SLOTS_PER_BLOCK + cube * 3 + uint32_t(axis);
}

// The lock-free claim passes (docs/REFINEMENT.md): pass k claims the cubes whose global position parity
// p = (x&1) | (y&1) << 1 | (z&1) << 2 is one of kParityPasses[k], i.e. (x&1, y&1, z&1) in {000, 111},
// {001, 110}, {010, 101}, {100, 011}: two parity vectors that differ on all three axes.
constexpr int kParityPasses[4][2] = {{0, 7}, {4, 3}, {2, 5}, {1, 6}};

inline int globalParity(const BlockCoord& block, uint32_t cube) {
    const auto l = localCoords(cube);
    const int side = int(gpu::BLOCK_SIDE);
    return ((block[0] * side + l[0]) & 1) | (((block[1] * side + l[1]) & 1) << 1) | (((block[2] * side + l[2]) & 1) << 2);
}

}  // namespace vkmesh::cpu::mesh_detail

namespace vkmesh::cpu {

// A block of D with everything its cubes read: the TSDF and the mesh state of it and its +x/+y/+z
// neighbours, and the new type of each of its cubes.
struct ReferenceMesher::DirtyBlock {
    BlockCoord coord{};
    BlockMeshState* state = nullptr;
    TsdfBlocks tsdf{};
    BlockMeshState* mesh[8] = {};
    CubeMask retype;                              // the cubes claim and triangulate visit
    std::array<uint8_t, gpu::VOXELS_PER_BLOCK> newType{};  // for those cubes: the (refined) type to build

    DirtyBlock(const ReferenceVolume& volume, std::map<BlockCoord, BlockMeshState>& states, const BlockCoord& c)
        : coord(c), state(&states.at(c)), tsdf(mesh_detail::tsdfNeighbourhood(volume, c)) {
        for (int i = 0; i < 8; ++i) {
            auto it = states.find(mesh_detail::plus(c, cornerOffset(i)));
            mesh[i] = it == states.end() ? nullptr : &it->second;
        }
    }

    // The slot of edge e of cube `cube`: it lives in the owner cube (this block or a +x/+y/+z neighbour).
    // Only called for cubes whose 8 corners exist, so the owner's block exists.
    struct Slot {
        BlockMeshState* state;
        uint32_t cube;
        int axis;
        uint32_t& vertex() const { return state->edgeVertex[cube * 3 + uint32_t(axis)]; }
    };
    Slot edgeSlot(uint32_t cube, int e) const {
        const auto local = localCoords(cube);
        const auto o = edgeOwnerOffset(e);
        const mesh_detail::Wrapped w = mesh_detail::wrap({local[0] + o[0], local[1] + o[1], local[2] + o[2]});
        if (!mesh[w.neighbour]) throw std::logic_error("ReferenceMesher: the owner block of an edge has no mesh state");
        return {mesh[w.neighbour], w.cube, edgeAxis(e)};
    }
};

}  // namespace vkmesh::cpu
