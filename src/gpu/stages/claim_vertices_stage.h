// Stage: claim edge vertices (paper §V.C; shaders_comp/claim_vertices/). Every cube of the retype list
// claims a vertex on each edge its new type cuts that has none yet (mesh_claim: one atomicCompSwap on the
// edge slot, the winner pops a vertex; or, lock-free, 4 dispatches by cube parity class that need no
// atomic on the slots), and commit_vertices pops what was handed out from the free stack.
//   reads  retype list, TSDF, hash, cube state    writes edge slots, vertex heap/owners, GC candidates
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class ClaimVerticesStage {
public:
    ClaimVerticesStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters, bool lockFree) const;

private:
    vk::ComputePipeline claim_, claimClass0_, claimClass1_, claimClass2_, claimClass3_, commit_;
};

}  // namespace vkmesh::gpu
