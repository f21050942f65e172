// What the volume can hold and how it grows: the check of every buffer against the device before anything is
// allocated (checkCapacities), the growth policy that runs between frames (growBeforeFrame, growAfterDeferral,
// growMeshAfterFrame: docs/MESH.md, "Capacities"), the growth of each capacity, and the warnings of what did not
// fit.
#include "gpu/capacities.h"

#include <algorithm>
#include <string>

#include "vk/check.h"

namespace vkmesh::gpu {

uint32_t nextPowerOfTwo(uint32_t v) {
    uint32_t p = 1;
    while (p < v && p < (1u << 31)) p <<= 1;
    return p;
}

// The largest device-local heap: where vkmesh's buffers live.
uint64_t deviceLocalHeapBytes(const vk::Context& context) {
    VkPhysicalDeviceMemoryProperties props{};
    vkGetPhysicalDeviceMemoryProperties(context.physicalDevice(), &props);
    uint64_t best = 0;
    for (uint32_t i = 0; i < props.memoryHeapCount; ++i)
        if (props.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) best = std::max<uint64_t>(best, props.memoryHeaps[i].size);
    return best;
}

FrameListCapacities listCapacities(const GpuVolumeConfig& c) {
    return {c.blockCapacity, c.touchedCapacity, c.retypeCapacity, c.vertexCapacity, c.chunkCapacity};
}

namespace {
std::string mib(uint64_t bytes) { return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB"; }
}  // namespace

void checkCapacities(const GpuVolumeConfig& c, uint64_t maxBufferBytes, uint64_t deviceMemoryBytes, const std::string& deviceName,
                     uint32_t hashKeyBytesPerSlot) {
    struct Planned {
        const char* buffer;
        uint64_t bytesPerUnit;
        uint64_t units;
        const char* setting;   // what sizes it: config field (CLI option)
    };
    const bool mesh = c.meshMode == MeshMode::Incremental;
    const uint64_t hashSlots = c.hashCapacity ? c.hashCapacity : std::max<uint64_t>(2ull * c.blockCapacity, 1024);
    std::vector<Planned> planned = {
        {"voxel sdf", 4ull * VOXELS_PER_BLOCK, c.blockCapacity, "blockCapacity (--blocks)"},
        {"voxel weight", 4ull * VOXELS_PER_BLOCK, c.blockCapacity, "blockCapacity (--blocks)"},
        {"hash keys", hashKeyBytesPerSlot, hashSlots, "hashCapacity (2 x blockCapacity by default, --blocks)"},
        {"depth image", c.params.colorFusion != ColorFusion::Off ? 8u : 4u, uint64_t(c.imageWidth) * uint64_t(c.imageHeight),
         "the image size"},
    };
    if (c.params.colorFusion != ColorFusion::Off)
        planned.push_back({"voxel colour", 4ull * VOXELS_PER_BLOCK, c.blockCapacity, "blockCapacity (--blocks; --no-color saves it)"});
    if (mesh) {
        planned.push_back({"cube state", 4ull * VOXELS_PER_BLOCK, c.blockCapacity, "blockCapacity (--blocks)"});
        for (const char* axis : {"edge vertex slots x", "edge vertex slots y", "edge vertex slots z"})
            planned.push_back({axis, 4ull * VOXELS_PER_BLOCK, c.blockCapacity, "blockCapacity (--blocks)"});
        planned.push_back({"owned slot masks", 4ull * OWNED_SLOT_WORDS, c.blockCapacity, "blockCapacity (--blocks)"});
        planned.push_back({"vertex heap", sizeof(Vertex), c.vertexCapacity, "vertexCapacity (--vertices)"});
        planned.push_back({"triangle chunks", 4ull * CHUNK_WORDS, c.chunkCapacity, "chunkCapacity (--chunks)"});
        planned.push_back({"retype list", 4ull * RETYPE_LIST_WORDS_PER_CUBE, c.retypeCapacity, "retypeCapacity"});
        if (c.trackDeltas) {
            planned.push_back({"vertex heap shadow", sizeof(Vertex), c.vertexCapacity, "vertexCapacity (--vertices)"});
            planned.push_back({"triangle chunk shadow", 4ull * CHUNK_WORDS, c.chunkCapacity, "chunkCapacity (--chunks)"});
        }
    }
    uint64_t total = 0;
    for (const Planned& p : planned) {
        const uint64_t bytes = p.bytesPerUnit * p.units;
        total += bytes;
        if (bytes > maxBufferBytes)
            throw Error(std::string("buffer '") + p.buffer + "' would need " + mib(bytes) + " but one storage buffer may hold at most " +
                        mib(maxBufferBytes) + " on " + deviceName + ": lower " + p.setting + " to at most " +
                        std::to_string(maxBufferBytes / p.bytesPerUnit) + " (currently " + std::to_string(p.units) +
                        "), or use a larger voxel size to need fewer");
    }
    // The rest (lists, masks, stamps, exports) is small next to these; 10 % covers it.
    const uint64_t needed = total + total / 10;
    if (deviceMemoryBytes && needed > deviceMemoryBytes) {
        std::string biggest;
        std::sort(planned.begin(), planned.end(),
                  [](const Planned& a, const Planned& b) { return a.bytesPerUnit * a.units > b.bytesPerUnit * b.units; });
        for (size_t i = 0; i < std::min<size_t>(3, planned.size()); ++i)
            biggest += std::string(i ? ", " : "") + planned[i].buffer + " " + mib(planned[i].bytesPerUnit * planned[i].units) + " (" +
                       planned[i].setting + ")";
        throw Error("these capacities need about " + mib(needed) + " of device memory but " + deviceName + " has " +
                    mib(deviceMemoryBytes) + " (largest device-local heap); the largest buffers: " + biggest +
                    ". Lower them, or choose another device (--device)");
    }
}


// ---- growth of each capacity ----------------------------------------------------------------------

void GpuVolume::growHash(uint32_t slots, FrameReport& report) {
    const uint64_t maxSlots = std::min<uint64_t>(context_.maxStorageBufferRange() / BlockHash::keyBytesPerSlot(context_.int64Atomics()), 1u << 31);
    slots = uint32_t(std::min<uint64_t>(nextPowerOfTwo(slots), maxSlots));
    const uint32_t oldSlots = config_.hashCapacity;
    if (slots <= oldSlots) {
        if (!(limitsReported_ & kHashLimit))
            report.warnings.push_back("the block hash cannot grow past " + std::to_string(oldSlots) + " slots on this device");
        limitsReported_ |= kHashLimit;
        return;
    }
    // With the old table: list the live blocks, keep each one's stamp in its coordinate's w.
    VkCommandBuffer cmd = beginSubmission();
    counters_.recordClear(cmd, offsetof(Counters, rehashLost), 1);
    blockList_.record(cmd, lastPush_, counters_, oldSlots);
    hash_.recordSaveStamps(cmd, lastPush_, config_.blockCapacity);
    recorder_.submitAndWait();
    // The new, empty table (BlockHash::grow's parts, so that the new hashCapacity reaches the GPU with the
    // parameters at the start of the next submission); every live block re-inserted under it.
    hash_.replace(slots);
    params_.edit().hashCapacity = slots;
    config_.hashCapacity = slots;
    cmd = beginSubmission();
    hash_.recordReinsert(cmd, lastPush_, config_.blockCapacity);
    counters_.recordReadback(cmd);
    recorder_.submitAndWait();
    report.growth.push_back("block hash " + std::to_string(oldSlots) + " -> " + std::to_string(slots) + " slots");
    if (counters_.read().rehashLost)
        report.warnings.push_back("growing the hash could not re-insert " + std::to_string(counters_.read().rehashLost) +
                                  " live blocks within " + std::to_string(HASH_MAX_PROBES) + " probes");
}

// ---- growth ---------------------------------------------------------------------------------------

void GpuVolume::growBlockPool(uint32_t blocks, FrameReport& report) {
    const uint32_t old = config_.blockCapacity;
    // The per-cube arrays (TSDF, cube state, edge slots: 2 KiB per block each) are the largest bindings.
    const uint64_t maxBlocks = std::min<uint64_t>(context_.maxStorageBufferRange() / (4ull * VOXELS_PER_BLOCK), 1u << 30);
    blocks = uint32_t(std::min<uint64_t>(blocks, maxBlocks));
    if (blocks <= old) {
        if (!(limitsReported_ & kPoolLimit))
            report.warnings.push_back("the block pool cannot grow past " + std::to_string(old) +
                                      " blocks: one storage buffer binding holds at most that many blocks' TSDF on this device");
        limitsReported_ |= kPoolLimit;
        return;
    }
    GpuVolumeConfig next = config_;
    next.blockCapacity = blocks;
    if (touchedFollowsPool_) next.touchedCapacity = blocks;
    next.hashCapacity = std::max(config_.hashCapacity, nextPowerOfTwo(2 * blocks));
    try {
        checkCapacities(next, context_.maxStorageBufferRange(), deviceLocalHeapBytes(context_), context_.info().name,
                        BlockHash::keyBytesPerSlot(context_.int64Atomics()));
    } catch (const Error& e) {
        if (!(limitsReported_ & kPoolLimit))
            report.warnings.push_back(std::string("the block pool cannot grow past ") + std::to_string(old) + " blocks: " + e.what());
        limitsReported_ |= kPoolLimit;
        return;
    }
    store_.grow(blocks, counters_);
    mesh_.growCubes(blocks);
    lists_.grow(listCapacities(next));
    config_.blockCapacity = blocks;
    config_.touchedCapacity = next.touchedCapacity;
    params_.edit().blockCapacity = blocks;
    params_.edit().touchedCapacity = next.touchedCapacity;
    report.growth.push_back("block pool " + std::to_string(old) + " -> " + std::to_string(blocks) + " blocks");
    if (next.hashCapacity > config_.hashCapacity) growHash(next.hashCapacity, report);
}

void GpuVolume::growTouched(uint32_t entries, FrameReport& report) {
    if (entries <= config_.touchedCapacity) return;
    const uint32_t old = config_.touchedCapacity;
    lists_.grow({config_.blockCapacity, entries, config_.retypeCapacity, config_.vertexCapacity, config_.chunkCapacity});
    config_.touchedCapacity = entries;
    params_.edit().touchedCapacity = entries;
    report.growth.push_back("touched list " + std::to_string(old) + " -> " + std::to_string(entries));
}

void GpuVolume::growRetypeList(uint32_t entries, FrameReport& report) {
    const uint32_t maxEntries = uint32_t(std::min<uint64_t>(context_.maxStorageBufferRange() / (4ull * RETYPE_LIST_WORDS_PER_CUBE),
                                                            uint64_t(config_.blockCapacity) * VOXELS_PER_BLOCK));
    entries = std::min(entries, maxEntries);
    if (entries <= config_.retypeCapacity) return;
    const uint32_t old = config_.retypeCapacity;
    lists_.grow({config_.blockCapacity, config_.touchedCapacity, entries, config_.vertexCapacity, config_.chunkCapacity});
    config_.retypeCapacity = entries;
    params_.edit().retypeCapacity = entries;
    report.growth.push_back("retype list " + std::to_string(old) + " -> " + std::to_string(entries));
}

void GpuVolume::growHeaps(uint32_t vertexCapacity, uint32_t chunkCapacity, FrameReport* report) {
    if (config_.meshMode != MeshMode::Incremental) throw Error("growMeshHeaps needs the incremental mesh mode");
    const uint32_t oldVertices = config_.vertexCapacity, oldChunks = config_.chunkCapacity;
    vertexCapacity = std::max(vertexCapacity, oldVertices);
    chunkCapacity = std::max(chunkCapacity, oldChunks);
    if (vertexCapacity == oldVertices && chunkCapacity == oldChunks) return;
    if (vertexCapacity >= CLAIMED_SLOT) throw Error("vertex capacity " + std::to_string(vertexCapacity) + " must be < 2^32 - 2");
    if (chunkCapacity >= (1u << (32 - CUBE_CHUNK_SHIFT)) - 1)
        throw Error("triangle chunk capacity " + std::to_string(chunkCapacity) + " must be < 2^23 - 1");
    for (VkDeviceSize bytes : {VkDeviceSize(vertexCapacity) * sizeof(Vertex), VkDeviceSize(chunkCapacity) * CHUNK_WORDS * 4})
        if (bytes > context_.maxStorageBufferRange())
            throw Error("a mesh heap of " + std::to_string(bytes) + " bytes exceeds one storage buffer on this device (" +
                        std::to_string(context_.maxStorageBufferRange()) + " bytes)");
    mesh_.growHeaps(vertexCapacity, chunkCapacity, counters_);
    lists_.grow({config_.blockCapacity, config_.touchedCapacity, config_.retypeCapacity, vertexCapacity, chunkCapacity});
    exportMesh_->growRemap(vertexCapacity);
    if (deltas_) deltas_->followHeaps(mesh_);
    config_.vertexCapacity = vertexCapacity;
    config_.chunkCapacity = chunkCapacity;
    params_.edit().vertexCapacity = vertexCapacity;
    params_.edit().chunkCapacity = chunkCapacity;
    retryPending_ = true;
    if (report)
        report->growth.push_back("mesh heaps " + std::to_string(oldVertices) + " -> " + std::to_string(vertexCapacity) + " vertices, " +
                                 std::to_string(oldChunks) + " -> " + std::to_string(chunkCapacity) + " triangle chunks");
}

void GpuVolume::growMeshHeaps(uint32_t vertexCapacity, uint32_t chunkCapacity) { growHeaps(vertexCapacity, chunkCapacity, nullptr); }

namespace {
// The next size of a capacity that must hold `wanted`: at least double, with a quarter of headroom.
uint32_t grownSize(uint32_t current, uint64_t wanted, uint64_t limit) {
    return uint32_t(std::min<uint64_t>(std::max<uint64_t>(2ull * current, wanted + wanted / 4), limit));
}
}  // namespace

void GpuVolume::growBeforeFrame(FrameReport& report) {
    // Keep a quarter of every capacity free, and room for twice what the last frame asked of it.
    const Counters k = counters_.read();
    const GpuVolumeConfig& c = config_;
    const uint64_t blocksWanted = uint64_t(k.blocksInUse) + std::max<uint64_t>(2ull * k.allocRequests, c.blockCapacity / 4);
    if (blocksWanted > c.blockCapacity) growBlockPool(grownSize(c.blockCapacity, blocksWanted, UINT32_MAX), report);
    if (2ull * (uint64_t(k.hashEntries) + k.hashTombstones) > c.hashCapacity) growHash(2 * c.hashCapacity, report);
    if (!touchedFollowsPool_ && 2ull * k.touchedCount > c.touchedCapacity) growTouched(grownSize(c.touchedCapacity, 2ull * k.touchedCount, UINT32_MAX), report);
    if (c.meshMode == MeshMode::Incremental) {
        const bool vertices = 4ull * k.verticesInUse > 3ull * c.vertexCapacity, chunks = 4ull * k.chunksInUse > 3ull * c.chunkCapacity;
        if (vertices || chunks) {
            const uint64_t maxVertices = std::min<uint64_t>(context_.maxStorageBufferRange() / sizeof(Vertex), CLAIMED_SLOT - 1);
            const uint64_t maxChunks = std::min<uint64_t>(context_.maxStorageBufferRange() / (4ull * CHUNK_WORDS), (1u << (32 - CUBE_CHUNK_SHIFT)) - 2);
            growHeaps(vertices ? grownSize(c.vertexCapacity, k.verticesInUse, maxVertices) : c.vertexCapacity,
                      chunks ? grownSize(c.chunkCapacity, k.chunksInUse, maxChunks) : c.chunkCapacity, &report);
        }
    }
}

void GpuVolume::growAfterDeferral(const Counters& k, FrameReport& report) {
    const GpuVolumeConfig& c = config_;
    if (k.poolExhausted) growBlockPool(grownSize(c.blockCapacity, uint64_t(k.blocksInUse) + k.poolExhausted, UINT32_MAX), report);
    // hashFull counts visits, at least one per key that found no slot: room for all of them at half load.
    if (k.hashFull) growHash(uint32_t(std::min<uint64_t>(4ull * (uint64_t(k.hashEntries) + k.hashFull), 1u << 31)), report);
    if (k.touchedCount > config_.touchedCapacity) growTouched(grownSize(config_.touchedCapacity, k.touchedCount, UINT32_MAX), report);
}

void GpuVolume::growMeshAfterFrame(const Counters& k, FrameReport& report) {
    const GpuVolumeConfig& c = config_;
    if (k.retypeDeferred) {
        growRetypeList(grownSize(c.retypeCapacity, uint64_t(k.retypeCount) + k.retypeDeferred, UINT32_MAX), report);
        retryPending_ = true;
    }
    if (k.vertexExhausted || k.chunkExhausted) {
        const uint64_t maxVertices = std::min<uint64_t>(context_.maxStorageBufferRange() / sizeof(Vertex), CLAIMED_SLOT - 1);
        const uint64_t maxChunks = std::min<uint64_t>(context_.maxStorageBufferRange() / (4ull * CHUNK_WORDS), (1u << (32 - CUBE_CHUNK_SHIFT)) - 2);
        const uint32_t vertices = k.vertexExhausted ? grownSize(c.vertexCapacity, uint64_t(c.vertexCapacity) + k.vertexExhausted, maxVertices)
                                                    : c.vertexCapacity;
        const uint32_t chunks = k.chunkExhausted ? grownSize(c.chunkCapacity, uint64_t(c.chunkCapacity) + k.chunkExhausted, maxChunks)
                                                 : c.chunkCapacity;
        if (vertices > c.vertexCapacity || chunks > c.chunkCapacity) growHeaps(vertices, chunks, &report);
    }
}

void GpuVolume::warnAboutCapacities(const Counters& k, FrameReport& report) const {
    if (k.hashFull)
        report.warnings.push_back(std::to_string(k.hashFull) + " block insertions found no free hash slot within " +
                                  std::to_string(HASH_MAX_PROBES) + " probes (hash capacity " +
                                  std::to_string(config_.hashCapacity) + "); those blocks were not fused this frame");
    if (k.poolExhausted)
        report.warnings.push_back("block pool exhausted: " + std::to_string(k.poolExhausted) +
                                  " new blocks got no memory (capacity " + std::to_string(config_.blockCapacity) +
                                  " blocks, all in use); raise --blocks. Blocks already fused are kept");
    if (k.touchedCount > config_.touchedCapacity)
        report.warnings.push_back("frame touched " + std::to_string(k.touchedCount) + " blocks, more than the touched-list capacity " +
                                  std::to_string(config_.touchedCapacity) + "; the rest were not fused this frame");
    if (k.outOfRange)
        report.warnings.push_back(std::to_string(k.outOfRange) + " block visits lay outside the addressable grid (|coordinate| >= 2^20 blocks)");
    if (k.retypeDeferred)
        report.warnings.push_back(std::to_string(k.retypeDeferred) + " cubes to re-mesh did not fit in the retype list (capacity " +
                                  std::to_string(config_.retypeCapacity) + "); they are re-meshed " +
                                  (config_.growCapacities ? "next frame (the list grew)" : "when their blocks are next dirty"));
    if (k.vertexExhausted)
        report.warnings.push_back("vertex heap exhausted: " + std::to_string(k.vertexExhausted) + " edge vertices not created (capacity " +
                                  std::to_string(config_.vertexCapacity) + "); their triangles are missing until there is room" +
                                  (config_.growCapacities ? " (the heap grew: next frame)" : ""));
    if (k.chunkExhausted)
        report.warnings.push_back("triangle chunk heap exhausted: " + std::to_string(k.chunkExhausted) + " cubes without triangles (capacity " +
                                  std::to_string(config_.chunkCapacity) + ")" + (config_.growCapacities ? " (the heap grew: next frame)" : ""));
    if (k.candidateCount > config_.vertexCapacity)
        report.warnings.push_back(std::to_string(k.candidateCount - config_.vertexCapacity) +
                                  " garbage-collection candidates did not fit in their list; those vertices stay allocated until re-meshed");
    if (k.recycleDeferred)
        report.warnings.push_back(std::to_string(k.recycleDeferred) + " empty blocks were not freed because they still owned mesh "
                                  "vertices or triangles (garbage collection fell behind); retried next frame");
    if (k.rehashLost)
        report.warnings.push_back("hash rebuild could not re-insert " + std::to_string(k.rehashLost) + " live blocks within " +
                                  std::to_string(HASH_MAX_PROBES) + " probes (hash capacity " + std::to_string(config_.hashCapacity) +
                                  "); their memory is lost until the volume is recreated: raise the hash capacity");
    if (k.rayTruncated)
        report.warnings.push_back(std::to_string(k.rayTruncated) + " pixels' truncation bands crossed more than " +
                                  std::to_string(RAY_MAX_BLOCKS) + " blocks and were cut");
}

}  // namespace vkmesh::gpu
