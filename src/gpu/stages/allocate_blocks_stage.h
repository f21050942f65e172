// Stage: block allocation (shaders_comp/allocate/), the first half of paper §V.A.
#pragma once

#include <memory>

#include "gpu/layout.h"
#include "vk/buffer.h"
#include "vk/context.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

// Tiles of pixels claim the blocks of the slab around the plane that fits their depths (allocate_tiles, where
// VolumeParams::allocationTiles), the other pixels walk their truncation bands (allocate_blocks); both claim
// block keys in the hash through structure/block_hash.glsl's hashInsertKey (either atomic path) and list the blocks
// touched, raising the dispatches over the touched list as they go; touched keys without memory get a block from the
// free list (assign_blocks), and the free list is shrunk by what was handed out (commit_allocation). Four dispatches
// (three per pixel), because a free list may not be read and shrunk in one. Reads the depth image; writes the hash,
// the touched list (hash slots, then block indices), the block coordinates of new blocks and
// Counters::touchedListDispatch / blockDispatch (the fuse stage's).
class AllocateBlocksStage {
public:
    AllocateBlocksStage(const vk::Context& context, const vk::BindingTable& layout);
    // `deintegrate`: the frame's FramePoseGpu::deintegrate (each way has its own allocate_blocks pipeline:
    // shared_layout.h, FUSE_INTEGRATE).
    void record(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters, uint32_t pixelStride, bool byTiles,
                bool deintegrate) const;

private:
    const vk::Context& context_;
    const vk::BindingTable& layout_;
    vk::ComputePipeline allocate_, allocateTiles_, assign_, commit_;
    mutable std::unique_ptr<vk::ComputePipeline> findForDeintegration_, findTilesForDeintegration_;   // made when a frame first de-integrates
};

}  // namespace vkmesh::gpu
