// What the data structure's components (block store, cube mesh, frame lists, counters, parameters, and the
// block hash) have in common: each owns its device buffers, binds them into the frame's BindingTable under
// the binding numbers of shared_layout.h (and again after it grows one), and lists them for pools().
#pragma once

#include <cstring>
#include <string>
#include <vector>

#include "vk/buffer.h"
#include "vk/commands.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

struct PoolInfo {
    std::string name;
    size_t bytes;
};

// A device-local storage buffer bound at `binding`.
inline vk::Buffer makeStorage(const vk::Context& context, const vk::BindingTable& table, uint32_t binding, VkDeviceSize size,
                              const std::string& name, VkBufferUsageFlags extraUsage = 0) {
    vk::Buffer buffer(context, size, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | extraUsage, vk::MemoryUse::Device, name);
    table.bind(binding, buffer);
    return buffer;
}

// Replaces `buffer` by a larger one bound at the same binding, recording the copy of the old contents into
// `cmd` and the fill of the new part with `fill`. The old buffer goes to `retired`, to be destroyed once
// `cmd` has finished. Returns the old size in bytes.
inline VkDeviceSize growStorage(VkCommandBuffer cmd, const vk::Context& context, const vk::BindingTable& table, uint32_t binding,
                                vk::Buffer& buffer, VkDeviceSize newSize, uint32_t fill, std::vector<vk::Buffer>& retired,
                                VkBufferUsageFlags extraUsage = 0) {
    const VkDeviceSize kept = buffer.size();
    vk::Buffer grown(context, newSize, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | extraUsage, vk::MemoryUse::Device, buffer.name());
    VkBufferCopy region{0, 0, kept};
    vkCmdCopyBuffer(cmd, buffer.handle(), grown.handle(), 1, &region);
    vkCmdFillBuffer(cmd, grown.handle(), kept, VK_WHOLE_SIZE, fill);
    retired.push_back(std::move(buffer));
    buffer = std::move(grown);
    table.bind(binding, buffer);
    return kept;
}

inline void listPools(std::vector<PoolInfo>& out, std::initializer_list<const vk::Buffer*> buffers) {
    for (const vk::Buffer* b : buffers)
        if (b->handle()) out.push_back({b->name(), size_t(b->size())});
}

// A free stack (entries [0, top) are free indices, popped from the top) grown from oldCapacity to
// newCapacity: the new indices go UNDER the old entries, highest first, so that holes and old indices are
// reused before any new one and new ones are handed out in ascending order. That keeps everything in use
// below the high-water mark, which the passes that scan a heap up to it rely on.
inline void growFreeStack(const vk::Context& context, const vk::BindingTable& table, uint32_t binding, vk::Buffer& stack,
                          uint32_t top, uint32_t oldCapacity, uint32_t newCapacity) {
    const uint32_t added = newCapacity - oldCapacity;
    std::vector<uint32_t> entries(size_t(top) + added);
    for (uint32_t i = 0; i < added; ++i) entries[i] = newCapacity - 1 - i;
    if (top) vk::downloadFromBuffer(context, stack, entries.data() + added, VkDeviceSize(top) * 4);
    std::string name = stack.name();
    stack = makeStorage(context, table, binding, VkDeviceSize(newCapacity) * 4, name);
    vk::uploadToBuffer(context, stack, entries.data(), VkDeviceSize(entries.size()) * 4);
}

// A full free stack: every index free, index 0 on top (handed out first).
inline void fillFreeStack(const vk::Context& context, const vk::Buffer& stack, uint32_t capacity) {
    std::vector<uint32_t> entries(capacity);
    for (uint32_t i = 0; i < capacity; ++i) entries[i] = capacity - 1 - i;
    vk::uploadToBuffer(context, stack, entries.data(), VkDeviceSize(capacity) * 4);
}

// Map files (src/gpu/map_file.cpp): fixed-size records of the given pool entries (the live blocks' parts of a
// per-block array), gathered into / scattered from one host array in `indices` order, one copy region each,
// through one staging buffer: only the used parts of a pool cross the bus.
inline void downloadRecords(const vk::Context& context, const vk::Buffer& src, VkDeviceSize recordBytes,
                            const std::vector<uint32_t>& indices, void* out) {
    if (indices.empty()) return;
    vk::Buffer staging(context, recordBytes * indices.size(), VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::Readback,
                       src.name() + " (map readback)");
    std::vector<VkBufferCopy> regions(indices.size());
    for (size_t i = 0; i < indices.size(); ++i) regions[i] = {indices[i] * recordBytes, i * recordBytes, recordBytes};
    vk::CommandRecorder recorder(context);
    VkCommandBuffer cmd = recorder.begin();
    vk::memoryBarrier(cmd);
    vkCmdCopyBuffer(cmd, src.handle(), staging.handle(), uint32_t(regions.size()), regions.data());
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
    staging.invalidate();
    std::memcpy(out, staging.mapped(), staging.size());
}

inline void uploadRecords(const vk::Context& context, const vk::Buffer& dst, VkDeviceSize recordBytes,
                          const std::vector<uint32_t>& indices, const void* data) {
    if (indices.empty()) return;
    vk::Buffer staging(context, recordBytes * indices.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::Upload,
                       dst.name() + " (map upload)");
    std::memcpy(staging.mapped(), data, staging.size());
    std::vector<VkBufferCopy> regions(indices.size());
    for (size_t i = 0; i < indices.size(); ++i) regions[i] = {i * recordBytes, indices[i] * recordBytes, recordBytes};
    vk::CommandRecorder recorder(context);
    VkCommandBuffer cmd = recorder.begin();
    vkCmdCopyBuffer(cmd, staging.handle(), dst.handle(), uint32_t(regions.size()), regions.data());
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
}

// The first `count` words of a buffer (0: nothing), and their upload.
inline std::vector<uint32_t> downloadWords(const vk::Context& context, const vk::Buffer& src, size_t count) {
    std::vector<uint32_t> words(count);
    if (count) vk::downloadFromBuffer(context, src, words.data(), count * 4);
    return words;
}
inline void uploadWords(const vk::Context& context, const vk::Buffer& dst, const std::vector<uint32_t>& words) {
    if (!words.empty()) vk::uploadToBuffer(context, dst, words.data(), words.size() * 4);
}

}  // namespace vkmesh::gpu
