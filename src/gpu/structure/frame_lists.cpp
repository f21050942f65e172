#include "gpu/structure/frame_lists.h"

#include <algorithm>

namespace vkmesh::gpu {
namespace {
VkDeviceSize garbageBytes(const FrameListCapacities& c) { return (VkDeviceSize(c.vertices) + c.chunks) * 4; }
}  // namespace

FrameLists::FrameLists(const vk::Context& context, const vk::BindingTable& table, const FrameListCapacities& c)
    : context_(context), table_(table), capacities_(c) {
    touched_ = makeStorage(context, table, BINDING_TOUCHED, VkDeviceSize(c.touched) * 4, "touched list");
    blockList_ = makeStorage(context, table, BINDING_BLOCK_LIST, VkDeviceSize(c.blocks) * 4, "block list");
    meshStamps_ = makeStorage(context, table, BINDING_MESH_STAMPS, VkDeviceSize(c.blocks) * 4, "mesh stamps");
    dirtyList_ = makeStorage(context, table, BINDING_DIRTY_LIST, VkDeviceSize(c.blocks) * 4, "dirty list");
    retypeMask_ = makeStorage(context, table, BINDING_RETYPE_MASK, VkDeviceSize(c.blocks) * MASK_WORDS * 4, "retype masks");
    retypeList_ = makeStorage(context, table, BINDING_RETYPE_LIST, VkDeviceSize(c.retype) * RETYPE_LIST_WORDS_PER_CUBE * 4, "retype list");
    garbage_ = makeStorage(context, table, BINDING_GARBAGE, garbageBytes(c), "garbage lists");
    moved_ = makeStorage(context, table, BINDING_MOVED_VERTICES, VkDeviceSize(c.vertices) * 4, "moved vertices");
    neighbors_ = makeStorage(context, table, BINDING_BLOCK_NEIGHBORS, VkDeviceSize(c.blocks) * NEIGHBORS_PER_BLOCK * 4, "block neighbours");
    meshSigns_ = makeStorage(context, table, BINDING_MESH_SIGNS, VkDeviceSize(c.blocks) * MESH_SIGN_WORDS * 4, "mesh signs");
    cornerFlips_ = makeStorage(context, table, BINDING_CORNER_FLIPS, VkDeviceSize(c.blocks) * MASK_WORDS * 4, "corner flips");
    vk::CommandRecorder recorder(context);
    VkCommandBuffer cmd = recorder.begin();
    vkCmdFillBuffer(cmd, meshSigns_.handle(), 0, VK_WHOLE_SIZE, 0);   // zero TSDF, zero masks
    vkCmdFillBuffer(cmd, cornerFlips_.handle(), 0, VK_WHOLE_SIZE, 0);
    recordReset(cmd);
    recorder.submitAndWait();
}

void FrameLists::recordReset(VkCommandBuffer cmd) const {
    vkCmdFillBuffer(cmd, meshStamps_.handle(), 0, VK_WHOLE_SIZE, 0);
    vkCmdFillBuffer(cmd, retypeMask_.handle(), 0, VK_WHOLE_SIZE, 0);
    // The mesh signs buffer is kept: its masks describe the TSDF, which a reset mesh keeps, and the meshing signs
    // are re-decided for every corner of the dirty blocks of every mesh pass.
    vk::memoryBarrier(cmd);
}

void FrameLists::grow(const FrameListCapacities& wanted) {
    FrameListCapacities c = capacities_;
    c.blocks = std::max(c.blocks, wanted.blocks);
    c.touched = std::max(c.touched, wanted.touched);
    c.retype = std::max(c.retype, wanted.retype);
    c.vertices = std::max(c.vertices, wanted.vertices);
    c.chunks = std::max(c.chunks, wanted.chunks);
    if (c.blocks > capacities_.blocks) {
        std::vector<vk::Buffer> retired;
        vk::CommandRecorder recorder(context_);
        VkCommandBuffer cmd = recorder.begin();
        growStorage(cmd, context_, table_, BINDING_MESH_STAMPS, meshStamps_, VkDeviceSize(c.blocks) * 4, 0, retired);
        growStorage(cmd, context_, table_, BINDING_RETYPE_MASK, retypeMask_, VkDeviceSize(c.blocks) * MASK_WORDS * 4, 0, retired);
        growStorage(cmd, context_, table_, BINDING_MESH_SIGNS, meshSigns_, VkDeviceSize(c.blocks) * MESH_SIGN_WORDS * 4, 0, retired);
        growStorage(cmd, context_, table_, BINDING_CORNER_FLIPS, cornerFlips_, VkDeviceSize(c.blocks) * MASK_WORDS * 4, 0, retired);
        vk::memoryBarrier(cmd);
        recorder.submitAndWait();
        blockList_ = makeStorage(context_, table_, BINDING_BLOCK_LIST, VkDeviceSize(c.blocks) * 4, "block list");
        dirtyList_ = makeStorage(context_, table_, BINDING_DIRTY_LIST, VkDeviceSize(c.blocks) * 4, "dirty list");
        neighbors_ = makeStorage(context_, table_, BINDING_BLOCK_NEIGHBORS, VkDeviceSize(c.blocks) * NEIGHBORS_PER_BLOCK * 4, "block neighbours");
    }
    if (c.touched > capacities_.touched) touched_ = makeStorage(context_, table_, BINDING_TOUCHED, VkDeviceSize(c.touched) * 4, "touched list");
    if (c.retype > capacities_.retype) retypeList_ = makeStorage(context_, table_, BINDING_RETYPE_LIST, VkDeviceSize(c.retype) * RETYPE_LIST_WORDS_PER_CUBE * 4, "retype list");
    if (garbageBytes(c) > garbageBytes(capacities_)) garbage_ = makeStorage(context_, table_, BINDING_GARBAGE, garbageBytes(c), "garbage lists");
    if (c.vertices > capacities_.vertices)
        moved_ = makeStorage(context_, table_, BINDING_MOVED_VERTICES, VkDeviceSize(c.vertices) * 4, "moved vertices");
    capacities_ = c;
}

void FrameLists::saveRetypeMasks(map::MapData& map, const std::vector<uint32_t>& blocks) const {
    std::vector<uint32_t> masks(blocks.size() * MASK_WORDS);
    downloadRecords(context_, retypeMask_, 4 * MASK_WORDS, blocks, masks.data());
    for (size_t i = 0; i < blocks.size(); ++i) std::copy_n(&masks[i * MASK_WORDS], MASK_WORDS, map.blocks[i].retypeMask.begin());
}

void FrameLists::loadRetypeMasks(const map::MapData& map, const std::vector<uint32_t>& blocks) {
    std::vector<uint32_t> masks(blocks.size() * MASK_WORDS);
    for (size_t i = 0; i < blocks.size(); ++i) std::copy_n(map.blocks[i].retypeMask.begin(), MASK_WORDS, &masks[i * MASK_WORDS]);
    uploadRecords(context_, retypeMask_, 4 * MASK_WORDS, blocks, masks.data());
}

void FrameLists::uploadBlockList(const std::vector<uint32_t>& blocks) { uploadWords(context_, blockList_, blocks); }

}  // namespace vkmesh::gpu
