#include "gpu/stages/baseline_mesh_stage.h"

#include <cstddef>

#include "core/types.h"

namespace vkmesh::gpu {

BaselineMeshStage::BaselineMeshStage(const vk::Context& context, const vk::BindingTable& table, ParamsBuffer& params)
    : context_(context), table_(table), mesh_(context, table, "mesh_baseline") {
    vertices_ = makeStorage(context, table, BINDING_MESH_VERTICES, VkDeviceSize(params.values().meshVertexCapacity) * 16,
                            "baseline mesh vertices");
}

void BaselineMeshStage::record(VkCommandBuffer cmd, const FramePush& push, CounterBuffer& counters) const {
    // meshVertices and meshVerticesDropped are consecutive.
    counters.recordClear(cmd, offsetof(Counters, meshVertices), 2);
    mesh_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, listDispatch));
    vk::memoryBarrier(cmd);
}

void BaselineMeshStage::ensureCapacity(uint32_t vertices, ParamsBuffer& params) {
    if (vertices <= params.values().meshVertexCapacity) return;
    const VkDeviceSize bytes = VkDeviceSize(vertices) * 16;
    if (bytes > context_.maxStorageBufferRange())
        throw Error("the baseline mesh needs " + std::to_string(vertices) + " vertices (" + std::to_string(bytes) +
                    " bytes), more than one storage buffer may hold on this device (" +
                    std::to_string(context_.maxStorageBufferRange()) + " bytes); use a larger voxel size");
    vertices_ = makeStorage(context_, table_, BINDING_MESH_VERTICES, bytes, "baseline mesh vertices");
    params.edit().meshVertexCapacity = vertices;
}

}  // namespace vkmesh::gpu
