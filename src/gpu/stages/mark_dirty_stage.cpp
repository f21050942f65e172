#include "gpu/stages/mark_dirty_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

MarkDirtyStage::MarkDirtyStage(const vk::Context& context, const vk::BindingTable& table)
    : touched_(context, table, "mark_dirty"), all_(context, table, "mark_all_dirty"), pending_(context, table, "mark_pending_dirty") {}

void MarkDirtyStage::recordTouched(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    touched_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, touchedListDispatch));
    vk::memoryBarrier(cmd);
}

void MarkDirtyStage::recordAll(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const {
    all_.dispatchItems(cmd, &push, blockCapacity);
    vk::memoryBarrier(cmd);
}

void MarkDirtyStage::recordPending(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const {
    pending_.dispatchItems(cmd, &push, blockCapacity);
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
