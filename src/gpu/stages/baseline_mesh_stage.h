// Stage: the Chisel-style baseline mesh (shaders_comp/baseline_mesh/): marching cubes in every cube of every
// live block, 3 vertices of its own per triangle, into a triangle-soup buffer this stage owns. Needs the
// live-block list (BlockListStage) recorded before it.
//   reads  block list, TSDF, hash, MC tables    writes mesh vertices, Counters::meshVertices(/Dropped)
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "gpu/structure/params_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class BaselineMeshStage {
public:
    BaselineMeshStage(const vk::Context& context, const vk::BindingTable& table, ParamsBuffer& params);
    void record(VkCommandBuffer cmd, const FramePush& push, CounterBuffer& counters) const;
    // Room for `vertices` soup vertices (the buffer is replaced; params.meshVertexCapacity follows).
    void ensureCapacity(uint32_t vertices, ParamsBuffer& params);
    const vk::Buffer& vertices() const { return vertices_; }
    void pools(std::vector<PoolInfo>& out) const { listPools(out, {&vertices_}); }

private:
    const vk::Context& context_;
    const vk::BindingTable& table_;
    vk::ComputePipeline mesh_;
    vk::Buffer vertices_;
};

}  // namespace vkmesh::gpu
