// Stage: allocate blocks (shaders_comp/allocate/). The other stages are in src/gpu/stages/, one file each.
#pragma once

#include "gpu/layout.h"
#include "vk/buffer.h"
#include "vk/commands.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

// Paper §V.A, first half: pixels walk their truncation bands and claim block keys in the hash
// (allocate_blocks), the touched list is sized (plan_frame), touched keys without memory get a block
// from the free list (assign_blocks), and the free list is shrunk by what was handed out
// (commit_allocation). Four dispatches, because a free list may not be read and shrunk in one.
class AllocateBlocksStage {
public:
    AllocateBlocksStage(const vk::Context& context, const vk::BindingTable& layout);
    void record(VkCommandBuffer cmd, const FramePush& push, const vk::Buffer& counters, uint32_t pixelStride) const;

private:
    vk::ComputePipeline allocate_, plan_, assign_, commit_;
};

}  // namespace vkmesh::gpu
