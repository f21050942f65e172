// A VkBuffer with its own memory. Device-local buffers are filled and read through staging copies
// (Context-independent helpers in vk/commands.h); host buffers are mapped for their whole life.
#pragma once

#include <vulkan/vulkan.h>

#include <cstddef>
#include <string>

#include "vk/context.h"

namespace vkmesh::vk {

enum class MemoryUse {
    Device,    // device-local: the data structure, written and read by shaders
    Upload,    // host-visible, coherent: per-frame inputs written by the host
    Readback,  // host-visible, cached when possible: small results read by the host
    DeviceMapped,  // device-local AND host-visible, coherent: per-frame inputs written by the host where shaders
                   // read them, on a device with unified memory (Context::unifiedMemory)
};

class Buffer {
public:
    Buffer() = default;
    Buffer(const Context& context, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use, std::string name);
    ~Buffer();
    Buffer(Buffer&& other) noexcept;
    Buffer& operator=(Buffer&& other) noexcept;
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;

    VkBuffer handle() const { return buffer_; }
    VkDeviceSize size() const { return size_; }
    const std::string& name() const { return name_; }
    // Host pointer for Upload/Readback buffers (nullptr for Device ones).
    void* mapped() const { return mapped_; }
    // Makes device writes visible to the host for non-coherent Readback memory.
    void invalidate() const;

private:
    void release();
    VkDevice device_ = VK_NULL_HANDLE;
    VkBuffer buffer_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkDeviceSize size_ = 0;
    void* mapped_ = nullptr;
    bool coherent_ = true;
    std::string name_;
};

}  // namespace vkmesh::vk
