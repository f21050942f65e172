// Stage: move vertices to the current zero crossing of their edge (paper §V.B; shaders_comp/update_vertices/):
// either the dirty blocks' cubes (update_vertices) plus this frame's new vertices (update_new_vertices), or
// a scan of the heap up to its high water (update_heap_vertices), whichever plan_mesh found cheaper
// (VolumeParamsGpu::vertexUpdate can force one); the other dispatches are empty. Same mesh either way.
//   reads  TSDF, hash, edge slots, dirty list, new vertices    writes vertex positions and normals
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class UpdateVerticesStage {
public:
    UpdateVerticesStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;

private:
    vk::ComputePipeline dirty_, fresh_, heap_;
};

}  // namespace vkmesh::gpu
