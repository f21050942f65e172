#include "vk/pipeline.h"

#include <algorithm>
#include <set>
#include <unordered_map>

#include "vk/check.h"
#include "vk/shader_registry.h"

namespace vkmesh::vk {
namespace {

// The few SPIR-V opcodes, decorations and storage classes the reflection needs (SPIR-V spec, section 3).
enum : uint32_t {
    kOpExecutionMode = 16, kOpTypeImage = 25, kOpTypeSampledImage = 27, kOpTypePointer = 32, kOpVariable = 59, kOpLoad = 61, kOpStore = 62, kOpCopyMemory = 63,
    kOpCopyMemorySized = 64, kOpAccessChain = 65, kOpInBoundsAccessChain = 66, kOpPtrAccessChain = 67, kOpArrayLength = 68,
    kOpInBoundsPtrAccessChain = 70, kOpDecorate = 71, kOpCopyObject = 83, kOpFunctionCall = 57, kOpAtomicLoad = 227,
    kOpAtomicStore = 228, kOpAtomicFirst = 229 /* OpAtomicExchange */, kOpAtomicLast = 242 /* OpAtomicXor */,
    kOpAtomicFlagTestAndSet = 318, kOpAtomicFlagClear = 319, kOpAtomicFMinEXT = 5614, kOpAtomicFMaxEXT = 5615,
    kOpAtomicFAddEXT = 6035,
};
enum : uint32_t { kDecorationBlock = 2, kDecorationBufferBlock = 3, kDecorationBinding = 33, kDecorationDescriptorSet = 34 };
enum : uint32_t { kStorageUniformConstant = 0, kStorageUniform = 2, kStorageStorageBuffer = 12 };
constexpr uint32_t kDimBuffer = 5;
constexpr uint32_t kExecutionModeLocalSize = 17;
constexpr uint32_t kSpirvMagic = 0x07230203;

}  // namespace

std::vector<ShaderBinding> reflectBindings(std::span<const uint32_t> spirv, const std::string& shaderName) {
    auto fail = [&](const std::string& what) { return Error("shader '" + shaderName + "': " + what); };
    if (spirv.size() < 5 || spirv[0] != kSpirvMagic) throw fail("not a SPIR-V module");
    struct Variable {
        uint32_t pointerType = 0, storageClass = 0;
    };
    std::unordered_map<uint32_t, uint32_t> binding, set;   // id -> decoration value
    std::set<uint32_t> block, bufferBlock;                 // struct types decorated Block / BufferBlock
    std::unordered_map<uint32_t, uint32_t> pointee;        // pointer type id -> pointee type id
    std::set<uint32_t> sampledBufferImages, texelBuffers;  // OpTypeImage Dim Buffer, Sampled 1; sampled images of them
    std::unordered_map<uint32_t, Variable> variables;      // global variables of interest
    std::set<uint32_t> used;
    auto use = [&](uint32_t id) { used.insert(id); };
    for (size_t at = 5; at < spirv.size();) {
        const uint32_t count = spirv[at] >> 16, op = spirv[at] & 0xFFFFu;
        if (count == 0 || at + count > spirv.size()) throw fail("truncated instruction at word " + std::to_string(at));
        const uint32_t* w = &spirv[at];
        auto word = [&](uint32_t i) { return i < count ? w[i] : 0u; };
        if (op == kOpDecorate && count >= 3) {
            if (w[2] == kDecorationBinding && count >= 4) binding[w[1]] = w[3];
            if (w[2] == kDecorationDescriptorSet && count >= 4) set[w[1]] = w[3];
            if (w[2] == kDecorationBlock) block.insert(w[1]);
            if (w[2] == kDecorationBufferBlock) bufferBlock.insert(w[1]);
        } else if (op == kOpTypeImage && count >= 9) {
            if (w[3] == kDimBuffer && w[7] == 1) sampledBufferImages.insert(w[1]);
        } else if (op == kOpTypeSampledImage && count >= 3) {
            if (sampledBufferImages.count(w[2])) texelBuffers.insert(w[1]);
        } else if (op == kOpTypePointer && count >= 4) {
            pointee[w[1]] = w[3];
        } else if (op == kOpVariable && count >= 4) {
            variables[w[2]] = {w[1], w[3]};
        } else if (op == kOpLoad || op == kOpAccessChain || op == kOpInBoundsAccessChain || op == kOpPtrAccessChain ||
                   op == kOpInBoundsPtrAccessChain || op == kOpArrayLength || op == kOpCopyObject || op == kOpAtomicLoad ||
                   (op >= kOpAtomicFirst && op <= kOpAtomicLast) || op == kOpAtomicFlagTestAndSet || op == kOpAtomicFMinEXT ||
                   op == kOpAtomicFMaxEXT || op == kOpAtomicFAddEXT) {
            use(word(3));   // the pointer operand follows result type and result id
        } else if (op == kOpStore || op == kOpAtomicStore || op == kOpAtomicFlagClear) {
            use(word(1));
        } else if (op == kOpCopyMemory || op == kOpCopyMemorySized) {
            use(word(1));
            use(word(2));
        } else if (op == kOpFunctionCall) {
            for (uint32_t i = 4; i < count; ++i) use(w[i]);   // a pointer passed on counts as used
        }
        at += count;
    }
    std::vector<ShaderBinding> out;
    for (const auto& [id, v] : variables) {
        if (!binding.count(id) || !used.count(id)) continue;
        if (set.count(id) && set[id] != 0) throw fail("binding " + std::to_string(binding[id]) + " is in descriptor set " + std::to_string(set[id]) + "; vkmesh uses set 0 only");
        const uint32_t type = pointee.count(v.pointerType) ? pointee[v.pointerType] : 0;
        ShaderBinding b;
        b.binding = binding[id];
        if (v.storageClass == kStorageStorageBuffer || (v.storageClass == kStorageUniform && bufferBlock.count(type)))
            b.type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        else if (v.storageClass == kStorageUniform && block.count(type))
            b.type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
        else if (v.storageClass == kStorageUniformConstant && texelBuffers.count(type))
            b.type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;   // a samplerBuffer (texelFetch)
        else
            throw fail("binding " + std::to_string(b.binding) + " is neither a uniform buffer, a storage buffer nor a samplerBuffer");
        out.push_back(b);
    }
    std::sort(out.begin(), out.end(), [](const ShaderBinding& a, const ShaderBinding& b) { return a.binding < b.binding; });
    // One buffer may be declared more than once, as views of different types (frame_lists.glsl's mesh signs): one
    // descriptor, so the declarations must agree on its type.
    for (size_t i = 1; i < out.size(); ++i)
        if (out[i].binding == out[i - 1].binding && out[i].type != out[i - 1].type)
            throw fail("binding " + std::to_string(out[i].binding) + " declared twice with different descriptor types");
    out.erase(std::unique(out.begin(), out.end(), [](const ShaderBinding& a, const ShaderBinding& b) { return a.binding == b.binding; }),
              out.end());
    return out;
}

namespace {
uint32_t reflectWorkgroupSize(std::span<const uint32_t> spirv, const std::string& shaderName) {
    for (size_t at = 5; at < spirv.size();) {
        const uint32_t count = spirv[at] >> 16, op = spirv[at] & 0xFFFFu;
        if (count == 0) break;
        if (op == kOpExecutionMode && count >= 6 && spirv[at + 2] == kExecutionModeLocalSize)
            return spirv[at + 3] * spirv[at + 4] * spirv[at + 5];
        at += count;
    }
    throw Error("shader '" + shaderName + "' declares no literal workgroup size (local_size_x/y/z)");
}
}  // namespace

BindingTable::BindingTable(const Context& context, uint32_t pushConstantSize, uint32_t features)
    : context_(context), pushConstantSize_(pushConstantSize), features_(features) {}

BindingTable::~BindingTable() {
    for (auto& [binding, b] : bound_)
        if (b.view) vkDestroyBufferView(context_.device(), b.view, nullptr);
}

void BindingTable::bindTexels(uint32_t binding, const Buffer& buffer, VkFormat format, uint32_t texelBytes) const {
    const VkDeviceSize texels = buffer.size() / texelBytes;
    if (texels > context_.properties().limits.maxTexelBufferElements)
        throw Error("Buffer '" + buffer.name() + "' (" + std::to_string(texels) + " texels) exceeds the device's maxTexelBufferElements of " +
                    std::to_string(context_.properties().limits.maxTexelBufferElements));
    VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    info.buffer = buffer.handle();
    info.format = format;
    info.offset = 0;
    info.range = texels * texelBytes;
    VkBufferView view = VK_NULL_HANDLE;
    check(vkCreateBufferView(context_.device(), &info, nullptr, &view), "vkCreateBufferView");
    Bound& b = bound_[binding];
    if (b.view) vkDestroyBufferView(context_.device(), b.view, nullptr);   // no recorded use may be pending (bind())
    b = {buffer.handle(), buffer.size(), buffer.name(), view};
    for (const ComputePipeline* p : pipelines_) p->write(binding, b);
}

void BindingTable::bind(uint32_t binding, const Buffer& buffer) const {
    if (buffer.size() > context_.maxStorageBufferRange())
        throw Error("Buffer '" + buffer.name() + "' (" + std::to_string(buffer.size()) + " bytes) exceeds the device's " +
                    "maxStorageBufferRange of " + std::to_string(context_.maxStorageBufferRange()) +
                    " bytes; lower the capacity that sizes it");
    Bound& b = bound_[binding];
    if (b.view) vkDestroyBufferView(context_.device(), b.view, nullptr);
    b = {buffer.handle(), buffer.size(), buffer.name()};
    for (const ComputePipeline* p : pipelines_) p->write(binding, b);
}

ComputePipeline::ComputePipeline(const Context& context, const BindingTable& table, const std::string& shaderName,
                                 std::optional<uint32_t> specialization)
    : context_(context), table_(table), name_(shaderName) {
    const std::span<const uint32_t> code = shaders::computeShaderFor(context, shaderName);   // the device's hash build
    bindings_ = reflectBindings(code, shaderName);
    workgroupSize_ = reflectWorkgroupSize(code, shaderName);
    const uint32_t storage = uint32_t(std::count_if(bindings_.begin(), bindings_.end(),
                                                    [](const ShaderBinding& b) { return b.type == VK_DESCRIPTOR_TYPE_STORAGE_BUFFER; }));
    const uint32_t deviceLimit = context.properties().limits.maxPerStageDescriptorStorageBuffers;
    if (storage > kMaxStorageBuffersPerPipeline || storage > deviceLimit)
        throw Error("shader '" + shaderName + "' uses " + std::to_string(storage) + " storage buffers; vkmesh allows " +
                    std::to_string(kMaxStorageBuffersPerPipeline) + " per pipeline and this device " + std::to_string(deviceLimit));
    VkDevice device = context.device();

    std::vector<VkDescriptorSetLayoutBinding> layoutBindings;
    uint32_t uniform = 0, texel = 0;
    for (const ShaderBinding& b : bindings_) {
        layoutBindings.push_back({b.binding, b.type, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
        uniform += b.type == VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
        texel += b.type == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    }
    VkDescriptorSetLayoutCreateInfo setInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    setInfo.bindingCount = uint32_t(layoutBindings.size());
    setInfo.pBindings = layoutBindings.data();
    check(vkCreateDescriptorSetLayout(device, &setInfo, nullptr, &setLayout_), "vkCreateDescriptorSetLayout");

    const uint32_t pushSize = table.pushConstantSize();
    VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, pushSize};
    VkPipelineLayoutCreateInfo layoutInfo{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layoutInfo.setLayoutCount = 1;
    layoutInfo.pSetLayouts = &setLayout_;
    layoutInfo.pushConstantRangeCount = pushSize ? 1 : 0;
    layoutInfo.pPushConstantRanges = &range;
    check(vkCreatePipelineLayout(device, &layoutInfo, nullptr, &pipelineLayout_), "vkCreatePipelineLayout");

    if (!bindings_.empty()) {
        std::vector<VkDescriptorPoolSize> sizes;
        if (storage) sizes.push_back({VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, storage});
        if (uniform) sizes.push_back({VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, uniform});
        if (texel) sizes.push_back({VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, texel});
        VkDescriptorPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        poolInfo.maxSets = 1;
        poolInfo.poolSizeCount = uint32_t(sizes.size());
        poolInfo.pPoolSizes = sizes.data();
        check(vkCreateDescriptorPool(device, &poolInfo, nullptr, &pool_), "vkCreateDescriptorPool");
        VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
        alloc.descriptorPool = pool_;
        alloc.descriptorSetCount = 1;
        alloc.pSetLayouts = &setLayout_;
        check(vkAllocateDescriptorSets(device, &alloc, &set_), "vkAllocateDescriptorSets");
    }

    VkShaderModuleCreateInfo moduleInfo{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    moduleInfo.codeSize = code.size() * sizeof(uint32_t);
    moduleInfo.pCode = code.data();
    VkShaderModule module = VK_NULL_HANDLE;
    check(vkCreateShaderModule(device, &moduleInfo, nullptr, &module), ("vkCreateShaderModule(" + name_ + ")").c_str());
    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    // Constant 1 (the family's features) always; constant 0 when given. An entry for a constant the shader
    // does not declare is ignored (Vulkan spec, VkSpecializationMapEntry).
    const uint32_t values[2] = {table.features(), specialization.value_or(0u)};
    const VkSpecializationMapEntry entries[2] = {{1, 0, sizeof(uint32_t)}, {0, sizeof(uint32_t), sizeof(uint32_t)}};
    VkSpecializationInfo spec{specialization ? 2u : 1u, entries, sizeof(values), values};
    info.stage.pSpecializationInfo = &spec;
    if (specialization) {
        // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "[" + std::string + "]".
        name_.append("[").append(std::to_string(*specialization)).append("]");
    }
    info.layout = pipelineLayout_;
    VkResult r = vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline_);
    vkDestroyShaderModule(device, module, nullptr);
    check(r, ("vkCreateComputePipelines(" + name_ + ")").c_str());

    table_.pipelines_.push_back(this);
    for (const ShaderBinding& b : bindings_) {
        auto bound = table_.bound_.find(b.binding);
        if (bound != table_.bound_.end()) write(b.binding, bound->second);
    }
}

ComputePipeline::~ComputePipeline() {
    auto& list = table_.pipelines_;
    list.erase(std::remove(list.begin(), list.end(), this), list.end());
    VkDevice device = context_.device();
    if (pipeline_) vkDestroyPipeline(device, pipeline_, nullptr);
    if (pool_) vkDestroyDescriptorPool(device, pool_, nullptr);
    if (pipelineLayout_) vkDestroyPipelineLayout(device, pipelineLayout_, nullptr);
    if (setLayout_) vkDestroyDescriptorSetLayout(device, setLayout_, nullptr);
}

void ComputePipeline::write(uint32_t binding, const BindingTable::Bound& bound) const {
    auto it = std::find_if(bindings_.begin(), bindings_.end(), [&](const ShaderBinding& b) { return b.binding == binding; });
    if (it == bindings_.end()) return;   // a buffer this shader does not use
    const bool texels = it->type == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    if (texels != (bound.view != VK_NULL_HANDLE))
        throw Error("shader '" + name_ + "' reads binding " + std::to_string(binding) + (texels ? " as texels but buffer '" : " as a buffer but '") +
                    bound.name + (texels ? "' is bound as a buffer (BindingTable::bindTexels)" : "' is bound as texels"));
    VkDescriptorBufferInfo info{bound.buffer, 0, bound.size};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = set_;
    write.dstBinding = binding;
    write.descriptorCount = 1;
    write.descriptorType = it->type;
    if (texels) write.pTexelBufferView = &bound.view;
    else write.pBufferInfo = &info;
    vkUpdateDescriptorSets(context_.device(), 1, &write, 0, nullptr);
}

void ComputePipeline::bind(VkCommandBuffer cmd, const void* push) const {
    for (const ShaderBinding& b : bindings_)
        if (!table_.bound_.count(b.binding))
            throw Error("shader '" + name_ + "' uses binding " + std::to_string(b.binding) + " but no buffer is bound to it");
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
    if (set_) vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipelineLayout_, 0, 1, &set_, 0, nullptr);
    if (table_.pushConstantSize())
        vkCmdPushConstants(cmd, pipelineLayout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, table_.pushConstantSize(), push);
}

void ComputePipeline::dispatch(VkCommandBuffer cmd, const void* push, uint32_t x, uint32_t y, uint32_t z) const {
    bind(cmd, push);
    vkCmdDispatch(cmd, x, y, z);
    ++table_.dispatchesRecorded_;
    if (table_.observer_) table_.observer_(cmd, name_);
}

void ComputePipeline::dispatchItems(VkCommandBuffer cmd, const void* push, uint32_t items) const {
    if (items == 0) return;
    dispatch(cmd, push, (items + workgroupSize_ - 1) / workgroupSize_);
}

void ComputePipeline::dispatchIndirect(VkCommandBuffer cmd, const void* push, const Buffer& args, VkDeviceSize offset) const {
    bind(cmd, push);
    vkCmdDispatchIndirect(cmd, args.handle(), offset);
    ++table_.dispatchesRecorded_;
    if (table_.observer_) table_.observer_(cmd, name_);
}

}  // namespace vkmesh::vk
