#include "gpu/stages/retype_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

RetypeStage::RetypeStage(const vk::Context& context, const vk::BindingTable& table)
    : refines_((table.features() & VOLUME_FEATURE_REFINE) != 0),
      cacheNeighbors_(context, table, "cache_neighbors"),
      buildMasks_(context, table, "build_tsdf_masks"),
      decideSigns_(context, table, "decide_mesh_signs"),
      collect_(context, table, "collect_retype") {}

void RetypeStage::recordMeshSigns(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters, bool fromTsdf) const {
    cacheNeighbors_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, collectDispatch));
    vk::memoryBarrier(cmd);
    if (refines_ && fromTsdf) {
        buildMasks_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, collectDispatch));
        vk::memoryBarrier(cmd);
    }
    decideSigns_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, collectDispatch));
    vk::memoryBarrier(cmd);
}

void RetypeStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    recordMeshSigns(cmd, push, counters);
    collect_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, collectDispatch));
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
