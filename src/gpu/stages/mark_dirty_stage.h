// Stage: dirty blocks (shaders_comp/mark_dirty/), the first of the incremental mesh (docs/MESH.md). Lists
// the blocks whose cubes may need re-meshing this frame in the dirty list, each once (mesh stamps):
//   touched  the touched blocks and their -x/-y/-z neighbours, whose border cubes read their corners
//            (over the touched list: Counters::touchedListDispatch, sized by allocation as it lists);
//   all      every live block (a from-scratch pass; needs the live-block list);
//   pending  every live block with retype bits left over (INCOMPLETE or deferred cubes; needs the list).
//   reads  touched list or block list, hash, retype masks    writes dirty list, mesh stamps, dirtyCount (touched,
//          refined: the touched blocks' neighbour caches)
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class MarkDirtyStage {
public:
    MarkDirtyStage(const vk::Context& context, const vk::BindingTable& table);
    void recordTouched(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;
    void recordAll(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const;
    void recordPending(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const;

private:
    vk::ComputePipeline touched_, all_, pending_;
};

}  // namespace vkmesh::gpu
