#include "gpu/stages/update_vertices_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

UpdateVerticesStage::UpdateVerticesStage(const vk::Context& context, const vk::BindingTable& table)
    : listDirty_(context, table, "list_dirty_vertices"),
      listNew_(context, table, "list_new_vertices"),
      listHeap_(context, table, "list_heap_vertices"),
      plan_(context, table, "plan_move_vertices"),
      move_(context, table, "move_vertices") {}

void UpdateVerticesStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    listDirty_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, vertexDispatch));
    vk::memoryBarrier(cmd);
    listNew_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, candidateDispatch));
    vk::memoryBarrier(cmd);
    listHeap_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, heapDispatch));
    vk::memoryBarrier(cmd);
    plan_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    move_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, vertexDispatch));
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
