#include "gpu/structure/counter_buffer.h"

#include <cstddef>
#include <cstring>

namespace vkmesh::gpu {

CounterBuffer::CounterBuffer(const vk::Context& context, const vk::BindingTable& table)
    : context_(context),
      buffer_(makeStorage(context, table, BINDING_COUNTERS, sizeof(Counters), "counters", VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT)),
      readback_(context, sizeof(Counters), VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::Readback, "counters readback") {
    Counters zero{};
    vk::uploadToBuffer(context, buffer_, &zero, sizeof(zero));
}

void CounterBuffer::recordClearFrame(VkCommandBuffer cmd) const {
    vkCmdFillBuffer(cmd, buffer_.handle(), COUNTERS_PER_FRAME_OFFSET, COUNTERS_PER_FRAME_SIZE, 0);
    // The dispatches that the passes raise as they list start empty (x 0, y and z 1): over the touched list
    // (allocation: block_visits.glsl), over the dirty blocks' mask words (dirty marking: listDirtyBlock in
    // frame_lists.glsl) and over the retype list (collect_retype). A one-invocation pass after each list sized them
    // before; each cost a dispatch and a barrier. decide_mesh_signs' count of decided corners starts at 0 too.
    static_assert(offsetof(Counters, blockDispatch) == offsetof(Counters, touchedListDispatch) + 4 * sizeof(uint32_t) &&
                  offsetof(Counters, retypeDispatch) == offsetof(Counters, collectDispatch) + 4 * sizeof(uint32_t));
    const uint32_t emptyDispatches[8] = {0, 1, 1, 0, 0, 1, 1, 0}, zero = 0;
    vkCmdUpdateBuffer(cmd, buffer_.handle(), offsetof(Counters, touchedListDispatch), sizeof(emptyDispatches), emptyDispatches);
    vkCmdUpdateBuffer(cmd, buffer_.handle(), offsetof(Counters, collectDispatch), sizeof(emptyDispatches), emptyDispatches);
    vkCmdUpdateBuffer(cmd, buffer_.handle(), offsetof(Counters, signCornerCount), sizeof(zero), &zero);
    vk::memoryBarrier(cmd);
}

void CounterBuffer::recordClear(VkCommandBuffer cmd, size_t offset, uint32_t count) const {
    vkCmdFillBuffer(cmd, buffer_.handle(), offset, VkDeviceSize(count) * sizeof(uint32_t), 0);
    vk::memoryBarrier(cmd);
}

void CounterBuffer::recordReadback(VkCommandBuffer cmd) {
    uploadedIsCurrent_ = false;
    VkBufferCopy region{0, 0, sizeof(Counters)};
    vkCmdCopyBuffer(cmd, buffer_.handle(), readback_.handle(), 1, &region);
    vk::memoryBarrier(cmd);
}

Counters CounterBuffer::read() const {
    if (uploadedIsCurrent_) return uploaded_;
    Counters k{};
    readback_.invalidate();
    std::memcpy(&k, readback_.mapped(), sizeof(k));
    return k;
}

void CounterBuffer::update(const std::function<void(Counters&)>& change) {
    Counters k{};
    vk::downloadFromBuffer(context_, buffer_, &k, sizeof(k));
    change(k);
    replace(k);
}

void CounterBuffer::replace(const Counters& counters) {
    vk::uploadToBuffer(context_, buffer_, &counters, sizeof(counters));
    uploaded_ = counters;
    uploadedIsCurrent_ = true;
}

}  // namespace vkmesh::gpu
