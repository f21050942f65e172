// Stage: fuse (paper §V.A, second half; shaders_comp/fuse/). One workgroup per touched block updates its
// 512 TSDF corners and marks the cubes around corners whose sign or observed state flipped.
//   reads  touched list (allocate), depth image, block coords    writes voxel sdf/weight, retype masks
#pragma once

#include <memory>

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class FuseDepthStage {
public:
    FuseDepthStage(const vk::Context& context, const vk::BindingTable& table);
    // Over Counters::blockDispatch (one workgroup per touched block, sized by allocation as it lists). `deintegrate`:
    // the frame's FramePoseGpu::deintegrate (each way has its own pipeline: shared_layout.h, FUSE_INTEGRATE).
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters, bool deintegrate) const;

private:
    const vk::Context& context_;
    const vk::BindingTable& table_;
    vk::ComputePipeline integrate_;
    mutable std::unique_ptr<vk::ComputePipeline> deintegrate_;   // made when a frame first de-integrates
};

}  // namespace vkmesh::gpu
