// Stage: garbage collection of the mesh (paper §V.E; shaders_comp/mesh_gc/). GC candidates still without a
// triangle are unlinked from their edge and pushed on the vertex free stack (free_vertices); released chunks
// go back on the chunk free stack (free_chunks); commit_free updates the tops and in-use counts.
//   reads  garbage lists, refcounts, owners    writes edge slots, free stacks
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class MeshGcStage {
public:
    MeshGcStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;

private:
    vk::ComputePipeline vertices_, chunks_, commit_;
};

}  // namespace vkmesh::gpu
