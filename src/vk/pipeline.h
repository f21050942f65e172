// Compute pipelines built from the SPIR-V embedded at build time (cmake/EmbedShaders.cmake). Each pipeline
// has a descriptor set layout of its own holding only the bindings its shader statically uses (reflected
// from the SPIR-V), so a pipeline never counts buffers it does not touch against the device's per-stage
// limit, and GPU-assisted validation has slots to spare. The buffers themselves are named once, by
// binding number, in a BindingTable shared by a family of pipelines.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "vk/buffer.h"
#include "vk/context.h"

namespace vkmesh::shaders {
// Every shaders_comp/**/*.comp as SPIR-V words, by file name without extension.
const std::map<std::string, std::span<const uint32_t>>& all();
}  // namespace vkmesh::shaders

namespace vkmesh::vk {

// The most storage buffers one vkmesh pipeline may use: half of lavapipe's (and many mobile GPUs')
// maxPerStageDescriptorStorageBuffers of 32, so that GPU-assisted validation, which needs slots of its own,
// fits too (docs/PORTABILITY.md). Checked when a pipeline is created.
inline constexpr uint32_t kMaxStorageBuffersPerPipeline = 16;

// A descriptor binding (set 0) that a shader's entry point statically uses.
struct ShaderBinding {
    uint32_t binding = 0;
    VkDescriptorType type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
};

// The set-0 bindings the entry point of a SPIR-V module statically uses (loads, stores, atomics, access
// chains, array lengths on the variable), sorted by binding. Declared but unused buffers are left out.
// Throws Error on malformed SPIR-V or on a binding in another set.
std::vector<ShaderBinding> reflectBindings(std::span<const uint32_t> spirv, const std::string& shaderName);

class ComputePipeline;

// Binding number -> buffer for a family of compute pipelines with a common numbering (shared_layout.h).
// The data structure's components bind their buffers here (again after growing one); every pipeline's own
// descriptor set is written from the table, at creation and whenever a binding it uses changes.
class BindingTable {
public:
    // `features`: the value of specialisation constant 1 (`VOLUME_FEATURES` in frame.glsl) that every pipeline
    // of the family is built with, a bit mask of the optional code its shaders keep (VOLUME_FEATURE_* in
    // shared_layout.h); all bits set keeps all of it.
    BindingTable(const Context& context, uint32_t pushConstantSize, uint32_t features = ~0u);
    ~BindingTable();
    BindingTable(const BindingTable&) = delete;
    BindingTable& operator=(const BindingTable&) = delete;

    // (Re)points `binding` at the whole buffer. Never while a command buffer that uses it is recorded but
    // not yet finished (descriptor sets are updated at once).
    void bind(uint32_t binding, const Buffer& buffer) const;
    // (Re)points `binding` at a view of the whole buffer as texels of `format` (`texelBytes` each), for a shader
    // that reads it as a samplerBuffer: on lavapipe texelFetch is a vector gather where an SSBO load at per-lane
    // addresses is a loop over the lanes (docs/TRACKING.md). Throws Error past the device's maxTexelBufferElements.
    // The buffer needs VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT.
    void bindTexels(uint32_t binding, const Buffer& buffer, VkFormat format, uint32_t texelBytes) const;
    uint32_t pushConstantSize() const { return pushConstantSize_; }
    uint32_t features() const { return features_; }
    // Dispatches recorded so far by the table's pipelines (direct and indirect, an indirect one that turns out
    // empty included): the difference over a frame's recording is its pass count, which is a fixed cost per
    // pass on every device (~26 us on lavapipe).
    uint64_t dispatchesRecorded() const { return dispatchesRecorded_; }
    // Called after every dispatch a pipeline of the table records, with the pipeline's shader name (per-pass
    // timestamps, GpuVolumeConfig::timePasses); empty: nothing is called.
    void setDispatchObserver(std::function<void(VkCommandBuffer, const std::string&)> observer) const { observer_ = std::move(observer); }

private:
    friend class ComputePipeline;
    struct Bound {
        VkBuffer buffer = VK_NULL_HANDLE;
        VkDeviceSize size = 0;
        std::string name;
        VkBufferView view = VK_NULL_HANDLE;   // bindTexels: the table's own view of the buffer
    };
    const Context& context_;
    uint32_t pushConstantSize_;
    uint32_t features_;
    // Mutable: binding buffers and (un)registering pipelines does not change which numbering the table is.
    mutable std::map<uint32_t, Bound> bound_;
    mutable std::vector<ComputePipeline*> pipelines_;
    mutable uint64_t dispatchesRecorded_ = 0;
    mutable std::function<void(VkCommandBuffer, const std::string&)> observer_;
};

class ComputePipeline {
public:
    // `specialization`: the value of the shader's `layout(constant_id = 0)` constant, when it has one.
    ComputePipeline(const Context& context, const BindingTable& table, const std::string& shaderName,
                    std::optional<uint32_t> specialization = std::nullopt);
    ~ComputePipeline();
    ComputePipeline(const ComputePipeline&) = delete;
    ComputePipeline& operator=(const ComputePipeline&) = delete;

    // Binds pipeline, descriptor set and push constants. Throws if a binding the shader uses has no buffer.
    void bind(VkCommandBuffer cmd, const void* pushConstants) const;
    void dispatch(VkCommandBuffer cmd, const void* push, uint32_t x, uint32_t y = 1, uint32_t z = 1) const;
    // One invocation per item: ceil(items / workgroup size) workgroups along x (none when items is 0).
    void dispatchItems(VkCommandBuffer cmd, const void* push, uint32_t items) const;
    void dispatchIndirect(VkCommandBuffer cmd, const void* push, const Buffer& args, VkDeviceSize offset) const;
    const std::string& name() const { return name_; }
    const std::vector<ShaderBinding>& bindings() const { return bindings_; }
    uint32_t workgroupSize() const { return workgroupSize_; }   // local_size_x * y * z of the shader

private:
    friend class BindingTable;
    void write(uint32_t binding, const BindingTable::Bound& bound) const;

    const Context& context_;
    const BindingTable& table_;
    std::string name_;
    std::vector<ShaderBinding> bindings_;
    uint32_t workgroupSize_ = 1;
    VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
    VkPipelineLayout pipelineLayout_ = VK_NULL_HANDLE;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
};

}  // namespace vkmesh::vk
