#include "gpu/stages/claim_vertices_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

ClaimVerticesStage::ClaimVerticesStage(const vk::Context& context, const vk::BindingTable& table)
    : claim_(context, table, "mesh_claim"),
      claimClass0_(context, table, "mesh_claim", 0u),
      claimClass1_(context, table, "mesh_claim", 1u),
      claimClass2_(context, table, "mesh_claim", 2u),
      claimClass3_(context, table, "mesh_claim", 3u),
      commit_(context, table, "commit_vertices") {}

void ClaimVerticesStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters, bool lockFree) const {
    if (lockFree) {
        for (const vk::ComputePipeline* claim : {&claimClass0_, &claimClass1_, &claimClass2_, &claimClass3_}) {
            claim->dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, retypeDispatch));
            vk::memoryBarrier(cmd);
        }
    } else {
        claim_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, retypeDispatch));
        vk::memoryBarrier(cmd);
    }
    commit_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
