#include "gpu/structure/params_buffer.h"

namespace vkmesh::gpu {

ParamsBuffer::ParamsBuffer(const vk::Context& context, const vk::BindingTable& table, const VolumeParamsGpu& initial)
    : buffer_(context, sizeof(VolumeParamsGpu), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, vk::MemoryUse::Device, "volume params"),
      values_(initial) {
    table.bind(BINDING_PARAMS, buffer_);
    vk::uploadToBuffer(context, buffer_, &values_, sizeof(values_));
    dirty_ = false;
}

void ParamsBuffer::recordUpload(VkCommandBuffer cmd) {
    if (!dirty_) return;
    vkCmdUpdateBuffer(cmd, buffer_.handle(), 0, sizeof(values_), &values_);
    vk::memoryBarrier(cmd);
    dirty_ = false;
}

}  // namespace vkmesh::gpu
