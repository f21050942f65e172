// Stage: the published mesh (shaders_comp/export/). Compacts the shared-vertex mesh into dense, draw-ready
// vertex and index buffers this stage owns (plan_export, export_vertices, export_triangles: each over the
// used part of its heap) and writes the indirect draw command of the result (finish_export).
//   reads  vertex heap, chunks    writes export vertices/indices, vertex remap, Counters::drawIndexed
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "gpu/structure/params_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class ExportMeshStage {
public:
    ExportMeshStage(const vk::Context& context, const vk::BindingTable& table, ParamsBuffer& params);
    // Clears the export counters and compacts.
    void record(VkCommandBuffer cmd, const FramePush& push, CounterBuffer& counters) const;
    // Room for at least this many vertices and triangles (grown by a quarter more than asked, so a slowly
    // growing mesh reallocates rarely; the params follow). The vertex remap follows the vertex heap.
    void ensureCapacity(uint32_t vertices, uint32_t triangles, ParamsBuffer& params);
    void growRemap(uint32_t vertexCapacity);
    bool fits(const Counters& k) const { return k.exportVertices <= vertexCapacity_ && k.exportTriangles <= triangleCapacity_; }
    uint32_t vertexCapacity() const { return vertexCapacity_; }
    const vk::Buffer& vertices() const { return vertices_; }
    const vk::Buffer& indices() const { return indices_; }
    void pools(std::vector<PoolInfo>& out) const { listPools(out, {&vertices_, &indices_, &remap_}); }

private:
    const vk::Context& context_;
    const vk::BindingTable& table_;
    vk::ComputePipeline plan_, vertices_pass_, triangles_pass_, finish_;
    vk::Buffer vertices_, indices_, remap_;
    uint32_t vertexCapacity_ = 1024, triangleCapacity_ = 1024;
};

}  // namespace vkmesh::gpu
