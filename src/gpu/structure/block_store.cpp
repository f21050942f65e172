#include "gpu/structure/block_store.h"

#include "core/tsdf_corner.h"

namespace vkmesh::gpu {

const std::vector<BlockStore::CornerArray> BlockStore::kCornerArrays = {
    {map::tag("sdf_"), &BlockStore::sdf_},
    {map::tag("wght"), &BlockStore::weight_},
    {map::tag("colr"), &BlockStore::color_, true},
};

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

std::vector<BlockSnapshot> BlockStore::download(const std::vector<uint32_t>& blocks, float metresPerStep) const {
    std::vector<int32_t> sdf(size_t(capacity_) * VOXELS_PER_BLOCK);
    std::vector<float> weight(sdf.size());
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
        snap.sdfSum.assign(sdf.begin() + size_t(b) * VOXELS_PER_BLOCK, sdf.begin() + size_t(b + 1) * VOXELS_PER_BLOCK);
        snap.weight.assign(weight.begin() + size_t(b) * VOXELS_PER_BLOCK, weight.begin() + size_t(b + 1) * VOXELS_PER_BLOCK);
        snap.sdf.resize(VOXELS_PER_BLOCK);
        for (uint32_t v = 0; v < VOXELS_PER_BLOCK; ++v) snap.sdf[v] = tsdfMean(snap.sdfSum[v], snap.weight[v], metresPerStep);
        if (withColor_)
            snap.color.assign(color.begin() + size_t(b) * VOXELS_PER_BLOCK, color.begin() + size_t(b + 1) * VOXELS_PER_BLOCK);
        out.push_back(std::move(snap));
    }
    return out;
}

void BlockStore::save(map::MapData& map, const std::vector<uint32_t>& blocks, uint32_t freeTop) const {
    for (const CornerArray& a : kCornerArrays) {
        if (a.colorOnly && !withColor_) continue;
        map::CornerArray out{a.tag, std::vector<uint32_t>(blocks.size() * VOXELS_PER_BLOCK)};
        downloadRecords(context_, this->*a.buffer, 4 * VOXELS_PER_BLOCK, blocks, out.words.data());
        map.cornerArrays.push_back(std::move(out));
    }
    map.blockFree = map::FreeStack::fromEntries(downloadWords(context_, freeList_, freeTop), capacity_);
}

void BlockStore::load(const map::MapData& map, const std::vector<uint32_t>& blocks, CounterBuffer& counters) {
    for (const CornerArray& a : kCornerArrays)   // present: checked by GpuVolume::load before anything was created
        if (!a.colorOnly || withColor_) uploadRecords(context_, this->*a.buffer, 4 * VOXELS_PER_BLOCK, blocks, map.corners(a.tag)->words.data());
    std::vector<int32_t> coords(map.blocks.size() * 4);
    for (size_t i = 0; i < map.blocks.size(); ++i) {
        const map::Block& b = map.blocks[i];
        coords[4 * i] = b.x, coords[4 * i + 1] = b.y, coords[4 * i + 2] = b.z, coords[4 * i + 3] = int32_t(b.hashStamp);
    }
    uploadRecords(context_, coords_, 16, blocks, coords.data());
    const std::vector<uint32_t> stack = map.blockFree.entries(capacity_);
    uploadWords(context_, freeList_, stack);
    counters.update([&](Counters& k) { k.freeTop = uint32_t(stack.size()); });
}

}  // namespace vkmesh::gpu
