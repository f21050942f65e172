#include "gpu/structure/counter_buffer.h"

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
