// Compute pipelines built from the SPIR-V embedded at build time (cmake/EmbedShaders.cmake).
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "vk/buffer.h"
#include "vk/context.h"

namespace vkmesh::shaders {
// Every shaders_comp/*.comp as SPIR-V words, by file name without extension.
const std::map<std::string, std::span<const uint32_t>>& all();
}  // namespace vkmesh::shaders

namespace vkmesh::vk {

// One descriptor set layout + push-constant range shared by a family of compute pipelines, and the
// single descriptor set that binds their buffers.
class BindingLayout {
public:
    // descriptorTypes[i] is the type of binding i (all visible to the compute stage).
    BindingLayout(const Context& context, const std::vector<VkDescriptorType>& descriptorTypes, uint32_t pushConstantSize);
    ~BindingLayout();
    BindingLayout(const BindingLayout&) = delete;
    BindingLayout& operator=(const BindingLayout&) = delete;

    void bind(uint32_t binding, const Buffer& buffer);   // (re)points a binding at a whole buffer
    VkPipelineLayout pipelineLayout() const { return pipelineLayout_; }
    VkDescriptorSet set() const { return set_; }
    uint32_t pushConstantSize() const { return pushConstantSize_; }

private:
    const Context& context_;
    std::vector<VkDescriptorType> types_;
    uint32_t pushConstantSize_;
    VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
    VkPipelineLayout pipelineLayout_ = VK_NULL_HANDLE;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
};

class ComputePipeline {
public:
    // `specialization`: the value of the shader's `layout(constant_id = 0)` constant, when it has one.
    ComputePipeline(const Context& context, const BindingLayout& layout, const std::string& shaderName,
                    std::optional<uint32_t> specialization = std::nullopt);
    ~ComputePipeline();
    ComputePipeline(const ComputePipeline&) = delete;
    ComputePipeline& operator=(const ComputePipeline&) = delete;

    // Binds pipeline, descriptor set and push constants.
    void bind(VkCommandBuffer cmd, const void* pushConstants) const;
    void dispatch(VkCommandBuffer cmd, const void* push, uint32_t x, uint32_t y = 1, uint32_t z = 1) const;
    void dispatchIndirect(VkCommandBuffer cmd, const void* push, const Buffer& args, VkDeviceSize offset) const;
    const std::string& name() const { return name_; }

private:
    const Context& context_;
    const BindingLayout& layout_;
    std::string name_;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
};

}  // namespace vkmesh::vk
