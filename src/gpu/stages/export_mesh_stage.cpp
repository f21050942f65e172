#include "gpu/stages/export_mesh_stage.h"

#include <cstddef>
#include <string>

namespace vkmesh::gpu {

ExportMeshStage::ExportMeshStage(const vk::Context& context, const vk::BindingTable& table, ParamsBuffer& params)
    : context_(context),
      table_(table),
      plan_(context, table, "plan_export"),
      vertices_pass_(context, table, "export_vertices"),
      triangles_pass_(context, table, "export_triangles"),
      finish_(context, table, "finish_export") {
    create(sets_[0], 0);
    growRemap(params.values().vertexCapacity);
    select(0, params);
}

void ExportMeshStage::create(Set& set, uint32_t index) {
    // Pool names are --stats keys (gpu_pool_bytes): set 0 keeps the names it always had.
    const std::string suffix = index == 0 ? "" : " (second set)";
    set.vertices = vk::Buffer(context_, VkDeviceSize(set.vertexCapacity) * sizeof(Vertex),
                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, vk::MemoryUse::Device,
                              "export vertices" + suffix);
    set.indices = vk::Buffer(context_, VkDeviceSize(set.triangleCapacity) * 12,
                             VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDEX_BUFFER_BIT, vk::MemoryUse::Device,
                             "export indices" + suffix);
    set.draw = vk::Buffer(context_, sizeof(Counters::drawIndexed), VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, vk::MemoryUse::Device,
                          "export draw command" + suffix);
}

void ExportMeshStage::select(uint32_t set, ParamsBuffer& params) {
    if (!sets_[set].vertices.handle()) create(sets_[set], set);
    selected_ = set;
    table_.bind(BINDING_EXPORT_VERTICES, sets_[set].vertices);
    table_.bind(BINDING_EXPORT_INDICES, sets_[set].indices);
    if (params.values().exportVertexCapacity != sets_[set].vertexCapacity)
        params.edit().exportVertexCapacity = sets_[set].vertexCapacity;
    if (params.values().exportTriangleCapacity != sets_[set].triangleCapacity)
        params.edit().exportTriangleCapacity = sets_[set].triangleCapacity;
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
    const VkBufferCopy region{offsetof(Counters, drawIndexed), 0, sizeof(Counters::drawIndexed)};
    vkCmdCopyBuffer(cmd, counters.buffer().handle(), sets_[selected_].draw.handle(), 1, &region);
    vk::memoryBarrier(cmd);
}

void ExportMeshStage::ensureCapacity(uint32_t vertices, uint32_t triangles, ParamsBuffer& params, bool slack) {
    Set& set = sets_[selected_];
    const std::string suffix = selected_ == 0 ? "" : " (second set)";
    if (set.vertexCapacity < vertices) {
        set.vertexCapacity = vertices + (slack ? vertices / 4 : 0);
        retired_.push_back(std::move(set.vertices));
        set.vertices = vk::Buffer(context_, VkDeviceSize(set.vertexCapacity) * sizeof(Vertex),
                                  VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, vk::MemoryUse::Device,
                                  "export vertices" + suffix);
    }
    if (set.triangleCapacity < triangles) {
        set.triangleCapacity = triangles + (slack ? triangles / 4 : 0);
        retired_.push_back(std::move(set.indices));
        set.indices = vk::Buffer(context_, VkDeviceSize(set.triangleCapacity) * 12,
                                 VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDEX_BUFFER_BIT, vk::MemoryUse::Device,
                                 "export indices" + suffix);
    }
    select(selected_, params);
}

void ExportMeshStage::growRemap(uint32_t vertexCapacity) {
    if (remap_.size() >= VkDeviceSize(vertexCapacity) * 4) return;
    remap_ = makeStorage(context_, table_, BINDING_VERTEX_REMAP, VkDeviceSize(vertexCapacity) * 4, "vertex remap");
}

void ExportMeshStage::pools(std::vector<PoolInfo>& out) const {
    for (const Set& s : sets_) listPools(out, {&s.vertices, &s.indices});
    listPools(out, {&remap_});
}

}  // namespace vkmesh::gpu
