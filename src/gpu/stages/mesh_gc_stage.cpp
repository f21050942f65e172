#include "gpu/stages/mesh_gc_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

MeshGcStage::MeshGcStage(const vk::Context& context, const vk::BindingTable& table)
    : vertices_(context, table, "free_vertices"), chunks_(context, table, "free_chunks"), commit_(context, table, "commit_free") {}

void MeshGcStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    vertices_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, candidateDispatch));
    vk::memoryBarrier(cmd);
    chunks_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, releaseDispatch));
    vk::memoryBarrier(cmd);
    commit_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
