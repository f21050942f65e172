// Component: the block hash (shaders_comp/structure/block_hash.glsl, docs/HASH.md). Block coordinate ->
// hash slot -> block index, open addressing over a power-of-two table. Owns its three buffers (keys,
// values = block index per slot, stamps = last frame that touched the slot), their clearing, their
// download, and the passes that rebuild the table on the GPU: dropping tombstones (rebuild) or moving
// every live block into a larger table (grow).
//
// Two key layouts, chosen from the device's features (vk::Context::int64Atomics()): one uint64 per slot,
// claimed with one 64-bit atomicCompSwap; or HASH32_KEY_WORDS uint32 per slot, claimed word by word with
// 32-bit atomics (devices without shaderInt64 or shaderBufferInt64Atomics). Both give the same table
// contents up to slot order; host code never looks at the key words except through downloadEntries().
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "gpu/layout.h"
#include "gpu/structure/component.h"
#include "vk/buffer.h"
#include "vk/commands.h"
#include "vk/context.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class BlockHash {
public:
    // Creates an empty table of `capacity` slots (a power of two) and binds its buffers in `layout`.
    BlockHash(const vk::Context& context, const vk::BindingTable& layout, uint32_t capacity);

    uint32_t capacity() const { return capacity_; }
    const vk::Buffer& values() const { return values_; }   // block per slot (NO_BLOCK: none)
    bool int64Keys() const { return int64Keys_; }
    // Bytes of the keys buffer per slot on a device with (8) or without (12) 64-bit atomics.
    static uint32_t keyBytesPerSlot(bool int64Atomics) { return int64Atomics ? 8u : 4u * HASH32_KEY_WORDS; }

    // Empties every slot: keys EMPTY, values NO_BLOCK, stamps 0. Follow with a memory barrier.
    void recordClear(VkCommandBuffer cmd) const;

    // Rebuilds the table in place (tombstones and keys without a block dropped), stamps kept. Needs the
    // live block list (blockList, liveBlockCount) of the current table, collected in the same command
    // buffer before. Sets counters hashEntries, hashTombstones (0), hashRebuilt (1) and rehashLost.
    void recordRebuild(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const;

    // Rehashes into a new, empty table of `newCapacity` slots (a power of two, larger than capacity())
    // between frames: every live block is re-inserted on the GPU, its coordinate's w points at its new
    // slot, stamps are kept, VolumeParamsGpu::hashCapacity in `params` becomes newCapacity and the counters
    // hashEntries / hashTombstones are those of the new table. `recordLiveBlocks` records the pass that
    // lists every live block of the current table (blockList, liveBlockCount); it runs in its own
    // submission, before the buffers are replaced (the descriptor set is rebound between the two halves).
    // Returns the number of live blocks that found no slot within HASH_MAX_PROBES (rehashLost, 0 unless
    // the new table is far too small); those blocks' memory is lost.
    uint32_t grow(uint32_t newCapacity, const vk::Buffer& params, const vk::Buffer& counters, const FramePush& push,
                  uint32_t blockCapacity, const std::function<void(VkCommandBuffer)>& recordLiveBlocks);

    // The three parts of grow(), for a caller with its own submissions (GpuVolume: parameters uploaded at the
    // start of each): record the stamps' save over the current table (after the live block list), submit;
    // replace() the buffers by empty ones of newCapacity slots (bound, cleared; the GPU must be idle) and set
    // hashCapacity in the parameters; record the re-insertion (hashEntries, hashTombstones, rehashLost), submit.
    void recordSaveStamps(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const;
    void replace(uint32_t newCapacity);
    void recordReinsert(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const;

    // Paging (src/gpu/stages/paging_stage.h), between frames: inserts the keys of the listed blocks (blockList[0,
    // liveBlockCount), their coordinates with w = the stamp to restore) into the table as it is, the first half of
    // recordReinsert. rehashLost counts those that found no slot; the caller updates hashEntries.
    void recordInsertListed(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const;

    // What one slot holds, as downloaded (tests, snapshots).
    struct Entry {
        uint32_t slot = 0;
        int32_t x = 0, y = 0, z = 0;   // block coordinate
        uint32_t block = NO_BLOCK;     // block index, NO_BLOCK while the key holds no block
        uint32_t stamp = 0;            // last frame that touched the slot
    };
    // Every slot holding a key (tombstones and empty slots left out), in slot order.
    std::vector<Entry> downloadEntries() const;
    // Raw counts of the table as downloaded: slots holding a key, tombstones.
    struct Occupancy {
        uint32_t keys = 0, tombstones = 0;
    };
    Occupancy downloadOccupancy() const;

    // The buffers it owns, for GpuVolume::pools().
    void pools(std::vector<PoolInfo>& out) const { listPools(out, {&keys_, &values_, &stamps_}); }

private:
    void allocate(uint32_t capacity);   // new buffers of `capacity` slots, bound (not cleared)

    const vk::Context& context_;
    const vk::BindingTable& layout_;
    bool int64Keys_;
    uint32_t capacity_ = 0;
    vk::Buffer keys_, values_, stamps_;
    vk::ComputePipeline save_, insert_, commit_;   // shaders_comp/hash/
};

}  // namespace vkmesh::gpu
