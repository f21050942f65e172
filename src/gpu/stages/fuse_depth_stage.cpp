#include "gpu/stages/fuse_depth_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

FuseDepthStage::FuseDepthStage(const vk::Context& context, const vk::BindingTable& table) : fuse_(context, table, "fuse_depth") {}

void FuseDepthStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    fuse_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, blockDispatch));
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
