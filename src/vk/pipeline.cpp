#include "vk/pipeline.h"

#include "vk/check.h"
#include "vk/shader_registry.h"

namespace vkmesh::vk {

BindingLayout::BindingLayout(const Context& context, const std::vector<VkDescriptorType>& descriptorTypes,
                             uint32_t pushConstantSize)
    : context_(context), types_(descriptorTypes), pushConstantSize_(pushConstantSize) {
    VkDevice device = context.device();
    std::vector<VkDescriptorSetLayoutBinding> bindings;
    uint32_t storage = 0, uniform = 0;
    for (uint32_t i = 0; i < types_.size(); ++i) {
        bindings.push_back({i, types_[i], 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
        (types_[i] == VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER ? uniform : storage)++;
    }
    VkDescriptorSetLayoutCreateInfo setInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    setInfo.bindingCount = static_cast<uint32_t>(bindings.size());
    setInfo.pBindings = bindings.data();
    check(vkCreateDescriptorSetLayout(device, &setInfo, nullptr, &setLayout_), "vkCreateDescriptorSetLayout");

    VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, pushConstantSize};
    VkPipelineLayoutCreateInfo layoutInfo{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layoutInfo.setLayoutCount = 1;
    layoutInfo.pSetLayouts = &setLayout_;
    layoutInfo.pushConstantRangeCount = pushConstantSize ? 1 : 0;
    layoutInfo.pPushConstantRanges = &range;
    check(vkCreatePipelineLayout(device, &layoutInfo, nullptr, &pipelineLayout_), "vkCreatePipelineLayout");

    std::vector<VkDescriptorPoolSize> sizes;
    if (storage) sizes.push_back({VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, storage});
    if (uniform) sizes.push_back({VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, uniform});
    VkDescriptorPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    poolInfo.maxSets = 1;
    poolInfo.poolSizeCount = static_cast<uint32_t>(sizes.size());
    poolInfo.pPoolSizes = sizes.data();
    check(vkCreateDescriptorPool(device, &poolInfo, nullptr, &pool_), "vkCreateDescriptorPool");

    VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    alloc.descriptorPool = pool_;
    alloc.descriptorSetCount = 1;
    alloc.pSetLayouts = &setLayout_;
    check(vkAllocateDescriptorSets(device, &alloc, &set_), "vkAllocateDescriptorSets");
}

BindingLayout::~BindingLayout() {
    VkDevice device = context_.device();
    if (pool_) vkDestroyDescriptorPool(device, pool_, nullptr);
    if (pipelineLayout_) vkDestroyPipelineLayout(device, pipelineLayout_, nullptr);
    if (setLayout_) vkDestroyDescriptorSetLayout(device, setLayout_, nullptr);
}

void BindingLayout::bind(uint32_t binding, const Buffer& buffer) {
    if (binding >= types_.size()) throw Error("descriptor binding " + std::to_string(binding) + " does not exist");
    if (buffer.size() > context_.maxStorageBufferRange())
        throw Error("Buffer '" + buffer.name() + "' (" + std::to_string(buffer.size()) + " bytes) exceeds the device's " +
                    "maxStorageBufferRange of " + std::to_string(context_.maxStorageBufferRange()) +
                    " bytes; lower the capacity that sizes it");
    VkDescriptorBufferInfo info{buffer.handle(), 0, buffer.size()};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = set_;
    write.dstBinding = binding;
    write.descriptorCount = 1;
    write.descriptorType = types_[binding];
    write.pBufferInfo = &info;
    vkUpdateDescriptorSets(context_.device(), 1, &write, 0, nullptr);
}

ComputePipeline::ComputePipeline(const Context& context, const BindingLayout& layout, const std::string& shaderName,
                                 std::optional<uint32_t> specialization)
    : context_(context), layout_(layout), name_(shaderName) {
    const std::span<const uint32_t> code = shaders::computeShaderFor(context, shaderName);   // the device's hash build
    VkShaderModuleCreateInfo moduleInfo{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    moduleInfo.codeSize = code.size() * sizeof(uint32_t);
    moduleInfo.pCode = code.data();
    VkShaderModule module = VK_NULL_HANDLE;
    check(vkCreateShaderModule(context.device(), &moduleInfo, nullptr, &module), ("vkCreateShaderModule(" + name_ + ")").c_str());

    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    VkSpecializationMapEntry entry{0, 0, sizeof(uint32_t)};
    VkSpecializationInfo spec{1, &entry, sizeof(uint32_t), specialization ? &*specialization : nullptr};
    if (specialization) {
        info.stage.pSpecializationInfo = &spec;
        // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "[" + std::string + "]".
        name_.append("[").append(std::to_string(*specialization)).append("]");
    }
    info.layout = layout.pipelineLayout();
    VkResult r = vkCreateComputePipelines(context.device(), VK_NULL_HANDLE, 1, &info, nullptr, &pipeline_);
    vkDestroyShaderModule(context.device(), module, nullptr);
    check(r, ("vkCreateComputePipelines(" + name_ + ")").c_str());
}

ComputePipeline::~ComputePipeline() {
    if (pipeline_) vkDestroyPipeline(context_.device(), pipeline_, nullptr);
}

void ComputePipeline::bind(VkCommandBuffer cmd, const void* push) const {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
    VkDescriptorSet set = layout_.set();
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_.pipelineLayout(), 0, 1, &set, 0, nullptr);
    if (layout_.pushConstantSize())
        vkCmdPushConstants(cmd, layout_.pipelineLayout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, layout_.pushConstantSize(), push);
}

void ComputePipeline::dispatch(VkCommandBuffer cmd, const void* push, uint32_t x, uint32_t y, uint32_t z) const {
    bind(cmd, push);
    vkCmdDispatch(cmd, x, y, z);
}

void ComputePipeline::dispatchIndirect(VkCommandBuffer cmd, const void* push, const Buffer& args, VkDeviceSize offset) const {
    bind(cmd, push);
    vkCmdDispatchIndirect(cmd, args.handle(), offset);
}

}  // namespace vkmesh::vk
