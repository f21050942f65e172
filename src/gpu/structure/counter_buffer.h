// Component: the counters (Counters in shared_layout.h): what each pass counts, the persistent tops of the
// free stacks and high-water marks, and the indirect-dispatch arguments the planning passes write. The host
// reads one small copy back per submission (recordReadback), never in the middle of a frame.
#pragma once

#include <functional>

#include "gpu/structure/component.h"
#include "gpu/layout.h"

namespace vkmesh::gpu {

class CounterBuffer {
public:
    CounterBuffer(const vk::Context& context, const vk::BindingTable& table);

    const vk::Buffer& buffer() const { return buffer_; }
    // Zeroes the per-frame counters (COUNTERS_PER_FRAME_*) and signCornerCount, and empties the dispatches that the
    // passes raise as they list (x 0, y and z 1: touched list, dirty blocks' mask words, retype list), then a barrier.
    void recordClearFrame(VkCommandBuffer cmd) const;
    // Zeroes `count` consecutive uints starting at the field at `offset` (offsetof(Counters, ...)).
    void recordClear(VkCommandBuffer cmd, size_t offset, uint32_t count) const;
    // Copies the counters to the host-visible copy that read() returns (after the submission finished).
    void recordReadback(VkCommandBuffer cmd);
    Counters read() const;
    // Between submissions: downloads the counters, lets `change` edit them, uploads them and refreshes the
    // host copy. For the host's bookkeeping when a component grows or is reset.
    void update(const std::function<void(Counters&)>& change);
    // Between submissions: uploads `counters` as they are (the host knows them all) and refreshes the host copy.
    void replace(const Counters& counters);
    void pools(std::vector<PoolInfo>& out) const { listPools(out, {&buffer_, &readback_}); }

private:
    const vk::Context& context_;
    vk::Buffer buffer_, readback_;
    // After update(), read() returns what was uploaded until the next readback is recorded (the readback
    // memory is written by the device only).
    Counters uploaded_{};
    bool uploadedIsCurrent_ = true;
};

}  // namespace vkmesh::gpu
