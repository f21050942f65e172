// Stage: the published mesh (shaders_comp/export/). Compacts the shared-vertex mesh into dense, draw-ready
// vertex and index buffers this stage owns (plan_export, export_vertices, export_triangles: each over the
// used part of its heap) and writes the indirect draw command of the result (finish_export), copied into
// the set's own draw buffer so that a renderer can draw it while the counters serve the next frame.
//   reads  vertex heap, chunks    writes export vertices/indices, vertex remap, Counters::drawIndexed, draw
// Two sets of output buffers: blocking frames always use set 0; asynchronous frames (GpuVolume::submitFrame)
// alternate, so that an application draws frame N from one set while frame N+1 is written into the other.
#pragma once

#include <array>
#include <vector>

#include "gpu/structure/counter_buffer.h"
#include "gpu/structure/params_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class ExportMeshStage {
public:
    ExportMeshStage(const vk::Context& context, const vk::BindingTable& table, ParamsBuffer& params);
    // Clears the export counters, compacts into the selected set, and copies the draw command into it.
    void record(VkCommandBuffer cmd, const FramePush& push, CounterBuffer& counters) const;
    // Makes `set` (0 or 1) the one the next record() writes: binds its buffers (never while a recorded command
    // buffer that uses the stage has not finished) and sets the capacities in the params. Creates set 1 on
    // first use.
    void select(uint32_t set, ParamsBuffer& params);
    uint32_t selected() const { return selected_; }
    // Room in the selected set for at least this many vertices and triangles (with `slack`, a quarter more than
    // asked, so a slowly growing mesh reallocates rarely; the params follow). The replaced buffers are kept
    // until releaseRetired(): an application may still be drawing from them.
    void ensureCapacity(uint32_t vertices, uint32_t triangles, ParamsBuffer& params, bool slack = true);
    // Destroys the buffers replaced by ensureCapacity(): call once a submission that began after everything
    // the application submitted before the replacement has finished (vkmesh's frames start with that barrier).
    void releaseRetired() { retired_.clear(); }
    void growRemap(uint32_t vertexCapacity);
    bool fits(const Counters& k) const {
        return k.exportVertices <= sets_[selected_].vertexCapacity && k.exportTriangles <= sets_[selected_].triangleCapacity;
    }
    uint32_t vertexCapacity() const { return sets_[selected_].vertexCapacity; }
    const vk::Buffer& vertices() const { return sets_[selected_].vertices; }
    const vk::Buffer& indices() const { return sets_[selected_].indices; }
    const vk::Buffer& drawCommand() const { return sets_[selected_].draw; }
    void pools(std::vector<PoolInfo>& out) const;

private:
    struct Set {
        vk::Buffer vertices, indices, draw;
        uint32_t vertexCapacity = 1024, triangleCapacity = 1024;
    };
    void create(Set& set, uint32_t index);

    const vk::Context& context_;
    const vk::BindingTable& table_;
    vk::ComputePipeline plan_, vertices_pass_, triangles_pass_, finish_;
    std::array<Set, 2> sets_;
    uint32_t selected_ = 0;
    vk::Buffer remap_;
    std::vector<vk::Buffer> retired_;
};

}  // namespace vkmesh::gpu
