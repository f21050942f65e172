// Stage: the cubes to retype (shaders_comp/retype/), over the dirty blocks' mask words (Counters::collectDispatch,
// raised by the marking as it lists dirty blocks). Caches each dirty block's neighbour blocks (cache_neighbors; with
// refinement mark_dirty has cached the touched ones); marks the cubes around the corners fusion flipped and, with
// refinement, re-decides the meshing signs of every corner of the dirty blocks from the masks of the
// TSDF and marks the cubes around those that changed, one invocation per mask word (decide_mesh_signs); then
// moves the retype-mask bits of the dirty blocks into the retype list, as many as fit (collect_retype; the rest
// stay set for the next pass and are counted in retypeDeferred), sizing mesh_claim's dispatch as it lists.
//   reads  dirty list, hash, retype masks, corner flips, mesh signs (and TSDF masks)
//   writes block neighbours, mesh signs, retype list, masks and corner flips (bits taken and set), dispatch arguments
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class RetypeStage {
public:
    RetypeStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;
    // Up to the meshing signs (cache_neighbors to decide_mesh_signs): the cubes around flipped corners marked, and with
    // refinement the signs of every corner of the dirty blocks.
    // Marks what changed, as record() does. `fromTsdf` (after a map is loaded): first sets the dirty blocks'
    // masks of the TSDF from the TSDF (build_tsdf_masks).
    void recordMeshSigns(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters, bool fromTsdf = false) const;

private:
    bool refines_;
    vk::ComputePipeline cacheNeighbors_, buildMasks_, decideSigns_, collect_;
};

}  // namespace vkmesh::gpu
