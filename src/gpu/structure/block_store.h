// Component: the block store. A pool of blockCapacity blocks, each the TSDF at its 512 cube corners
// (distance and weight, block-major, x fastest), the block's coordinate and hash slot, and the free list of
// unused blocks (a stack popped from its top; its top is Counters::freeTop); with colour fusion, a colour
// word per corner (structure/voxel_color.glsl). A block on the free list holds
// weight 0 at every corner, so a block handed out needs no clearing. GLSL: shaders_comp/structure/block_store.glsl.
#pragma once

#include <Eigen/Core>

#include "core/map_format.h"
#include "gpu/structure/component.h"
#include "gpu/structure/counter_buffer.h"
#include "gpu/layout.h"

namespace vkmesh::gpu {

// The TSDF of one block as downloaded (tests, snapshots).
struct BlockSnapshot {
    Eigen::Vector3i coord;
    uint32_t index = 0;               // its block in the pool
    std::vector<int32_t> sdfSum;      // VOXELS_PER_BLOCK each, x fastest: the corners as stored (step sums) ...
    std::vector<float> weight;        //  ... and observation counts
    std::vector<float> sdf;           // their distances in metres (tsdfMean, core/tsdf_corner.h)
    std::vector<uint32_t> color;      // VOXELS_PER_BLOCK colour words (voxel_color.glsl), empty without colour
};

class BlockStore {
public:
    // Every block free; counters.freeTop set to the capacity. withColor: keep a colour word per corner (else
    // the colour binding gets a small placeholder that no shader touches).
    BlockStore(const vk::Context& context, const vk::BindingTable& table, uint32_t capacity, CounterBuffer& counters,
               bool withColor);

    uint32_t capacity() const { return capacity_; }
    const vk::Buffer& coords() const { return coords_; }   // ivec4 per block: coordinate, w = hash slot
    // Grows the pool between frames; blocks keep their index and TSDF, the new ones go on the free list
    // (under the old entries, so freed blocks are reused first).
    void grow(uint32_t newCapacity, CounterBuffer& counters);
    // The TSDF of the given blocks with their coordinates (index = block index); metresPerStep converts the
    // sums to distances (tsdfFixedPoint of the volume's truncation).
    std::vector<BlockSnapshot> download(const std::vector<uint32_t>& blocks, float metresPerStep) const;
    void pools(std::vector<PoolInfo>& out) const { listPools(out, {&coords_, &sdf_, &weight_, &color_, &freeList_}); }
    bool hasColor() const { return withColor_; }
    const vk::Buffer& freeList() const { return freeList_; }   // paging pops it on the host (src/gpu/paging.cpp)

    static constexpr uint64_t kBytesPerBlock = 16 + 2ull * 4 * VOXELS_PER_BLOCK + 4;
    static constexpr uint64_t kColorBytesPerBlock = 4ull * VOXELS_PER_BLOCK;

    // Map files (docs/MAPFILE.md). Each per-corner array is one section, listed once in kCornerArrays
    // (block_store.cpp): adding an array is one line there. The colour array is written and read only when
    // the store keeps colour (the map's FEATURE_COLOR).
    struct CornerArray {
        uint32_t tag;
        vk::Buffer BlockStore::*buffer;
        bool colorOnly = false;
    };
    static const std::vector<CornerArray> kCornerArrays;
    // The live blocks' corner arrays (in `blocks` order) and the free list. Coordinates come from the hash.
    void save(map::MapData& map, const std::vector<uint32_t>& blocks, uint32_t freeTop) const;
    // Into a store just created (capacity >= the map's): corner arrays, free list (counters.freeTop), and each
    // live block's coordinate with w = its hash stamp, which the hash's re-insertion reads (BlockHash::restore).
    void load(const map::MapData& map, const std::vector<uint32_t>& blocks, CounterBuffer& counters);

private:
    const vk::Context& context_;
    const vk::BindingTable& table_;
    uint32_t capacity_;
    bool withColor_;
    vk::Buffer coords_, sdf_, weight_, color_, freeList_;
};

}  // namespace vkmesh::gpu
