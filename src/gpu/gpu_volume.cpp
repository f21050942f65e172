#include "gpu/gpu_volume.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>

#include "core/camera.h"
#include "core/marching_cubes.h"
#include "vk/check.h"

namespace vkmesh::gpu {
namespace {

constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;

uint32_t nextPowerOfTwo(uint32_t v) {
    uint32_t p = 1;
    while (p < v && p < (1u << 31)) p <<= 1;
    return p;
}

// The marching-cubes tables in the word layout the shaders read (see MC_TRIANGLE_WORDS_OFFSET).
std::vector<uint32_t> packMarchingCubesTables() {
    const MarchingCubesTables& t = marchingCubesTables();
    std::vector<uint32_t> words(MC_TABLE_WORDS, 0);
    for (uint32_t type = 0; type < 256; ++type) {
        words[type] = t.edgeMask[type] | (uint32_t(t.triangleCount[type]) << 16);
        for (uint32_t i = 0; i < 16; ++i) {
            uint32_t edge = i < 15 && t.triangleEdges[type][i] >= 0 ? uint32_t(t.triangleEdges[type][i]) : 0xFFu;
            words[MC_TRIANGLE_WORDS_OFFSET + type * 4 + i / 4] |= edge << ((i % 4) * 8);
        }
    }
    return words;
}

void validateConfig(const GpuVolumeConfig& c) {
    const VolumeParams& p = c.params;
    if (!(p.voxelSize >= 0.001f && p.voxelSize <= 1.0f))
        throw Error("voxel size " + std::to_string(p.voxelSize) + " m is outside the supported range [0.001, 1] m");
    if (!(p.truncVoxels >= 1.0f && p.truncVoxels <= 64.0f))
        throw Error("truncation of " + std::to_string(p.truncVoxels) + " voxels is outside [1, 64]");
    if (!(p.maxWeight >= 1.0f)) throw Error("max weight " + std::to_string(p.maxWeight) + " must be >= 1");
    if (!(p.minDepth > 0.0f && p.maxDepth > p.minDepth))
        throw Error("depth range [" + std::to_string(p.minDepth) + ", " + std::to_string(p.maxDepth) + "] m is empty");
    if (p.allocationStride < 1 || p.allocationStride > 64)
        throw Error("allocation stride " + std::to_string(p.allocationStride) + " must be in [1, 64]");
    if (c.blockCapacity == 0 || c.blockCapacity > (1u << 30)) throw Error("block capacity must be in [1, 2^30]");
    if (c.imageWidth <= 0 || c.imageHeight <= 0 || c.imageWidth > 65535 || c.imageHeight > 65535)
        throw Error("image size " + std::to_string(c.imageWidth) + "x" + std::to_string(c.imageHeight) + " is not supported");
}

GpuVolumeConfig resolved(GpuVolumeConfig c) {
    validateConfig(c);
    if (c.hashCapacity == 0) c.hashCapacity = nextPowerOfTwo(std::max(2u * c.blockCapacity, 1024u));
    if ((c.hashCapacity & (c.hashCapacity - 1)) != 0)
        throw Error("hash capacity " + std::to_string(c.hashCapacity) + " must be a power of two");
    if (c.touchedCapacity == 0) c.touchedCapacity = c.blockCapacity;
    if (c.meshMode == MeshMode::Baseline) c.vertexCapacity = c.chunkCapacity = 1024;   // unused: keep them small
    if (!(c.refineEpsilonVoxels >= 0.0f && c.refineEpsilonVoxels <= 1.0f))
        throw Error("refinement epsilon " + std::to_string(c.refineEpsilonVoxels) + " voxels must be in [0, 1]");
    if (c.deltaRecordCapacity == 0) throw Error("delta record capacity must be at least 1");
    if (c.retypeCapacity < 1024) throw Error("retype capacity " + std::to_string(c.retypeCapacity) + " must be >= 1024");
    if (c.vertexCapacity < 64 || c.vertexCapacity >= CLAIMED_SLOT)
        throw Error("vertex capacity " + std::to_string(c.vertexCapacity) + " must be in [64, 2^32 - 2)");
    if (c.chunkCapacity < 64 || c.chunkCapacity >= (1u << (32 - CUBE_CHUNK_SHIFT)) - 1)
        throw Error("triangle chunk capacity " + std::to_string(c.chunkCapacity) + " must be in [64, 2^23 - 1)");
    c.meshVertexCapacity = std::max(c.meshVertexCapacity, 1024u);
    if (c.meshMode != MeshMode::Incremental && (c.publishMesh || c.trackDeltas))
        throw Error("publishing the mesh and mesh deltas need the incremental mesh mode");
    if (!(c.keepRadius >= 0.0f)) throw Error("keep radius " + std::to_string(c.keepRadius) + " m must be >= 0 (0 = off)");
    if (c.recycle && (c.recycleAfterFrames == 0 || !(c.starveWeight > 0.0f)))
        throw Error("recycling needs recycleAfterFrames >= 1 and a starve weight > 0");
    if (!(c.hashRebuildTombstoneFraction > 0.0f && c.hashRebuildTombstoneFraction <= 1.0f))
        throw Error("hash rebuild tombstone fraction must be in (0, 1]");
    return c;
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
        {"depth image", 4, uint64_t(c.imageWidth) * uint64_t(c.imageHeight), "the image size"},
    };
    if (mesh) {
        planned.push_back({"cube state", 4ull * VOXELS_PER_BLOCK, c.blockCapacity, "blockCapacity (--blocks)"});
        for (const char* axis : {"edge vertex slots x", "edge vertex slots y", "edge vertex slots z"})
            planned.push_back({axis, 4ull * VOXELS_PER_BLOCK, c.blockCapacity, "blockCapacity (--blocks)"});
        planned.push_back({"vertex heap", sizeof(Vertex), c.vertexCapacity, "vertexCapacity (--vertices)"});
        planned.push_back({"triangle chunks", 4ull * CHUNK_WORDS, c.chunkCapacity, "chunkCapacity (--chunks)"});
        planned.push_back({"retype list", 4, c.retypeCapacity, "retypeCapacity"});
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

namespace {
// The resolved configuration, checked against the device before any buffer is created.
GpuVolumeConfig checkedFor(const vk::Context& context, const GpuVolumeConfig& config) {
    GpuVolumeConfig c = resolved(config);
    checkCapacities(c, context.maxStorageBufferRange(), deviceLocalHeapBytes(context), context.info().name,
                    BlockHash::keyBytesPerSlot(context.int64Atomics()));
    return c;
}
}  // namespace

vk::Buffer GpuVolume::makeBuffer(VkDeviceSize size, VkBufferUsageFlags extraUsage, const std::string& name, uint32_t binding) {
    vk::Buffer buffer(context_, size, kStorage | extraUsage, vk::MemoryUse::Device, name);
    layout_.bind(binding, buffer);
    return buffer;
}

GpuVolume::GpuVolume(const vk::Context& context, const GpuVolumeConfig& config)
    : context_(context),
      config_(checkedFor(context, config)),
      layout_(context, sizeof(FramePush)),
      hash_(context, layout_, config_.hashCapacity),
      allocate_(context, layout_),
      fuse_(context, layout_),
      baselineMesh_(context, layout_),
      incrementalMesh_(context, layout_),
      exportMesh_(context, layout_),
      recycle_(context, layout_),
      recorder_(context),
      timer_(context) {
    const GpuVolumeConfig& c = config_;
    const VkDeviceSize voxels = VkDeviceSize(c.blockCapacity) * VOXELS_PER_BLOCK;
    params_ = vk::Buffer(context, sizeof(VolumeParamsGpu), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, vk::MemoryUse::Device, "volume params");
    layout_.bind(BINDING_PARAMS, params_);
    counters_ = makeBuffer(sizeof(Counters), VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, "counters", BINDING_COUNTERS);
    blockCoords_ = makeBuffer(VkDeviceSize(c.blockCapacity) * 16, 0, "block coords", BINDING_BLOCK_COORDS);
    voxelSdf_ = makeBuffer(voxels * 4, 0, "voxel sdf", BINDING_VOXEL_SDF);
    voxelWeight_ = makeBuffer(voxels * 4, 0, "voxel weight", BINDING_VOXEL_WEIGHT);
    freeList_ = makeBuffer(VkDeviceSize(c.blockCapacity) * 4, 0, "free list", BINDING_FREE_LIST);
    touched_ = makeBuffer(VkDeviceSize(c.touchedCapacity) * 4, 0, "touched list", BINDING_TOUCHED);
    depth_ = makeBuffer(VkDeviceSize(c.imageWidth) * c.imageHeight * 4, 0, "depth image", BINDING_DEPTH);
    mcTables_ = vk::Buffer(context, MC_TABLE_WORDS * 4, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, vk::MemoryUse::Device, "marching cubes tables");
    layout_.bind(BINDING_MC_TABLES, mcTables_);
    blockList_ = makeBuffer(VkDeviceSize(c.blockCapacity) * 4, 0, "block list", BINDING_BLOCK_LIST);
    meshVertices_ = makeBuffer(VkDeviceSize(c.meshVertexCapacity) * 16, 0, "baseline mesh vertices", BINDING_MESH_VERTICES);
    const VkDeviceSize cubes = voxels;
    cubeState_ = makeBuffer(cubes * 4, 0, "cube state", BINDING_CUBE_STATE);
    edgeVertexX_ = makeBuffer(cubes * 4, 0, "edge vertex slots x", BINDING_EDGE_VERTEX_X);
    edgeVertexY_ = makeBuffer(cubes * 4, 0, "edge vertex slots y", BINDING_EDGE_VERTEX_Y);
    edgeVertexZ_ = makeBuffer(cubes * 4, 0, "edge vertex slots z", BINDING_EDGE_VERTEX_Z);
    meshStamps_ = makeBuffer(VkDeviceSize(c.blockCapacity) * 4, 0, "mesh stamps", BINDING_MESH_STAMPS);
    dirtyList_ = makeBuffer(VkDeviceSize(c.blockCapacity) * 4, 0, "dirty list", BINDING_DIRTY_LIST);
    vertices_ = makeBuffer(VkDeviceSize(c.vertexCapacity) * sizeof(Vertex), 0, "vertex heap", BINDING_VERTICES);
    vertexOwner_ = makeBuffer(VkDeviceSize(c.vertexCapacity) * 4, 0, "vertex owners", BINDING_VERTEX_OWNER);
    vertexFree_ = makeBuffer(VkDeviceSize(c.vertexCapacity) * 4, 0, "vertex free stack", BINDING_VERTEX_FREE);
    garbage_ = makeBuffer((VkDeviceSize(c.vertexCapacity) + c.chunkCapacity) * 4, 0, "garbage lists", BINDING_GARBAGE);
    chunkTriangles_ = makeBuffer(VkDeviceSize(c.chunkCapacity) * CHUNK_WORDS * 4, 0, "triangle chunks", BINDING_CHUNK_TRIANGLES);
    chunkFree_ = makeBuffer(VkDeviceSize(c.chunkCapacity) * 4, 0, "chunk free stack", BINDING_CHUNK_FREE);
    vertexRemap_ = makeBuffer(VkDeviceSize(c.vertexCapacity) * 4, 0, "vertex remap", BINDING_VERTEX_REMAP);
    retypeMask_ = makeBuffer(VkDeviceSize(c.blockCapacity) * MASK_WORDS * 4, 0, "retype masks", BINDING_RETYPE_MASK);
    retypeList_ = makeBuffer(VkDeviceSize(c.retypeCapacity) * 4, 0, "retype list", BINDING_RETYPE_LIST);
    exportVertices_ = makeBuffer(1024 * sizeof(Vertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, "export vertices", BINDING_EXPORT_VERTICES);
    exportIndices_ = makeBuffer(1024 * 12, VK_BUFFER_USAGE_INDEX_BUFFER_BIT, "export indices", BINDING_EXPORT_INDICES);
    exportVertexCapacity_ = exportTriangleCapacity_ = 1024;
    depthStaging_ = vk::Buffer(context, depth_.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::Upload, "depth staging");
    countersReadback_ = vk::Buffer(context, sizeof(Counters), VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::Readback, "counters readback");

    VolumeParamsGpu gp{};
    gp.voxelSize = c.params.voxelSize;
    gp.truncation = c.params.truncation();
    gp.maxWeight = c.params.maxWeight;
    gp.minMeshWeight = c.minMeshWeight;
    gp.hashCapacity = c.hashCapacity;
    gp.blockCapacity = c.blockCapacity;
    gp.touchedCapacity = c.touchedCapacity;
    gp.meshVertexCapacity = c.meshVertexCapacity;
    gp.allocationStride = uint32_t(c.params.allocationStride);
    gp.vertexCapacity = c.vertexCapacity;
    gp.chunkCapacity = c.chunkCapacity;
    gp.exportTriangleCapacity = 1024;
    gp.retypeCapacity = c.retypeCapacity;
    gp.incrementalMesh = c.meshMode == MeshMode::Incremental ? 1u : 0u;
    gp.refine = c.refine ? 1u : 0u;
    gp.refineEpsilon = c.refineEpsilonVoxels * c.params.voxelSize;
    gp.vertexUpdate = c.vertexUpdate;
    gp.exportVertexCapacity = exportVertexCapacity_;
    gp.keepRadius = c.keepRadius;
    gp.starveAfterFrames = c.recycle ? c.recycleAfterFrames : 0u;
    gp.starveWeight = c.starveWeight;
    vk::uploadToBuffer(context, params_, &gp, sizeof(gp));
    auto tables = packMarchingCubesTables();
    vk::uploadToBuffer(context, mcTables_, tables.data(), tables.size() * 4);
    // The free list is a stack popped from its top: block 0 is handed out first.
    std::vector<uint32_t> free(c.blockCapacity);
    for (uint32_t i = 0; i < c.blockCapacity; ++i) free[i] = c.blockCapacity - 1 - i;
    vk::uploadToBuffer(context, freeList_, free.data(), free.size() * 4);
    Counters initial{};
    initial.freeTop = c.blockCapacity;
    vk::uploadToBuffer(context, counters_, &initial, sizeof(initial));

    resetMeshState();

    if (c.trackDeltas) {
        deltaLayout_.emplace(context, 0);
        deltaStage_.emplace(context, *deltaLayout_);
        auto deltaBuffer = [&](VkDeviceSize size, VkBufferUsageFlags usage, const char* name, uint32_t binding) {
            vk::Buffer b(context, size, kStorage | usage, vk::MemoryUse::Device, name);
            deltaLayout_->bind(binding, b);
            return b;
        };
        prevVertices_ = deltaBuffer(vertices_.size(), 0, "vertex heap shadow", DELTA_BINDING_PREV_VERTICES);
        prevChunks_ = deltaBuffer(chunkTriangles_.size(), 0, "triangle chunk shadow", DELTA_BINDING_PREV_CHUNKS);
        deltaState_ = deltaBuffer(sizeof(DeltaState), VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, "delta state", DELTA_BINDING_STATE);
        deltaVertexRecords_ = deltaBuffer(c.deltaRecordCapacity * sizeof(DeltaVertexRecord), 0, "vertex delta records", DELTA_BINDING_VERTEX_RECORDS);
        deltaTriangleRecords_ = deltaBuffer(c.deltaRecordCapacity * sizeof(DeltaTriangleRecord), 0, "triangle delta records", DELTA_BINDING_TRIANGLE_RECORDS);
        deltaLayout_->bind(DELTA_BINDING_COUNTERS, counters_);
        deltaLayout_->bind(DELTA_BINDING_VERTICES, vertices_);
        deltaLayout_->bind(DELTA_BINDING_CHUNKS, chunkTriangles_);
        deltaStateReadback_ = vk::Buffer(context, sizeof(DeltaState), VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::Readback, "delta state readback");
        DeltaState state{};
        state.vertexRecordCapacity = state.triangleRecordCapacity = c.deltaRecordCapacity;
        vk::uploadToBuffer(context, deltaState_, &state, sizeof(state));
        // The shadows start as an empty mesh: every vertex dead, every triangle slot empty.
        VkCommandBuffer cmd = recorder_.begin();
        vkCmdFillBuffer(cmd, prevVertices_.handle(), 0, VK_WHOLE_SIZE, 0xFFFFFFFFu);
        vkCmdFillBuffer(cmd, prevChunks_.handle(), 0, VK_WHOLE_SIZE, INVALID_INDEX);
        vk::memoryBarrier(cmd);
        recorder_.submitAndWait();
    }
}

void GpuVolume::resetMeshState() {
    const GpuVolumeConfig& c = config_;
    VkCommandBuffer cmd = recorder_.begin();
    vkCmdFillBuffer(cmd, cubeState_.handle(), 0, VK_WHOLE_SIZE, 0);
    for (const vk::Buffer* b : {&edgeVertexX_, &edgeVertexY_, &edgeVertexZ_}) vkCmdFillBuffer(cmd, b->handle(), 0, VK_WHOLE_SIZE, EMPTY_SLOT);
    vkCmdFillBuffer(cmd, meshStamps_.handle(), 0, VK_WHOLE_SIZE, 0);
    vkCmdFillBuffer(cmd, retypeMask_.handle(), 0, VK_WHOLE_SIZE, 0);
    vkCmdFillBuffer(cmd, vertices_.handle(), 0, VK_WHOLE_SIZE, 0xFFFFFFFFu);   // refcount DEAD everywhere
    vkCmdFillBuffer(cmd, chunkTriangles_.handle(), 0, VK_WHOLE_SIZE, INVALID_INDEX);   // every triangle slot empty
    vk::memoryBarrier(cmd);
    recorder_.submitAndWait();
    // Free stacks popped from the top: index 0 first.
    std::vector<uint32_t> stack(std::max(c.vertexCapacity, c.chunkCapacity));
    for (uint32_t i = 0; i < c.vertexCapacity; ++i) stack[i] = c.vertexCapacity - 1 - i;
    vk::uploadToBuffer(context_, vertexFree_, stack.data(), VkDeviceSize(c.vertexCapacity) * 4);
    for (uint32_t i = 0; i < c.chunkCapacity; ++i) stack[i] = c.chunkCapacity - 1 - i;
    vk::uploadToBuffer(context_, chunkFree_, stack.data(), VkDeviceSize(c.chunkCapacity) * 4);
    Counters k{};
    vk::downloadFromBuffer(context_, counters_, &k, sizeof(k));
    k.vertexFreeTop = c.vertexCapacity;
    k.verticesInUse = k.vertexHighWater = 0;
    k.chunkFreeTop = c.chunkCapacity;
    k.chunksInUse = k.chunkHighWater = 0;
    k.liveTriangles = 0;
    vk::uploadToBuffer(context_, counters_, &k, sizeof(k));
    // readCounters() reads the host copy: keep it current even before the first frame.
    VkCommandBuffer readback = recorder_.begin();
    recordCountersReadback(readback);
    recorder_.submitAndWait();
}

void GpuVolume::setParam(uint32_t VolumeParamsGpu::*field, uint32_t value) {
    VolumeParamsGpu gp{};
    vk::downloadFromBuffer(context_, params_, &gp, sizeof(gp));
    gp.*field = value;
    vk::uploadToBuffer(context_, params_, &gp, sizeof(gp));
}

void GpuVolume::recordCountersReadback(VkCommandBuffer cmd) {
    VkBufferCopy region{0, 0, sizeof(Counters)};
    vkCmdCopyBuffer(cmd, counters_.handle(), countersReadback_.handle(), 1, &region);
    vk::memoryBarrier(cmd);
}

FrameReport GpuVolume::integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                 const vk::SubmitSync& sync) {
    if (depth.width != config_.imageWidth || depth.height != config_.imageHeight ||
        depth.meters.size() != size_t(depth.width) * depth.height)
        throw Error("depth image is " + std::to_string(depth.width) + "x" + std::to_string(depth.height) +
                    " but the volume was created for " + std::to_string(config_.imageWidth) + "x" +
                    std::to_string(config_.imageHeight));
    if (intrinsics.width != depth.width || intrinsics.height != depth.height)
        throw Error("intrinsics are for " + std::to_string(intrinsics.width) + "x" + std::to_string(intrinsics.height) +
                    " images but the depth image is " + std::to_string(depth.width) + "x" + std::to_string(depth.height));
    std::memcpy(depthStaging_.mapped(), depth.meters.data(), depth.meters.size() * sizeof(float));
    FramePush push = makeFramePush(intrinsics, cameraToWorld, config_.params, ++frameNumber_);
    lastPush_ = push;

    if (config_.publishMesh) {
        // Room for last frame's mesh plus what one frame can plausibly add; a frame that adds more is
        // re-exported below after growing the buffers.
        Counters last = readCounters();
        ensureExportCapacity(last.verticesInUse + last.verticesInUse / 8 + 4096, last.liveTriangles + last.liveTriangles / 8 + 8192);
    }
    const bool recycling = this->recycling();
    // Tombstones of freed keys make probes longer and are never reused by insertions: past the threshold
    // (read from the previous frame's counters) the table is rebuilt before this frame allocates.
    const bool rebuildHash = recycling && double(readCounters().hashTombstones) >
                                              double(config_.hashRebuildTombstoneFraction) * config_.hashCapacity;
    auto collectLiveBlocks = [&](VkCommandBuffer cmd) {
        vkCmdFillBuffer(cmd, counters_.handle(), offsetof(Counters, liveBlockCount), sizeof(uint32_t), 0);
        vk::memoryBarrier(cmd);
        baselineMesh_.recordCollect(cmd, push, config_.hashCapacity);
    };

    VkCommandBuffer cmd = recorder_.begin();
    timer_.reset(cmd);
    // Execution dependency on everything submitted before (an application's draws reading the last
    // frame's mesh buffers on this queue): this frame overwrites them.
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                         0, 0, nullptr, 0, nullptr, 0, nullptr);
    VkBufferCopy region{0, 0, depthStaging_.size()};
    vkCmdCopyBuffer(cmd, depthStaging_.handle(), depth_.handle(), 1, &region);
    vkCmdFillBuffer(cmd, counters_.handle(), COUNTERS_PER_FRAME_OFFSET, COUNTERS_PER_FRAME_SIZE, 0);
    vk::memoryBarrier(cmd);
    timer_.mark(cmd, "start");
    if (rebuildHash) {
        collectLiveBlocks(cmd);
        hash_.recordRebuild(cmd, push, config_.blockCapacity);
        timer_.mark(cmd, "rehash");
    }
    allocate_.record(cmd, push, counters_, uint32_t(config_.params.allocationStride));
    timer_.mark(cmd, "allocate");
    fuse_.record(cmd, push, counters_);
    timer_.mark(cmd, "fuse");
    const bool incremental = config_.meshMode == MeshMode::Incremental;
    const bool retryPending = incremental && retryPending_;
    if (incremental) {
        incrementalMesh_.recordMarkTouched(cmd, push, counters_);
        timer_.mark(cmd, "mesh_mark");
    }
    if (recycling || retryPending) collectLiveBlocks(cmd);
    if (retryPending) incrementalMesh_.recordMarkPending(cmd, push, config_.blockCapacity);
    if (recycling) {
        recycle_.recordRetire(cmd, push, counters_);
        timer_.mark(cmd, "recycle_retire");
    }
    if (incremental) incrementalMesh_.recordMesh(cmd, push, counters_, &timer_, config_.lockFree);
    if (recycling) {
        // The live block list is still the one collected above: the mesh passes do not touch the hash.
        recycle_.recordFree(cmd, push, counters_);
        timer_.mark(cmd, "recycle_free");
    }
    if (config_.publishMesh) {
        recordExport(cmd);
        timer_.mark(cmd, "export");
    }
    if (config_.trackDeltas) {
        recordDeltas(cmd);
        timer_.mark(cmd, "deltas");
    }
    recordCountersReadback(cmd);
    recorder_.submitAndWait(sync);

    FrameReport report;
    countersReadback_.invalidate();
    std::memcpy(&report.counters, countersReadback_.mapped(), sizeof(Counters));
    report.stageMs = timer_.read();
    if (config_.publishMesh) {
        meshPublished_ = true;
        if (!exportFits(report.counters)) report.counters = runExport(nullptr);   // grows to the exact counts
    }
    if (config_.trackDeltas) {
        report.delta = collectDeltas();
        report.delta.frame = frameNumber_;
    }
    const Counters& k = report.counters;
    // Cubes deferred by a full retype list are left for the next frame's retry; INCOMPLETE cubes are retried
    // once after a growth (while the heap stays full they wait for their block to be dirty again).
    if (retryPending) retryPending_ = k.retypeDeferred > 0;
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
                                  std::to_string(config_.retypeCapacity) + "); they are re-meshed when their blocks are next dirty");
    if (k.vertexExhausted)
        report.warnings.push_back("vertex heap exhausted: " + std::to_string(k.vertexExhausted) + " edge vertices not created (capacity " +
                                  std::to_string(config_.vertexCapacity) + "); their triangles are missing until there is room");
    if (k.chunkExhausted)
        report.warnings.push_back("triangle chunk heap exhausted: " + std::to_string(k.chunkExhausted) + " cubes without triangles (capacity " +
                                  std::to_string(config_.chunkCapacity) + ")");
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
    return report;
}

Counters GpuVolume::runBaselinePass(std::vector<std::pair<std::string, double>>* stageMs) {
    VkCommandBuffer cmd = recorder_.begin();
    timer_.reset(cmd);
    // liveBlockCount, meshVertices, meshVerticesDropped are consecutive.
    vkCmdFillBuffer(cmd, counters_.handle(), offsetof(Counters, liveBlockCount), 3 * sizeof(uint32_t), 0);
    vk::memoryBarrier(cmd);
    timer_.mark(cmd, "start");
    baselineMesh_.record(cmd, lastPush_, counters_, config_.hashCapacity);
    timer_.mark(cmd, "mesh_baseline");
    recordCountersReadback(cmd);
    recorder_.submitAndWait();
    if (stageMs) *stageMs = timer_.read();
    return readCounters();
}

uint32_t GpuVolume::countBaselineVertices() {
    // The GPU counts every vertex the pass wants, whether or not it fit in the buffer.
    return runBaselinePass(nullptr).meshVertices;
}

TriangleSoup GpuVolume::extractBaselineMesh(std::vector<std::pair<std::string, double>>* stageMs) {
    for (int attempt = 0; attempt < 2; ++attempt) {
        Counters k = runBaselinePass(stageMs);
        if (k.meshVerticesDropped == 0) {
            TriangleSoup soup;
            soup.vertices.resize(k.meshVertices);
            if (k.meshVertices) {
                std::vector<float> raw(size_t(k.meshVertices) * 4);
                vk::downloadFromBuffer(context_, meshVertices_, raw.data(), raw.size() * 4);
                for (size_t i = 0; i < soup.vertices.size(); ++i)
                    soup.vertices[i] = Eigen::Vector3f(raw[4 * i], raw[4 * i + 1], raw[4 * i + 2]);
            }
            return soup;
        }
        // Too small: grow to exactly what the GPU counted and run the pass again.
        VkDeviceSize need = VkDeviceSize(k.meshVertices) * 16;
        if (need > context_.maxStorageBufferRange())
            throw Error("the baseline mesh needs " + std::to_string(k.meshVertices) + " vertices (" + std::to_string(need) +
                        " bytes), more than one storage buffer may hold on this device (" +
                        std::to_string(context_.maxStorageBufferRange()) + " bytes); use a larger voxel size");
        config_.meshVertexCapacity = k.meshVertices;
        meshVertices_ = makeBuffer(need, 0, "baseline mesh vertices", BINDING_MESH_VERTICES);
        VolumeParamsGpu gp{};
        vk::downloadFromBuffer(context_, params_, &gp, sizeof(gp));
        gp.meshVertexCapacity = k.meshVertices;
        vk::uploadToBuffer(context_, params_, &gp, sizeof(gp));
    }
    throw Error("baseline mesh extraction did not fit after growing its buffer");
}

void GpuVolume::ensureExportCapacity(uint32_t vertices, uint32_t triangles) {
    // Grown by a quarter more than asked, so a slowly growing mesh reallocates rarely.
    if (exportVertexCapacity_ < vertices) {
        exportVertexCapacity_ = vertices + vertices / 4;
        exportVertices_ = makeBuffer(VkDeviceSize(exportVertexCapacity_) * sizeof(Vertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT,
                                     "export vertices", BINDING_EXPORT_VERTICES);
        setParam(&VolumeParamsGpu::exportVertexCapacity, exportVertexCapacity_);
    }
    if (exportTriangleCapacity_ < triangles) {
        exportTriangleCapacity_ = triangles + triangles / 4;
        exportIndices_ = makeBuffer(VkDeviceSize(exportTriangleCapacity_) * 12, VK_BUFFER_USAGE_INDEX_BUFFER_BIT, "export indices",
                                    BINDING_EXPORT_INDICES);
        setParam(&VolumeParamsGpu::exportTriangleCapacity, exportTriangleCapacity_);
    }
}

void GpuVolume::recordExport(VkCommandBuffer cmd) {
    vkCmdFillBuffer(cmd, counters_.handle(), offsetof(Counters, exportVertices), 3 * sizeof(uint32_t), 0);
    vk::memoryBarrier(cmd);
    exportMesh_.record(cmd, lastPush_, counters_);
}

bool GpuVolume::exportFits(const Counters& k) const {
    return k.exportVertices <= exportVertexCapacity_ && k.exportTriangles <= exportTriangleCapacity_;
}

Counters GpuVolume::runExport(std::vector<std::pair<std::string, double>>* stageMs) {
    Counters k = readCounters();
    uint32_t wantVertices = k.verticesInUse, wantTriangles = k.liveTriangles;
    for (int attempt = 0; attempt < 2; ++attempt) {
        ensureExportCapacity(wantVertices, wantTriangles);
        VkCommandBuffer cmd = recorder_.begin();
        timer_.reset(cmd);
        timer_.mark(cmd, "start");
        recordExport(cmd);
        timer_.mark(cmd, "export");
        recordCountersReadback(cmd);
        recorder_.submitAndWait();
        if (stageMs) *stageMs = timer_.read();
        k = readCounters();
        meshPublished_ = true;
        if (exportFits(k)) return k;
        // Cannot happen if the live counts are right; grow to what was counted and retry.
        wantVertices = k.exportVertices;
        wantTriangles = k.exportTriangles;
    }
    throw Error("mesh export did not fit after growing its buffers");
}

ExportedMesh GpuVolume::exportMesh(std::vector<std::pair<std::string, double>>* stageMs) {
    if (config_.meshMode != MeshMode::Incremental) throw Error("exportMesh needs the incremental mesh mode");
    Counters k = runExport(stageMs);
    ExportedMesh out;
    out.unreferencedVertices = k.exportUnreferenced;
    out.vertices.resize(k.exportVertices);
    out.triangles.resize(k.exportTriangles);
    if (k.exportVertices)
        vk::downloadFromBuffer(context_, exportVertices_, out.vertices.data(), out.vertices.size() * sizeof(Vertex));
    if (k.exportTriangles)
        vk::downloadFromBuffer(context_, exportIndices_, out.triangles.data(), out.triangles.size() * 12);
    return out;
}

MeshBuffers GpuVolume::meshBuffers() const {
    MeshBuffers b;
    if (!meshPublished_) return b;
    Counters k = readCounters();
    b.vertices = exportVertices_.handle();
    b.indices = exportIndices_.handle();
    b.drawIndirect = counters_.handle();
    b.drawIndirectOffset = offsetof(Counters, drawIndexed);
    b.vertexCount = std::min(k.exportVertices, exportVertexCapacity_);
    b.triangleCount = k.drawIndexed[0] / 3;
    b.frame = frameNumber_;
    return b;
}

void recordMeshReadBarrier(VkCommandBuffer cmd) {
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_INDEX_READ_BIT | VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT |
                            VK_ACCESS_SHADER_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                         VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
                         0, 1, &barrier, 0, nullptr, 0, nullptr);
}

void GpuVolume::recordDeltas(VkCommandBuffer cmd) {
    deltaStage_->record(cmd, deltaState_);
    VkBufferCopy region{0, 0, sizeof(DeltaState)};
    vkCmdCopyBuffer(cmd, deltaState_.handle(), deltaStateReadback_.handle(), 1, &region);
    vk::memoryBarrier(cmd);
}

MeshDelta GpuVolume::collectDeltas() {
    MeshDelta delta;
    // Each pass lists what fits and updates the shadows of only what it listed, so a re-run after growing
    // the lists finds exactly the rest. The number of records is bounded by the heaps: 3 passes suffice.
    for (int pass = 0; pass < 3; ++pass) {
        DeltaState state{};
        deltaStateReadback_.invalidate();
        std::memcpy(&state, deltaStateReadback_.mapped(), sizeof(state));
        uint32_t nv = std::min(state.vertexRecords, state.vertexRecordCapacity);
        uint32_t nt = std::min(state.triangleRecords, state.triangleRecordCapacity);
        size_t v0 = delta.vertices.size(), t0 = delta.triangles.size();
        delta.vertices.resize(v0 + nv);
        delta.triangles.resize(t0 + nt);
        if (nv) vk::downloadFromBuffer(context_, deltaVertexRecords_, &delta.vertices[v0], nv * sizeof(DeltaVertexRecord));
        if (nt) vk::downloadFromBuffer(context_, deltaTriangleRecords_, &delta.triangles[t0], nt * sizeof(DeltaTriangleRecord));
        if (state.vertexRecords <= state.vertexRecordCapacity && state.triangleRecords <= state.triangleRecordCapacity) return delta;
        // Grow the lists that overflowed to what was missing, with headroom, and run the passes again.
        if (state.vertexRecords > state.vertexRecordCapacity) {
            state.vertexRecordCapacity = state.vertexRecords + state.vertexRecords / 2;
            deltaVertexRecords_ = vk::Buffer(context_, VkDeviceSize(state.vertexRecordCapacity) * sizeof(DeltaVertexRecord), kStorage,
                                             vk::MemoryUse::Device, "vertex delta records");
            deltaLayout_->bind(DELTA_BINDING_VERTEX_RECORDS, deltaVertexRecords_);
        }
        if (state.triangleRecords > state.triangleRecordCapacity) {
            state.triangleRecordCapacity = state.triangleRecords + state.triangleRecords / 2;
            deltaTriangleRecords_ = vk::Buffer(context_, VkDeviceSize(state.triangleRecordCapacity) * sizeof(DeltaTriangleRecord), kStorage,
                                               vk::MemoryUse::Device, "triangle delta records");
            deltaLayout_->bind(DELTA_BINDING_TRIANGLE_RECORDS, deltaTriangleRecords_);
        }
        vk::uploadToBuffer(context_, deltaState_, &state.vertexRecordCapacity, 2 * sizeof(uint32_t),
                           offsetof(DeltaState, vertexRecordCapacity));
        VkCommandBuffer cmd = recorder_.begin();
        recordDeltas(cmd);
        recorder_.submitAndWait();
    }
    throw Error("mesh deltas did not fit after growing their lists");
}

void GpuVolume::rebuildMesh() {
    resetMeshState();
    // Every cube of every block is listed for retyping; a pass retypes up to retypeCapacity of them and
    // leaves the rest of the bits set, so passes repeat until none is left.
    VkCommandBuffer cmd = recorder_.begin();
    vkCmdFillBuffer(cmd, retypeMask_.handle(), 0, VK_WHOLE_SIZE, 0xFFFFFFFFu);
    vk::memoryBarrier(cmd);
    recorder_.submitAndWait();
    const uint32_t maxPasses = 2 + config_.blockCapacity * VOXELS_PER_BLOCK / config_.retypeCapacity;
    for (uint32_t pass = 0; pass < maxPasses; ++pass) {
        cmd = recorder_.begin();
        vkCmdFillBuffer(cmd, counters_.handle(), COUNTERS_PER_FRAME_OFFSET, COUNTERS_PER_FRAME_SIZE, 0);
        vkCmdFillBuffer(cmd, counters_.handle(), offsetof(Counters, liveBlockCount), sizeof(uint32_t), 0);
        vk::memoryBarrier(cmd);
        baselineMesh_.recordCollect(cmd, lastPush_, config_.hashCapacity);
        incrementalMesh_.recordMarkAll(cmd, lastPush_, config_.blockCapacity);
        incrementalMesh_.recordMesh(cmd, lastPush_, counters_, nullptr, config_.lockFree);
        recordCountersReadback(cmd);
        recorder_.submitAndWait();
        if (readCounters().retypeDeferred == 0) {
            if (config_.publishMesh) runExport(nullptr);   // the published buffers show the rebuilt mesh
            return;
        }
    }
    throw Error("mesh rebuild did not finish in " + std::to_string(maxPasses) + " passes");
}

void GpuVolume::growMeshHeaps(uint32_t vertexCapacity, uint32_t chunkCapacity) {
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
    Counters k{};
    vk::downloadFromBuffer(context_, counters_, &k, sizeof(k));
    // The free stacks (entries [0, top) are free indices, popped from the top): the new indices go UNDER the
    // old entries, highest first, so that holes and old indices are reused before any new one and new ones are
    // handed out in ascending order. That keeps every live vertex below the high water, which
    // update_heap_vertices relies on.
    auto growStack = [&](vk::Buffer& stack, uint32_t top, uint32_t oldCapacity, uint32_t newCapacity, const char* name, uint32_t binding) {
        const uint32_t added = newCapacity - oldCapacity;
        std::vector<uint32_t> entries(top + added);
        for (uint32_t i = 0; i < added; ++i) entries[i] = newCapacity - 1 - i;
        if (top) vk::downloadFromBuffer(context_, stack, entries.data() + added, VkDeviceSize(top) * 4);
        stack = makeBuffer(VkDeviceSize(newCapacity) * 4, 0, name, binding);
        vk::uploadToBuffer(context_, stack, entries.data(), VkDeviceSize(entries.size()) * 4);
    };
    // Heap contents are copied on the GPU; the old buffers live until the copy is done.
    std::vector<vk::Buffer> old;
    VkCommandBuffer cmd = recorder_.begin();
    auto growCopy = [&](vk::Buffer& buffer, VkDeviceSize newSize, const char* name, uint32_t binding) {
        old.push_back(std::move(buffer));
        buffer = makeBuffer(newSize, 0, name, binding);
        VkBufferCopy region{0, 0, old.back().size()};
        vkCmdCopyBuffer(cmd, old.back().handle(), buffer.handle(), 1, &region);
        return old.back().size();
    };
    if (vertexCapacity > oldVertices) {
        VkDeviceSize kept = growCopy(vertices_, VkDeviceSize(vertexCapacity) * sizeof(Vertex), "vertex heap", BINDING_VERTICES);
        vkCmdFillBuffer(cmd, vertices_.handle(), kept, VK_WHOLE_SIZE, 0xFFFFFFFFu);   // new entries: refcount DEAD
        growCopy(vertexOwner_, VkDeviceSize(vertexCapacity) * 4, "vertex owners", BINDING_VERTEX_OWNER);
        vertexRemap_ = makeBuffer(VkDeviceSize(vertexCapacity) * 4, 0, "vertex remap", BINDING_VERTEX_REMAP);
    }
    if (chunkCapacity > oldChunks) {
        VkDeviceSize kept = growCopy(chunkTriangles_, VkDeviceSize(chunkCapacity) * CHUNK_WORDS * 4, "triangle chunks", BINDING_CHUNK_TRIANGLES);
        vkCmdFillBuffer(cmd, chunkTriangles_.handle(), kept, VK_WHOLE_SIZE, INVALID_INDEX);   // new chunks: no triangle
    }
    garbage_ = makeBuffer((VkDeviceSize(vertexCapacity) + chunkCapacity) * 4, 0, "garbage lists", BINDING_GARBAGE);
    if (deltaLayout_) {
        // The delta passes read the heaps through their own set, and their shadows grow with the heaps
        // (new entries: dead vertices, empty triangle slots, as the heaps' new entries are).
        auto growShadow = [&](vk::Buffer& shadow, VkDeviceSize newSize, uint32_t fill, const char* name, uint32_t binding) {
            old.push_back(std::move(shadow));
            shadow = vk::Buffer(context_, newSize, kStorage, vk::MemoryUse::Device, name);
            deltaLayout_->bind(binding, shadow);
            VkBufferCopy region{0, 0, old.back().size()};
            vkCmdCopyBuffer(cmd, old.back().handle(), shadow.handle(), 1, &region);
            vkCmdFillBuffer(cmd, shadow.handle(), old.back().size(), VK_WHOLE_SIZE, fill);
        };
        if (vertexCapacity > oldVertices)
            growShadow(prevVertices_, vertices_.size(), 0xFFFFFFFFu, "vertex heap shadow", DELTA_BINDING_PREV_VERTICES);
        if (chunkCapacity > oldChunks)
            growShadow(prevChunks_, chunkTriangles_.size(), INVALID_INDEX, "triangle chunk shadow", DELTA_BINDING_PREV_CHUNKS);
        deltaLayout_->bind(DELTA_BINDING_VERTICES, vertices_);
        deltaLayout_->bind(DELTA_BINDING_CHUNKS, chunkTriangles_);
    }
    vk::memoryBarrier(cmd);
    recorder_.submitAndWait();
    old.clear();
    if (vertexCapacity > oldVertices) growStack(vertexFree_, k.vertexFreeTop, oldVertices, vertexCapacity, "vertex free stack", BINDING_VERTEX_FREE);
    if (chunkCapacity > oldChunks) growStack(chunkFree_, k.chunkFreeTop, oldChunks, chunkCapacity, "chunk free stack", BINDING_CHUNK_FREE);
    k.vertexFreeTop += vertexCapacity - oldVertices;
    k.chunkFreeTop += chunkCapacity - oldChunks;
    vk::uploadToBuffer(context_, counters_, &k, sizeof(k));
    config_.vertexCapacity = vertexCapacity;
    config_.chunkCapacity = chunkCapacity;
    setParam(&VolumeParamsGpu::vertexCapacity, vertexCapacity);
    setParam(&VolumeParamsGpu::chunkCapacity, chunkCapacity);
    VkCommandBuffer readback = recorder_.begin();
    recordCountersReadback(readback);
    recorder_.submitAndWait();
    retryPending_ = true;
}

MeshStateSnapshot GpuVolume::downloadMeshState() const {
    const GpuVolumeConfig& c = config_;
    MeshStateSnapshot s;
    s.counters = readCounters();
    s.vertices.resize(c.vertexCapacity);
    vk::downloadFromBuffer(context_, vertices_, s.vertices.data(), s.vertices.size() * sizeof(Vertex));
    s.vertexOwner.resize(c.vertexCapacity);
    vk::downloadFromBuffer(context_, vertexOwner_, s.vertexOwner.data(), s.vertexOwner.size() * 4);
    const size_t cubes = size_t(c.blockCapacity) * VOXELS_PER_BLOCK;
    s.edgeVertex.resize(cubes * 3);
    std::vector<uint32_t> axis(cubes);
    const vk::Buffer* axes[3] = {&edgeVertexX_, &edgeVertexY_, &edgeVertexZ_};
    for (int a = 0; a < 3; ++a) {
        vk::downloadFromBuffer(context_, *axes[a], axis.data(), cubes * 4);
        for (size_t i = 0; i < cubes; ++i) s.edgeVertex[i * 3 + a] = axis[i];
    }
    std::vector<uint32_t> state(size_t(c.blockCapacity) * VOXELS_PER_BLOCK), chunks(size_t(c.chunkCapacity) * CHUNK_WORDS);
    vk::downloadFromBuffer(context_, cubeState_, state.data(), state.size() * 4);
    vk::downloadFromBuffer(context_, chunkTriangles_, chunks.data(), chunks.size() * 4);
    const MarchingCubesTables& tables = marchingCubesTables();
    for (uint32_t st : state) {
        uint32_t chunk = st >> CUBE_CHUNK_SHIFT;
        if (!chunk) continue;
        for (uint32_t t = 0; t < tables.triangleCount[st & CUBE_TYPE_MASK]; ++t) {
            const uint32_t* tri = &chunks[size_t(chunk - 1) * CHUNK_WORDS + 3 * t];
            if (tri[0] != INVALID_INDEX) s.liveTriangles.push_back({tri[0], tri[1], tri[2]});
        }
    }
    return s;
}

std::array<uint64_t, 256> GpuVolume::surfaceCubeTypes() const {
    std::vector<uint32_t> state(size_t(config_.blockCapacity) * VOXELS_PER_BLOCK);
    vk::downloadFromBuffer(context_, cubeState_, state.data(), state.size() * 4);
    std::array<uint64_t, 256> histogram{};
    for (uint32_t st : state)
        if ((st >> CUBE_CHUNK_SHIFT) != 0) ++histogram[st & CUBE_TYPE_MASK];
    return histogram;
}

Counters GpuVolume::readCounters() const {
    Counters k{};
    countersReadback_.invalidate();
    std::memcpy(&k, countersReadback_.mapped(), sizeof(k));
    return k;
}

std::vector<BlockSnapshot> GpuVolume::downloadBlocks() const {
    const GpuVolumeConfig& c = config_;
    std::vector<float> sdf(size_t(c.blockCapacity) * VOXELS_PER_BLOCK), weight(sdf.size());
    vk::downloadFromBuffer(context_, voxelSdf_, sdf.data(), sdf.size() * 4);
    vk::downloadFromBuffer(context_, voxelWeight_, weight.data(), weight.size() * 4);
    std::vector<int32_t> coords(size_t(c.blockCapacity) * 4);
    vk::downloadFromBuffer(context_, blockCoords_, coords.data(), coords.size() * 4);

    std::vector<BlockSnapshot> out;
    for (const BlockHash::Entry& e : hash_.downloadEntries()) {
        if (e.block == NO_BLOCK) continue;
        uint32_t b = e.block;
        BlockSnapshot snap;
        snap.coord = Eigen::Vector3i(coords[4 * b], coords[4 * b + 1], coords[4 * b + 2]);
        snap.index = b;
        snap.sdf.assign(sdf.begin() + size_t(b) * VOXELS_PER_BLOCK, sdf.begin() + size_t(b + 1) * VOXELS_PER_BLOCK);
        snap.weight.assign(weight.begin() + size_t(b) * VOXELS_PER_BLOCK, weight.begin() + size_t(b + 1) * VOXELS_PER_BLOCK);
        out.push_back(std::move(snap));
    }
    return out;
}

void GpuVolume::growHash(uint32_t hashCapacity) {
    const uint32_t lost = hash_.grow(hashCapacity, params_, counters_, lastPush_, config_.blockCapacity, [&](VkCommandBuffer cmd) {
        vkCmdFillBuffer(cmd, counters_.handle(), offsetof(Counters, liveBlockCount), sizeof(uint32_t), 0);
        vk::memoryBarrier(cmd);
        baselineMesh_.recordCollect(cmd, lastPush_, config_.hashCapacity);
    });
    config_.hashCapacity = hash_.capacity();
    // readCounters() reads the host copy: hashEntries and hashTombstones changed.
    VkCommandBuffer readback = recorder_.begin();
    recordCountersReadback(readback);
    recorder_.submitAndWait();
    if (lost)
        throw Error("hash growth to " + std::to_string(hashCapacity) + " slots could not re-insert " + std::to_string(lost) +
                    " live blocks within " + std::to_string(HASH_MAX_PROBES) + " probes");
}

std::vector<PoolInfo> GpuVolume::pools() const {
    std::vector<PoolInfo> out;
    for (const vk::Buffer* b : hash_.buffers()) out.push_back({b->name(), size_t(b->size())});
    for (const vk::Buffer* b : {&params_, &counters_, &blockCoords_, &voxelSdf_,
                                &voxelWeight_, &freeList_, &touched_, &depth_, &mcTables_, &blockList_, &meshVertices_,
                                &cubeState_, &edgeVertexX_, &edgeVertexY_, &edgeVertexZ_, &meshStamps_, &dirtyList_, &vertices_, &vertexOwner_, &vertexFree_, &garbage_,
                                &chunkTriangles_, &chunkFree_, &exportVertices_, &exportIndices_, &vertexRemap_,
                                &retypeMask_, &retypeList_,
                                &depthStaging_, &countersReadback_, &prevVertices_, &prevChunks_, &deltaState_,
                                &deltaVertexRecords_, &deltaTriangleRecords_, &deltaStateReadback_})
        if (b->handle()) out.push_back({b->name(), size_t(b->size())});
    return out;
}

}  // namespace vkmesh::gpu
