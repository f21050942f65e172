// Stage: paging (docs/PAGING.md; shaders_comp/paging/). Moves whole blocks between the pool and records that the
// host keeps (PAGE_RECORD_WORDS each, shared_layout.h), between frames, over the block list the host writes:
// page_out_blocks copies a block's arrays into its record and clears them, page_out_keys frees the block (tombstone,
// free list); page_in_blocks
// writes a record into a free block and re-points its vertices' owners, and rehash_insert puts its key back.
// Owns the records on the GPU and their host-visible copy. GpuVolume (src/gpu/paging.cpp) decides which blocks.
//   reads  block list, TSDF, colour, cube state, edge slots, masks, hash    writes records; the same arrays, owners,
//                                                                         hash keys, free list
#pragma once

#include <cstdint>

#include "gpu/structure/block_hash.h"
#include "gpu/structure/counter_buffer.h"
#include "vk/buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class PagingStage {
public:
    PagingStage(const vk::Context& context, const vk::BindingTable& table);
    // Room for `blocks` records each way (between submissions: it may rebind the records).
    void reserve(uint32_t blocks);
    // page_out_blocks and page_out_keys over blockList[0, liveBlockCount) (at most `blocks`; counters.blocksFreed
    // zeroed by the caller), then the records' copy to the host. After the submission: hostRecords().
    void recordOut(VkCommandBuffer cmd, const FramePush& push, uint32_t blocks) const;
    // The host's records into the GPU's, page_in_blocks over blockList[0, liveBlockCount), then the keys' insertion
    // (rehashLost counts the keys that found no slot). The caller writes hostRecords() first.
    void recordIn(VkCommandBuffer cmd, const FramePush& push, uint32_t blocks, const BlockHash& hash, uint32_t blockCapacity) const;
    uint32_t* hostRecords() const;
    void pools(std::vector<PoolInfo>& out) const { listPools(out, {&records_, &host_}); }

private:
    const vk::Context& context_;
    const vk::BindingTable& table_;
    vk::ComputePipeline out_, outKeys_, in_;
    vk::Buffer records_, host_;
    uint32_t capacity_ = 0;
};

}  // namespace vkmesh::gpu
