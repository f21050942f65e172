#include "gpu/stages/update_vertices_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

UpdateVerticesStage::UpdateVerticesStage(const vk::Context& context, const vk::BindingTable& table)
    : dirty_(context, table, "update_vertices"), fresh_(context, table, "update_new_vertices"), heap_(context, table, "update_heap_vertices") {}

void UpdateVerticesStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    dirty_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, vertexDispatch));
    vk::memoryBarrier(cmd);
    fresh_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, candidateDispatch));
    vk::memoryBarrier(cmd);
    heap_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, heapDispatch));
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
