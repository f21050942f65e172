#include "gpu/stages/paging_stage.h"

#include "gpu/structure/component.h"

namespace vkmesh::gpu {

PagingStage::PagingStage(const vk::Context& context, const vk::BindingTable& table)
    : context_(context), table_(table), out_(context, table, "page_out_blocks"), outKeys_(context, table, "page_out_keys"), in_(context, table, "page_in_blocks") {
    reserve(64);
}

void PagingStage::reserve(uint32_t blocks) {
    if (blocks <= capacity_) return;
    capacity_ = std::max(blocks, capacity_ + capacity_ / 2);
    const VkDeviceSize bytes = VkDeviceSize(capacity_) * PAGE_RECORD_WORDS * 4;
    records_ = makeStorage(context_, table_, BINDING_PAGE_RECORDS, bytes, "page records");
    // Read back (cached where the device allows) and written by the host for the way in: flushed by being coherent
    // or invalidated before reading (vk::Buffer).
    host_ = vk::Buffer(context_, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::Upload,
                       "page records (host)");
}

void PagingStage::recordOut(VkCommandBuffer cmd, const FramePush& push, uint32_t blocks) const {
    if (!blocks) return;
    out_.dispatch(cmd, &push, blocks);
    vk::memoryBarrier(cmd);
    outKeys_.dispatchItems(cmd, &push, blocks);
    vk::memoryBarrier(cmd);
    VkBufferCopy region{0, 0, VkDeviceSize(blocks) * PAGE_RECORD_WORDS * 4};
    vkCmdCopyBuffer(cmd, records_.handle(), host_.handle(), 1, &region);
    vk::memoryBarrier(cmd);
}

void PagingStage::recordIn(VkCommandBuffer cmd, const FramePush& push, uint32_t blocks, const BlockHash& hash, uint32_t blockCapacity) const {
    if (!blocks) return;
    VkBufferCopy region{0, 0, VkDeviceSize(blocks) * PAGE_RECORD_WORDS * 4};
    vkCmdCopyBuffer(cmd, host_.handle(), records_.handle(), 1, &region);
    vk::memoryBarrier(cmd);
    in_.dispatch(cmd, &push, blocks);
    vk::memoryBarrier(cmd);
    hash.recordInsertListed(cmd, push, blockCapacity);
}

uint32_t* PagingStage::hostRecords() const {
    host_.invalidate();
    return static_cast<uint32_t*>(host_.mapped());
}

}  // namespace vkmesh::gpu
