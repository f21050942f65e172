#include "gpu/stages/block_list_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

BlockListStage::BlockListStage(const vk::Context& context, const vk::BindingTable& table)
    : collect_(context, table, "collect_blocks"), plan_(context, table, "plan_block_list") {}

void BlockListStage::record(VkCommandBuffer cmd, const FramePush& push, CounterBuffer& counters, uint32_t hashCapacity) const {
    counters.recordClear(cmd, offsetof(Counters, liveBlockCount), 1);
    collect_.dispatchItems(cmd, &push, hashCapacity);
    vk::memoryBarrier(cmd);
    plan_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
