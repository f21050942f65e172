#include "gpu/stages/recycle_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

RecycleStage::RecycleStage(const vk::Context& context, const vk::BindingTable& table)
    : retire_(context, table, "recycle_retire"), free_(context, table, "recycle_free"), freeEmptied_(context, table, "free_emptied"),
      commit_(context, table, "commit_recycle") {}

void RecycleStage::recordRetire(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    retire_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, listDispatch));
    vk::memoryBarrier(cmd);
}

void RecycleStage::recordFree(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters, bool overTouched) const {
    if (overTouched) freeEmptied_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, blockDispatch));
    else free_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, listDispatch));
    vk::memoryBarrier(cmd);
    commit_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
