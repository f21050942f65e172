// Component: the volume's parameters (VolumeParamsGpu, a uniform buffer every stage reads). The host keeps
// the authoritative copy; a change (a capacity that grew, the export buffers' size) is written into the next
// submission with vkCmdUpdateBuffer, so no parameter change costs a host round trip.
#pragma once

#include "gpu/structure/component.h"
#include "gpu/layout.h"

namespace vkmesh::gpu {

class ParamsBuffer {
public:
    ParamsBuffer(const vk::Context& context, const vk::BindingTable& table, const VolumeParamsGpu& initial);

    const VolumeParamsGpu& values() const { return values_; }
    // The copy to change; the change reaches the GPU with the next recordUpload().
    VolumeParamsGpu& edit() {
        dirty_ = true;
        return values_;
    }
    // At the start of a submission: uploads the parameters if they changed, then a barrier.
    void recordUpload(VkCommandBuffer cmd);
    void pools(std::vector<PoolInfo>& out) const { listPools(out, {&buffer_}); }

private:
    vk::Buffer buffer_;
    VolumeParamsGpu values_;
    bool dirty_ = true;
};

}  // namespace vkmesh::gpu
