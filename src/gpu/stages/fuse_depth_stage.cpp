#include "gpu/stages/fuse_depth_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

FuseDepthStage::FuseDepthStage(const vk::Context& context, const vk::BindingTable& table)
    : context_(context), table_(table), integrate_(context, table, "fuse_depth", FUSE_INTEGRATE) {}

void FuseDepthStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters, bool deintegrate) const {
    if (deintegrate && !deintegrate_) deintegrate_ = std::make_unique<vk::ComputePipeline>(context_, table_, "fuse_depth", FUSE_DEINTEGRATE);
    (deintegrate ? *deintegrate_ : integrate_).dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, blockDispatch));
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
