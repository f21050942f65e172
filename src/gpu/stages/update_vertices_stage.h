// Stage: move vertices to the current zero crossing of their edge (paper §V.B; shaders_comp/update_vertices/).
// First the vertices to move are listed: from the dirty blocks' cubes (list_dirty_vertices) plus this
// frame's new vertices (list_new_vertices), or from a scan of the heap up to its high water
// (list_heap_vertices), whichever commit_vertices found cheaper (VolumeParamsGpu::vertexUpdate can force
// one; the other dispatches are empty; the same list either way). Then move_vertices moves each listed
// vertex, with every SIMD lane busy (plan_move_vertices sizes it).
//   reads  TSDF, hash, edge slots, dirty list, new vertices    writes moved list, vertex positions, normals, colours
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class UpdateVerticesStage {
public:
    UpdateVerticesStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;

private:
    vk::ComputePipeline listDirty_, listNew_, listHeap_, plan_, move_;
};

}  // namespace vkmesh::gpu
