#include "gpu/structure/block_hash.h"

#include <cstddef>
#include <string>

#include "vk/check.h"

namespace vkmesh::gpu {

BlockHash::BlockHash(const vk::Context& context, const vk::BindingTable& layout, uint32_t capacity)
    : context_(context),
      layout_(layout),
      int64Keys_(context.int64Atomics()),
      save_(context, layout, "rehash_save"),
      insert_(context, layout, "rehash_insert"),
      commit_(context, layout, "commit_rehash") {
    replace(capacity);
}

void BlockHash::replace(uint32_t capacity) {
    allocate(capacity);
    vk::CommandRecorder recorder(context_);
    VkCommandBuffer cmd = recorder.begin();
    recordClear(cmd);
    vk::memoryBarrier(cmd);
    recorder.submitAndWait();
}

void BlockHash::allocate(uint32_t capacity) {
    if (capacity == 0 || (capacity & (capacity - 1)) != 0)
        throw Error("hash capacity " + std::to_string(capacity) + " must be a power of two");
    const VkDeviceSize keyBytes = VkDeviceSize(capacity) * keyBytesPerSlot(int64Keys_);
    if (keyBytes > context_.maxStorageBufferRange())
        throw Error("a hash of " + std::to_string(capacity) + " slots needs " + std::to_string(keyBytes) +
                    " bytes of keys but one storage buffer may hold at most " + std::to_string(context_.maxStorageBufferRange()) +
                    " on " + context_.info().name);
    constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    keys_ = vk::Buffer(context_, keyBytes, kStorage, vk::MemoryUse::Device, "hash keys");
    values_ = vk::Buffer(context_, VkDeviceSize(capacity) * 4, kStorage, vk::MemoryUse::Device, "hash values");
    stamps_ = vk::Buffer(context_, VkDeviceSize(capacity) * 4, kStorage, vk::MemoryUse::Device, "hash stamps");
    layout_.bind(BINDING_HASH_KEYS, keys_);
    layout_.bind(BINDING_HASH_VALUES, values_);
    layout_.bind(BINDING_HASH_STAMPS, stamps_);
    capacity_ = capacity;
}

void BlockHash::recordClear(VkCommandBuffer cmd) const {
    // All-ones is KEY_EMPTY in the 64-bit layout and HASH32_WORD_EMPTY in every word of the 32-bit one.
    static_assert(HASH32_WORD_EMPTY == 0xFFFFFFFFu);
    vkCmdFillBuffer(cmd, keys_.handle(), 0, VK_WHOLE_SIZE, HASH32_WORD_EMPTY);
    vkCmdFillBuffer(cmd, values_.handle(), 0, VK_WHOLE_SIZE, NO_BLOCK);
    vkCmdFillBuffer(cmd, stamps_.handle(), 0, VK_WHOLE_SIZE, 0);
}

void BlockHash::recordSaveStamps(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const {
    save_.dispatchItems(cmd, &push, blockCapacity);   // one invocation per block (rehash_save skips past liveBlockCount)
    vk::memoryBarrier(cmd);
}

void BlockHash::recordReinsert(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const {
    insert_.dispatchItems(cmd, &push, blockCapacity);
    vk::memoryBarrier(cmd);
    commit_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
}

void BlockHash::recordInsertListed(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const {
    insert_.dispatchItems(cmd, &push, blockCapacity);
    vk::memoryBarrier(cmd);
}

void BlockHash::recordRebuild(VkCommandBuffer cmd, const FramePush& push, uint32_t blockCapacity) const {
    recordSaveStamps(cmd, push, blockCapacity);
    // Stamps too: rehash_insert writes back those of the live blocks; the others belong to no key.
    recordClear(cmd);
    vk::memoryBarrier(cmd);
    recordReinsert(cmd, push, blockCapacity);
}

uint32_t BlockHash::grow(uint32_t newCapacity, const vk::Buffer& params, const vk::Buffer& counters, const FramePush& push,
                         uint32_t blockCapacity, const std::function<void(VkCommandBuffer)>& recordLiveBlocks) {
    if (newCapacity <= capacity_)
        throw Error("hash growth to " + std::to_string(newCapacity) + " slots: the table has " + std::to_string(capacity_) +
                    " already (it never shrinks)");
    if ((newCapacity & (newCapacity - 1)) != 0)
        throw Error("hash capacity " + std::to_string(newCapacity) + " must be a power of two");
    vk::CommandRecorder recorder(context_);
    // 1. Over the current table: list the live blocks and keep each one's stamp in its coordinate's w.
    VkCommandBuffer cmd = recorder.begin();
    recordLiveBlocks(cmd);
    recordSaveStamps(cmd, push, blockCapacity);
    recorder.submitAndWait();
    // 2. New, empty buffers (the old ones are released once replaced: the GPU is idle).
    replace(newCapacity);
    cmd = recorder.begin();
    vkCmdUpdateBuffer(cmd, params.handle(), offsetof(VolumeParamsGpu, hashCapacity), sizeof(uint32_t), &newCapacity);
    vkCmdFillBuffer(cmd, counters.handle(), offsetof(Counters, rehashLost), sizeof(uint32_t), 0);
    vk::memoryBarrier(cmd);
    // 3. Every live block into the new table (hashEntries = live blocks, no tombstones).
    recordReinsert(cmd, push, blockCapacity);
    recorder.submitAndWait();
    Counters k{};
    vk::downloadFromBuffer(context_, counters, &k, sizeof(k));
    return k.rehashLost;
}

std::vector<BlockHash::Entry> BlockHash::downloadEntries() const {
    std::vector<uint32_t> words(keys_.size() / 4), values(capacity_), stamps(capacity_);
    vk::downloadFromBuffer(context_, keys_, words.data(), keys_.size());
    vk::downloadFromBuffer(context_, values_, values.data(), values_.size());
    vk::downloadFromBuffer(context_, stamps_, stamps.data(), stamps_.size());
    std::vector<Entry> out;
    const int bias = int(KEY_BIAS);
    for (uint32_t s = 0; s < capacity_; ++s) {
        uint32_t x, y, z;
        if (int64Keys_) {
            const uint64_t key = uint64_t(words[2 * s]) | (uint64_t(words[2 * s + 1]) << 32);
            if (key == KEY_EMPTY || key == KEY_TOMBSTONE) continue;
            x = uint32_t(key & KEY_AXIS_MASK);
            y = uint32_t((key >> KEY_BITS) & KEY_AXIS_MASK);
            z = uint32_t((key >> (2 * KEY_BITS)) & KEY_AXIS_MASK);
        } else {
            const uint32_t* w = &words[size_t(s) * HASH32_KEY_WORDS];
            if (w[0] == HASH32_WORD_EMPTY || w[0] == HASH32_WORD_TOMBSTONE) continue;
            x = w[0], y = w[1], z = w[2];
        }
        out.push_back({s, int(x) - bias, int(y) - bias, int(z) - bias, values[s], stamps[s]});
    }
    return out;
}

BlockHash::Occupancy BlockHash::downloadOccupancy() const {
    std::vector<uint32_t> words(keys_.size() / 4);
    vk::downloadFromBuffer(context_, keys_, words.data(), keys_.size());
    Occupancy o;
    for (uint32_t s = 0; s < capacity_; ++s) {
        bool empty, tombstone;
        if (int64Keys_) {
            const uint64_t key = uint64_t(words[2 * s]) | (uint64_t(words[2 * s + 1]) << 32);
            empty = key == KEY_EMPTY, tombstone = key == KEY_TOMBSTONE;
        } else {
            empty = words[size_t(s) * HASH32_KEY_WORDS] == HASH32_WORD_EMPTY;
            tombstone = words[size_t(s) * HASH32_KEY_WORDS] == HASH32_WORD_TOMBSTONE;
        }
        o.keys += !empty && !tombstone;
        o.tombstones += tombstone;
    }
    return o;
}

}  // namespace vkmesh::gpu
