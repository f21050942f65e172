#include "gpu/structure/block_store.h"

namespace vkmesh::gpu {

BlockStore::BlockStore(const vk::Context& context, const vk::BindingTable& table, uint32_t capacity, CounterBuffer& counters,
                       bool withColor)
    : context_(context), table_(table), capacity_(capacity), withColor_(withColor) {
    const VkDeviceSize voxels = VkDeviceSize(capacity) * VOXELS_PER_BLOCK;
    coords_ = makeStorage(context, table, BINDING_BLOCK_COORDS, VkDeviceSize(capacity) * 16, "block coords");
    sdf_ = makeStorage(context, table, BINDING_VOXEL_SDF, voxels * 4, "voxel sdf");
    weight_ = makeStorage(context, table, BINDING_VOXEL_WEIGHT, voxels * 4, "voxel weight");
    color_ = makeStorage(context, table, BINDING_VOXEL_COLOR, withColor ? voxels * 4 : 16, withColor ? "voxel colour" : "voxel colour (off)");
    freeList_ = makeStorage(context, table, BINDING_FREE_LIST, VkDeviceSize(capacity) * 4, "free list");
    // Fresh memory is zero (vkCmdFillBuffer below), which is the state of every free block.
    vk::CommandRecorder recorder(context);
    VkCommandBuffer cmd = recorder.begin();
    vkCmdFillBuffer(cmd, sdf_.handle(), 0, VK_WHOLE_SIZE, 0);
    vkCmdFillBuffer(cmd, weight_.handle(), 0, VK_WHOLE_SIZE, 0);
    vkCmdFillBuffer(cmd, color_.handle(), 0, VK_WHOLE_SIZE, 0);   // no colour yet
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
    fillFreeStack(context, freeList_, capacity);
    counters.update([&](Counters& k) { k.freeTop = capacity; });
}

void BlockStore::grow(uint32_t newCapacity, CounterBuffer& counters) {
    if (newCapacity <= capacity_) return;
    const Counters k = counters.read();
    std::vector<vk::Buffer> retired;
    vk::CommandRecorder recorder(context_);
    VkCommandBuffer cmd = recorder.begin();
    const VkDeviceSize voxels = VkDeviceSize(newCapacity) * VOXELS_PER_BLOCK;
    growStorage(cmd, context_, table_, BINDING_BLOCK_COORDS, coords_, VkDeviceSize(newCapacity) * 16, 0, retired);
    growStorage(cmd, context_, table_, BINDING_VOXEL_SDF, sdf_, voxels * 4, 0, retired);
    growStorage(cmd, context_, table_, BINDING_VOXEL_WEIGHT, weight_, voxels * 4, 0, retired);
    if (withColor_) growStorage(cmd, context_, table_, BINDING_VOXEL_COLOR, color_, voxels * 4, 0, retired);
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
    retired.clear();
    growFreeStack(context_, table_, BINDING_FREE_LIST, freeList_, k.freeTop, capacity_, newCapacity);
    const uint32_t added = newCapacity - capacity_;
    counters.update([&](Counters& c) { c.freeTop += added; });
    capacity_ = newCapacity;
}

std::vector<BlockSnapshot> BlockStore::download(const std::vector<uint32_t>& blocks) const {
    std::vector<float> sdf(size_t(capacity_) * VOXELS_PER_BLOCK), weight(sdf.size());
    vk::downloadFromBuffer(context_, sdf_, sdf.data(), sdf.size() * 4);
    vk::downloadFromBuffer(context_, weight_, weight.data(), weight.size() * 4);
    std::vector<uint32_t> color(withColor_ ? sdf.size() : 0);
    if (withColor_) vk::downloadFromBuffer(context_, color_, color.data(), color.size() * 4);
    std::vector<int32_t> coords(size_t(capacity_) * 4);
    vk::downloadFromBuffer(context_, coords_, coords.data(), coords.size() * 4);
    std::vector<BlockSnapshot> out;
    out.reserve(blocks.size());
    for (uint32_t b : blocks) {
        BlockSnapshot snap;
        snap.coord = Eigen::Vector3i(coords[4 * size_t(b)], coords[4 * size_t(b) + 1], coords[4 * size_t(b) + 2]);
        snap.index = b;
        snap.sdf.assign(sdf.begin() + size_t(b) * VOXELS_PER_BLOCK, sdf.begin() + size_t(b + 1) * VOXELS_PER_BLOCK);
        snap.weight.assign(weight.begin() + size_t(b) * VOXELS_PER_BLOCK, weight.begin() + size_t(b + 1) * VOXELS_PER_BLOCK);
        if (withColor_)
            snap.color.assign(color.begin() + size_t(b) * VOXELS_PER_BLOCK, color.begin() + size_t(b + 1) * VOXELS_PER_BLOCK);
        out.push_back(std::move(snap));
    }
    return out;
}

}  // namespace vkmesh::gpu
