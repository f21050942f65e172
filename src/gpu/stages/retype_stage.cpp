#include "gpu/stages/retype_stage.h"

#include <cstddef>

namespace vkmesh::gpu {

RetypeStage::RetypeStage(const vk::Context& context, const vk::BindingTable& table)
    : plan_(context, table, "plan_mesh"), collect_(context, table, "collect_retype"), planRetype_(context, table, "plan_retype") {}

void RetypeStage::record(VkCommandBuffer cmd, const FramePush& push, const CounterBuffer& counters) const {
    plan_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    collect_.dispatchIndirect(cmd, &push, counters.buffer(), offsetof(Counters, collectDispatch));
    vk::memoryBarrier(cmd);
    planRetype_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
