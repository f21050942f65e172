#include "gpu/stages/export_mesh_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

ExportMeshStage::ExportMeshStage(const vk::Context& context, const vk::BindingTable& table, ParamsBuffer& params)
    : context_(context),
      table_(table),
      plan_(context, table, "plan_export"),
      vertices_pass_(context, table, "export_vertices"),
      triangles_pass_(context, table, "export_triangles"),
      finish_(context, table, "finish_export") {
    vertices_ = makeStorage(context, table, BINDING_EXPORT_VERTICES, VkDeviceSize(vertexCapacity_) * sizeof(Vertex), "export vertices",
                            VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
    indices_ = makeStorage(context, table, BINDING_EXPORT_INDICES, VkDeviceSize(triangleCapacity_) * 12, "export indices",
                           VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
    growRemap(params.values().vertexCapacity);
    params.edit().exportVertexCapacity = vertexCapacity_;
    params.edit().exportTriangleCapacity = triangleCapacity_;
}

void ExportMeshStage::record(VkCommandBuffer cmd, const FramePush& push, CounterBuffer& counters) const {
    // exportVertices, exportTriangles, exportUnreferenced are consecutive.
    counters.recordClear(cmd, offsetof(Counters, exportVertices), 3);
    plan_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    vertices_pass_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, exportDispatch));
    vk::memoryBarrier(cmd);
    triangles_pass_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, exportTriangleDispatch));
    vk::memoryBarrier(cmd);
    finish_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

void ExportMeshStage::ensureCapacity(uint32_t vertices, uint32_t triangles, ParamsBuffer& params) {
    if (vertexCapacity_ < vertices) {
        vertexCapacity_ = vertices + vertices / 4;
        vertices_ = makeStorage(context_, table_, BINDING_EXPORT_VERTICES, VkDeviceSize(vertexCapacity_) * sizeof(Vertex),
                                "export vertices", VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
        params.edit().exportVertexCapacity = vertexCapacity_;
    }
    if (triangleCapacity_ < triangles) {
        triangleCapacity_ = triangles + triangles / 4;
        indices_ = makeStorage(context_, table_, BINDING_EXPORT_INDICES, VkDeviceSize(triangleCapacity_) * 12, "export indices",
                               VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
        params.edit().exportTriangleCapacity = triangleCapacity_;
    }
}

void ExportMeshStage::growRemap(uint32_t vertexCapacity) {
    if (remap_.size() >= VkDeviceSize(vertexCapacity) * 4) return;
    remap_ = makeStorage(context_, table_, BINDING_VERTEX_REMAP, VkDeviceSize(vertexCapacity) * 4, "vertex remap");
}

}  // namespace vkmesh::gpu
