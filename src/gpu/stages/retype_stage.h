// Stage: the cubes to retype (shaders_comp/retype/). Sizes the dispatches over the dirty blocks (plan_mesh),
// moves the retype-mask bits of the dirty blocks into the retype list, as many as fit (collect_retype; the
// rest stay set for the next pass and are counted in retypeDeferred), and sizes the passes over the list
// (plan_retype).
//   reads  dirty list, retype masks    writes retype list, masks (bits taken), dispatch arguments
#pragma once

#include "gpu/structure/counter_buffer.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

class RetypeStage {
public:
    RetypeStage(const vk::Context& context, const vk::BindingTable& table);
    void record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const;

private:
    vk::ComputePipeline plan_, collect_, planRetype_;
};

}  // namespace vkmesh::gpu
