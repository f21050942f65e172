// Stage: the cubes to retype (shaders_comp/retype/). Sizes the dispatches over the dirty blocks (plan_mesh),
// caches each dirty block's neighbour blocks (cache_neighbors); with refinement lists the corners of the
// marked cubes (list_sign_corners, plan_sign_corners), re-decides their meshing signs and marks the cubes
// around those that changed (decide_mesh_signs); then moves the retype-mask bits of the dirty blocks into the
// retype list, as many as fit (collect_retype; the rest stay set for the next pass and are counted in
// retypeDeferred), and sizes the passes over the list (plan_retype).
//   reads  dirty list, hash, TSDF, retype masks, mesh signs
//   writes block neighbours, mesh signs, retype list, masks (bits taken and set), dispatch arguments
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class RetypeStage {
public:
    RetypeStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;
    // Up to the meshing signs (plan_mesh to decide_mesh_signs): with every retype bit set, the signs of every
    // corner of the dirty blocks (after a map is loaded). Marks what changed, as record() does.
    void recordMeshSigns(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;

private:
    bool refines_;
    vk::ComputePipeline plan_, cacheNeighbors_, listSignCorners_, planSignCorners_, decideSigns_, collect_, planRetype_;
};

}  // namespace vkmesh::gpu
