#include "gpu/stages/update_vertices_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

UpdateVerticesStage::UpdateVerticesStage(const vk::Context& context, const vk::BindingTable& table)
    : list_(context, table, "list_moved_vertices"),
      move_(context, table, "move_vertices") {}

void UpdateVerticesStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    list_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, ownedDispatch));
    vk::memoryBarrier(cmd);
    move_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, vertexDispatch));
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
