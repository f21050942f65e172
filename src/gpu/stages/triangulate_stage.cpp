#include "gpu/stages/triangulate_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

TriangulateStage::TriangulateStage(const vk::Context& context, const vk::BindingTable& table)
    : triangulate_(context, table, "mesh_triangulate"), commit_(context, table, "commit_chunks") {}

void TriangulateStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    triangulate_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, retypeDispatch));
    vk::memoryBarrier(cmd);
    commit_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
