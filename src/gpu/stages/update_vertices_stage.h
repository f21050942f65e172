// Stage: move vertices to the current zero crossing of their edge (paper §V.B; shaders_comp/update_vertices/).
// First the vertices to move are listed by their edge slots (list_moved_vertices): the set bits of every dirty
// block's owned-slot mask (the slots that hold a vertex, kept by claim and GC) plus this frame's new vertices
// whose owner block is not dirty; the cost follows the frame, not the map. Then move_vertices moves the vertex
// of each listed slot, with every SIMD lane busy (the listing sizes its dispatch).
//   reads  TSDF, edge slots, owned-slot masks, dirty list, new vertices   writes moved list, vertex positions, normals, colours
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class UpdateVerticesStage {
public:
    UpdateVerticesStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;

private:
    vk::ComputePipeline list_, move_;
};

}  // namespace vkmesh::gpu
