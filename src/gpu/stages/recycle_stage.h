// Stage: bounded maps (docs/MESH.md, "Recycling blocks"; shaders_comp/recycle/). Phase 1 (recordRetire,
// after fusion and mark_dirty, before the mesh passes) zeroes the weights of blocks beyond the keep radius
// and decays those of idle blocks, marking the cubes that read corners which stop being observed; phase 2
// (recordFree, after the mesh passes) frees the blocks left with no weight and no mesh state. Both run over
// the live-block list (BlockListStage).
//   reads  block list, hash stamps, TSDF, cube state, edge slots
//   writes weights, retype masks; hash keys (tombstones), free list, zeroed TSDF of freed blocks
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class RecycleStage {
public:
    RecycleStage(const vk::Context& context, const vk::BindingTable& table);
    void recordRetire(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;
    // overTouched: free_emptied over the frame's touched blocks (a de-integrating frame frees those it emptied)
    // instead of recycle_free over the live-block list.
    void recordFree(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters, bool overTouched = false) const;

private:
    vk::ComputePipeline retire_, free_, freeEmptied_, commit_;
};

}  // namespace vkmesh::gpu
