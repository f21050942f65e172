// Stage: the live-block list (shaders_comp/block_list/). Lists every block that holds pool memory by a scan
// of the hash (collect_blocks) and sizes Counters::listDispatch, one workgroup per listed block
// (plan_block_list), for the whole-volume passes: recycling, the hash rebuild, the baseline mesh, a full
// re-mesh, the retry of pending cubes.
//   reads  hash keys/values    writes block list, Counters::liveBlockCount, listDispatch
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class BlockListStage {
public:
    BlockListStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, CounterBuffer& counters, uint32_t hashCapacity) const;

private:
    vk::ComputePipeline collect_, plan_;
};

}  // namespace vkmesh::gpu
