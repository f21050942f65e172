#include "gpu/gpu_volume.h"

#include "gpu/capacities.h"

#include <algorithm>
#include <cstring>

#include "core/camera.h"
#include "core/marching_cubes.h"
#include "vk/check.h"

namespace vkmesh::gpu {
namespace {


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
    if (p.colorFusion != ColorFusion::Off && p.colorFusion != ColorFusion::Average && p.colorFusion != ColorFusion::Recent)
        throw Error("colour fusion mode " + std::to_string(uint32_t(p.colorFusion)) + " is not one of off, average, recent");
    if (!(p.colorRecency > 0.0f && p.colorRecency <= 1.0f))
        throw Error("colour recency " + std::to_string(p.colorRecency) + " must be in (0, 1]");
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

// The resolved configuration, checked against the device before any buffer is created.
GpuVolumeConfig checkedFor(const vk::Context& context, const GpuVolumeConfig& config) {
    GpuVolumeConfig c = resolved(config);
    checkCapacities(c, context.maxStorageBufferRange(), deviceLocalHeapBytes(context), context.info().name,
                    BlockHash::keyBytesPerSlot(context.int64Atomics()));
    return c;
}

// The optional shader code the volume's pipelines keep: colour and refinement are fixed at creation.
uint32_t compiledFeatures(const GpuVolumeConfig& c) {
    return (c.params.colorFusion != ColorFusion::Off ? VOLUME_FEATURE_COLOR : 0u) | (c.refine ? VOLUME_FEATURE_REFINE : 0u);
}

VolumeParamsGpu initialParams(const GpuVolumeConfig& c) {
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
    gp.retypeCapacity = c.retypeCapacity;
    gp.incrementalMesh = c.meshMode == MeshMode::Incremental ? 1u : 0u;
    gp.refine = c.refine ? 1u : 0u;
    gp.refineEpsilon = c.refineEpsilonVoxels * c.params.voxelSize;
    gp.vertexUpdate = c.vertexUpdate;
    gp.keepRadius = c.keepRadius;
    gp.starveAfterFrames = c.recycle ? c.recycleAfterFrames : 0u;
    gp.starveWeight = c.starveWeight;
    gp.deferOnOverflow = c.growCapacities ? 1u : 0u;
    gp.colorMode = uint32_t(c.params.colorFusion);
    gp.colorRecency = c.params.colorRecency;
    return gp;   // the export capacities are set by ExportMeshStage
}


// A frame deferred this many times (growing each time) runs the last time without deferral: what still
// does not fit (a device limit reached) is reported and skipped.
constexpr int kMaxDeferrals = 4;
// Follow-up mesh passes after a frame whose mesh passes ran out of a heap or the retype list.
constexpr int kMaxMeshCompletions = 4;

// The counters of a frame whose mesh was completed by follow-up passes: the frame's own counts, the state
// (everything persistent) as the last pass left it, what ran out as the last pass saw it, and the mesh work
// of all passes added up.
Counters mergedCounters(const Counters& frame, const std::vector<Counters>& passes) {
    if (passes.empty()) return frame;
    Counters k = frame;
    const Counters& last = passes.back();
    std::memcpy(reinterpret_cast<char*>(&k) + offsetof(Counters, freeTop), reinterpret_cast<const char*>(&last) + offsetof(Counters, freeTop),
                sizeof(Counters) - offsetof(Counters, freeTop));
    k.vertexExhausted = last.vertexExhausted;
    k.chunkExhausted = last.chunkExhausted;
    k.trianglesInvalid = last.trianglesInvalid;
    k.retypeDeferred = last.retypeDeferred;
    k.meshPending = last.meshPending;
    for (const Counters& p : passes) {
        k.cubesRetyped += p.cubesRetyped;
        k.vertexAllocRequests += p.vertexAllocRequests;
        k.chunkAllocRequests += p.chunkAllocRequests;
        k.trianglesCreated += p.trianglesCreated;
        k.trianglesReleased += p.trianglesReleased;
        k.vertexPushes += p.vertexPushes;
        k.chunkPushes += p.chunkPushes;
        k.retypeCount += p.retypeCount;
    }
    return k;
}

}  // namespace

GpuVolumeConfig resolveConfig(const GpuVolumeConfig& config) { return resolved(config); }

GpuVolume::GpuVolume(const vk::Context& context, const GpuVolumeConfig& config)
    : context_(context),
      config_(checkedFor(context, config)),
      table_(context, sizeof(FramePush), compiledFeatures(config_)),
      counters_(context, table_),
      params_(context, table_, initialParams(config_)),
      hash_(context, table_, config_.hashCapacity),
      store_(context, table_, config_.blockCapacity, counters_, config_.params.colorFusion != ColorFusion::Off),
      mesh_(context, table_, config_.blockCapacity, config_.vertexCapacity, config_.chunkCapacity, counters_),
      lists_(context, table_, listCapacities(config_)),
      allocate_(context, table_),
      deferFrame_(context, table_, "defer_frame"),
      fuse_(context, table_),
      blockList_(context, table_),
      baselineMesh_(context, table_, params_),
      markDirty_(context, table_),
      retype_(context, table_),
      claim_(context, table_),
      updateVertices_(context, table_),
      triangulate_(context, table_),
      meshGc_(context, table_),
      recycle_(context, table_),
      recorder_(context),
      timer_(context) {
    const GpuVolumeConfig& c = config_;
    touchedFollowsPool_ = config.touchedCapacity == 0;
    // The depth image, then (when colour is fused) the colour image's RGBA8 words: one binding for both.
    const VkDeviceSize pixels = VkDeviceSize(c.imageWidth) * c.imageHeight;
    depth_ = makeStorage(context, table_, BINDING_DEPTH, pixels * 4 * (fusesColor() ? 2 : 1), "depth image");   // name kept: a --stats key
    depthStaging_ = vk::Buffer(context, depth_.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::Upload, "depth staging");
    mcTables_ = vk::Buffer(context, MC_TABLE_WORDS * 4, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, vk::MemoryUse::Device, "marching cubes tables");
    table_.bind(BINDING_MC_TABLES, mcTables_);
    const auto tables = packMarchingCubesTables();
    vk::uploadToBuffer(context, mcTables_, tables.data(), tables.size() * 4);
    exportMesh_.emplace(context, table_, params_);
    if (c.trackDeltas) deltas_.emplace(context, counters_, mesh_, c.deltaRecordCapacity);
    VkCommandBuffer cmd = beginSubmission();
    counters_.recordReadback(cmd);
    recorder_.submitAndWait();
}

GpuVolume::~GpuVolume() { recorder_.wait(); }

VkCommandBuffer GpuVolume::beginSubmission() {
    VkCommandBuffer cmd = recorder_.begin();
    params_.recordUpload(cmd);
    return cmd;
}

// ---- the block hash -------------------------------------------------------------------------------

void GpuVolume::recordRebuildHash(VkCommandBuffer cmd, const FramePush& push) {
    blockList_.record(cmd, push, counters_, config_.hashCapacity);
    hash_.recordRebuild(cmd, push, config_.blockCapacity);
}

// ---- the frame ------------------------------------------------------------------------------------

void GpuVolume::recordFrame(VkCommandBuffer cmd, const FramePush& push, bool rebuildHash, bool retryPending, bool copyInput) {
    const bool incremental = config_.meshMode == MeshMode::Incremental;
    const bool recycling = this->recycling();
    // Pass                          reads                                     writes
    // (host)   depth upload         staging                                   depth image; per-frame counters cleared
    // rehash   (tombstones > 1/8)   block list, hash                          hash (no tombstones), block coords.w
    // allocate allocate_blocks      depth, hash                               hash keys, stamps, touched list
    //          plan_frame           touchedCount                              assign/block dispatch
    //          assign_blocks        touched list, free list, hash             hash values, block coords, touched list
    //          commit_allocation    allocRequests                             free list top, pool counts
    //          defer_frame          overflow counts                           frameDeferred, emptied dispatches
    // fuse     fuse_depth           touched list, depth, block coords         TSDF, retype masks
    // mesh     mark_dirty           touched list, hash                        dirty list, mesh stamps
    //          (block list)         hash                                      live-block list  [recycling, pending]
    //          mark_pending_dirty   block list, retype masks                  dirty list       [after heap growth]
    // recycle  recycle_retire       block list, hash stamps                   weights, retype masks
    //          retype stage         dirty list, retype masks                  retype list
    //          claim stage          retype list, TSDF, hash, cube state       edge slots, vertex heap
    //          update stage         TSDF, edge slots, dirty list              vertex positions, normals
    //          triangulate stage    retype list, TSDF, edge slots             cube state, chunks, garbage lists
    //          mesh GC stage        garbage lists                             free stacks, edge slots
    // recycle  recycle_free         block list, TSDF, cube state, edge slots  hash (tombstones), free list
    // export   export stage         vertex heap, chunks                       export buffers, draw command
    // deltas   delta stage          vertex heap, chunks, shadows              records, shadows
    // Every pass reads what the one before wrote (at least the counters its dispatch size comes from), so
    // each is followed by a full compute/transfer barrier (vk::memoryBarrier, inside the stages).
    // An execution dependency on everything submitted before (an application's draws reading the last
    // frame's mesh buffers on this queue): this frame overwrites them.
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                         0, 0, nullptr, 0, nullptr, 0, nullptr);
    params_.recordUpload(cmd);   // what grew since the last submission
    if (copyInput) recordInputCopy(cmd, (push.imageSize & FRAME_HAS_COLOR) != 0);
    counters_.recordClearFrame(cmd);
    timer_.mark(cmd, "start");
    if (rebuildHash) {
        recordRebuildHash(cmd, push);
        timer_.mark(cmd, "rehash");
    }
    allocate_.record(cmd, push, counters_.buffer(), uint32_t(config_.params.allocationStride));
    deferFrame_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    timer_.mark(cmd, "allocate");
    fuse_.record(cmd, push, counters_);
    timer_.mark(cmd, "fuse");
    if (incremental) {
        markDirty_.recordTouched(cmd, push, counters_);
        timer_.mark(cmd, "mesh_mark");
    }
    if (recycling || retryPending) blockList_.record(cmd, push, counters_, config_.hashCapacity);
    if (retryPending) markDirty_.recordPending(cmd, push, config_.blockCapacity);
    if (recycling) {
        recycle_.recordRetire(cmd, push, counters_);
        timer_.mark(cmd, "recycle_retire");
    }
    if (incremental) recordMeshPasses(cmd, push, &timer_);
    if (recycling) {
        // The live block list is still the one collected above: the mesh passes do not touch the hash.
        recycle_.recordFree(cmd, push, counters_);
        timer_.mark(cmd, "recycle_free");
    }
    if (config_.publishMesh) {
        recordExport(cmd);
        timer_.mark(cmd, "export");
    }
    if (deltas_) {
        deltas_->record(cmd);
        timer_.mark(cmd, "deltas");
    }
}

void GpuVolume::recordInputCopy(VkCommandBuffer cmd, bool withColor) {
    const VkDeviceSize pixelBytes = VkDeviceSize(config_.imageWidth) * config_.imageHeight * 4;
    const FrameInput& in = inFlight_->input;
    if (!inFlight_->fromGpu) {
        VkBufferCopy region{0, 0, withColor ? 2 * pixelBytes : pixelBytes};
        vkCmdCopyBuffer(cmd, depthStaging_.handle(), depth_.handle(), 1, &region);
        return;
    }
    // The application's GPU images, straight into the input buffer (depth, then the colour words).
    auto copy = [&](const GpuImageInput& image, VkDeviceSize dstOffset, bool depthAspect) {
        if (image.buffer) {
            VkBufferCopy region{image.offset, dstOffset, pixelBytes};
            vkCmdCopyBuffer(cmd, image.buffer, depth_.handle(), 1, &region);
            return;
        }
        VkBufferImageCopy region{};
        region.bufferOffset = dstOffset;
        region.imageSubresource.aspectMask = depthAspect ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
        region.imageSubresource.layerCount = 1;
        region.imageExtent = {uint32_t(config_.imageWidth), uint32_t(config_.imageHeight), 1};
        vkCmdCopyImageToBuffer(cmd, image.image, image.layout, depth_.handle(), 1, &region);
    };
    copy(in.gpuDepth, 0, in.gpuDepth.format == VK_FORMAT_D32_SFLOAT);
    if (withColor) copy(in.gpuColor, pixelBytes, false);
}

void GpuVolume::recordMeshPasses(VkCommandBuffer cmd, const FramePush& push, vk::StageTimer* timer) {
    auto mark = [&](const char* name) { if (timer) timer->mark(cmd, name); };
    retype_.record(cmd, push, counters_);
    claim_.record(cmd, push, counters_, config_.lockFree);
    mark("mesh_claim");
    updateVertices_.record(cmd, push, counters_);
    mark("mesh_update");
    triangulate_.record(cmd, push, counters_);
    mark("mesh_triangulate");
    meshGc_.record(cmd, push, counters_);
    mark("mesh_gc");
}

FrameReport GpuVolume::integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                 const vk::SubmitSync& sync) {
    return integrate(depth, nullptr, intrinsics, cameraToWorld, sync);
}

FrameReport GpuVolume::integrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                 const Pose& cameraToWorld, const vk::SubmitSync& sync) {
    FrameInput input;
    input.depth = &depth;
    input.color = color;
    input.intrinsics = intrinsics;
    input.cameraToWorld = cameraToWorld;
    input.sync = sync;
    submitFrame(input);
    return finishFrame();
}

namespace {

std::string sizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

// What a GPU image input must be, checked before anything is recorded.
void checkGpuInput(const GpuImageInput& in, bool color) {
    const char* what = color ? "GPU colour input" : "GPU depth input";
    if (in.buffer && in.image) throw Error(std::string(what) + ": give a buffer or an image, not both");
    if (!in.image) return;
    const bool ok = color ? (in.format == VK_FORMAT_R8G8B8A8_UNORM || in.format == VK_FORMAT_R8G8B8A8_SRGB)
                          : (in.format == VK_FORMAT_R32_SFLOAT || in.format == VK_FORMAT_D32_SFLOAT);
    if (!ok)
        throw Error(std::string(what) + ": image format " + std::to_string(int(in.format)) + " is not supported (" +
                    (color ? "R8G8B8A8_UNORM or R8G8B8A8_SRGB" : "R32_SFLOAT or D32_SFLOAT") + ")");
    if (in.layout != VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL && in.layout != VK_IMAGE_LAYOUT_GENERAL)
        throw Error(std::string(what) + ": the image must be in TRANSFER_SRC_OPTIMAL or GENERAL layout");
}

}  // namespace

void GpuVolume::submitFrame(const FrameInput& input, uint64_t timelineValue) {
    if (inFlight_) throw Error("submitFrame: the previous frame has not been finished (finishFrame)");
    const int w = config_.imageWidth, h = config_.imageHeight;
    InFlight frame;
    frame.fromGpu = !input.gpuDepth.empty();
    if (frame.fromGpu == (input.depth != nullptr))
        throw Error("a frame needs exactly one depth image: a host DepthImage or a GPU input");
    if (frame.fromGpu) {
        checkGpuInput(input.gpuDepth, false);
        checkGpuInput(input.gpuColor, true);
        if (input.color) throw Error("a frame with GPU depth takes its colour as a GPU input too");
        if (input.intrinsics.width != w || input.intrinsics.height != h)
            throw Error("intrinsics are for " + sizeText(input.intrinsics.width, input.intrinsics.height) +
                        " images but the volume was created for " + sizeText(w, h) + " (the GPU input's size)");
        frame.withColor = fusesColor() && !input.gpuColor.empty();
    } else {
        const DepthImage& depth = *input.depth;
        if (depth.width != w || depth.height != h || depth.meters.size() != size_t(depth.width) * depth.height)
            throw Error("depth image is " + sizeText(depth.width, depth.height) + " but the volume was created for " + sizeText(w, h));
        if (!input.gpuColor.empty()) throw Error("a frame with a host depth image takes its colour as a host image too");
        if (input.intrinsics.width != w || input.intrinsics.height != h)
            throw Error("intrinsics are for " + sizeText(input.intrinsics.width, input.intrinsics.height) +
                        " images but the depth image is " + sizeText(w, h));
        const ColorImage* color = input.color;
        frame.withColor = fusesColor() && color && !color->empty();
        if (frame.withColor && (color->width != w || color->height != h || color->rgb.size() != size_t(color->width) * color->height * 3))
            throw Error("colour image is " + sizeText(color->width, color->height) + " but the depth image is " + sizeText(w, h) +
                        " (colour must be registered to depth)");
        std::memcpy(depthStaging_.mapped(), depth.meters.data(), depth.meters.size() * sizeof(float));
        if (frame.withColor) {
            // RGBA8 words after the depth samples; alpha 255: every pixel of the image has a colour.
            auto* words = static_cast<uint32_t*>(depthStaging_.mapped()) + depth.meters.size();
            const uint8_t* rgb = color->rgb.data();
            for (size_t i = 0; i < depth.meters.size(); ++i, rgb += 3)
                words[i] = uint32_t(rgb[0]) | uint32_t(rgb[1]) << 8 | uint32_t(rgb[2]) << 16 | 0xFF000000u;
        }
    }
    frame.input = input;
    frame.input.depth = nullptr;   // the host images are in the staging buffer now
    frame.input.color = nullptr;
    frame.timelineValue = timelineValue;

    if (config_.growCapacities && framesIntegrated_ > 0) growBeforeFrame(frame.report);
    if (config_.publishMesh) {
        if (timelineValue) {
            // An asynchronous frame writes the other set (the application may be drawing the last one), sized
            // for the whole heaps: it cannot overflow, so the set holds the whole mesh at the ready value and
            // is never re-exported (which would write buffers the application was told it may draw).
            exportMesh_->select(exportMesh_->selected() ^ 1u, params_);
            exportMesh_->ensureCapacity(config_.vertexCapacity, config_.chunkCapacity * TRIANGLES_PER_CHUNK, params_, false);
            meshPublished_ = true;   // meshBuffers() hands out the set with its ready value
        } else {
            if (exportMesh_->selected() != 0) exportMesh_->select(0, params_);
            // Room for last frame's mesh plus what one frame can plausibly add; a frame that adds more is
            // re-exported in finishFrame() after growing the buffers.
            const Counters last = counters_.read();
            exportMesh_->ensureCapacity(last.verticesInUse + last.verticesInUse / 8 + 4096,
                                        last.liveTriangles + last.liveTriangles / 8 + 8192, params_);
        }
    }
    // Tombstones of freed keys make probes longer and are never reused by insertions: past the threshold
    // (read from the previous frame's counters) the table is rebuilt before this frame allocates.
    frame.rebuildHash = recycling() && double(counters_.read().hashTombstones) >
                                           double(config_.hashRebuildTombstoneFraction) * config_.hashCapacity;
    frame.retryPending = config_.meshMode == MeshMode::Incremental && retryPending_;
    inFlight_ = std::move(frame);
    submitAttempt();
}

void GpuVolume::submitAttempt() {
    InFlight& f = *inFlight_;
    // A frame whose allocation overflows is deferred (nothing fused), the capacities grow, and it runs again
    // under the next frame number. The application's semaphores: waited on by the first submission,
    // signalled by the one that ends the frame (an empty one when deferral was possible). vkmesh's timeline
    // is raised by the first: its mesh buffers then hold a whole mesh (without this frame's depth when it was
    // deferred; a re-run writes the same set again, ordered after the application's reads by contract).
    f.mayDefer = config_.growCapacities && f.attempt < kMaxDeferrals;
    if (params_.values().deferOnOverflow != uint32_t(f.mayDefer)) params_.edit().deferOnOverflow = f.mayDefer ? 1u : 0u;
    FramePush push = makeFramePush(f.input.intrinsics, f.input.cameraToWorld, config_.params, ++frameNumber_);
    if (f.withColor) push.imageSize |= FRAME_HAS_COLOR;
    lastPush_ = push;
    VkCommandBuffer cmd = recorder_.begin();
    timer_.reset(cmd);
    recordFrame(cmd, push, f.rebuildHash && f.attempt == 0, f.retryPending, f.attempt == 0);
    counters_.recordReadback(cmd);
    vk::SubmitSync attemptSync;
    if (f.attempt == 0) {
        attemptSync.wait = f.input.sync.wait;
        attemptSync.waitStages = f.input.sync.waitStages;
        attemptSync.waitValues = f.input.sync.waitValues;
        if (f.timelineValue) {
            // Every signal gets a value once one is a timeline semaphore (binary ones ignore theirs).
            attemptSync.signal.push_back(timeline().handle());
            attemptSync.signalValues.push_back(f.timelineValue);
        }
    }
    if (!f.mayDefer) {
        if (!attemptSync.signalValues.empty() || !f.input.sync.signalValues.empty()) {
            attemptSync.signalValues.resize(attemptSync.signal.size(), 0);
            for (size_t i = 0; i < f.input.sync.signal.size(); ++i)
                attemptSync.signalValues.push_back(i < f.input.sync.signalValues.size() ? f.input.sync.signalValues[i] : 0);
        }
        attemptSync.signal.insert(attemptSync.signal.end(), f.input.sync.signal.begin(), f.input.sync.signal.end());
        f.signalled = true;
    }
    recorder_.submit(attemptSync);
}

FrameReport GpuVolume::finishFrame() {
    if (!inFlight_) throw Error("finishFrame: no frame was submitted");
    Counters k{};
    for (;;) {
        recorder_.wait();
        exportMesh_->releaseRetired();   // the application's draws of the replaced buffers came before this frame
        k = counters_.read();
        if (!k.frameDeferred) break;
        ++inFlight_->report.deferredAttempts;
        growAfterDeferral(k, inFlight_->report);
        ++inFlight_->attempt;
        submitAttempt();
    }
    InFlight f = std::move(*inFlight_);
    inFlight_.reset();
    FrameReport& report = f.report;
    if (!f.signalled && !f.input.sync.signal.empty()) {
        vk::SubmitSync signalOnly;
        signalOnly.signal = f.input.sync.signal;
        signalOnly.signalValues = f.input.sync.signalValues;
        recorder_.begin();
        recorder_.submitAndWait(signalOnly);
    }
    ++framesIntegrated_;
    report.stageMs = timer_.read();
    // Cubes deferred by a full retype list are left for the next frame's retry; INCOMPLETE cubes are retried
    // once after a growth (while the heap stays full they wait for their block to be dirty again).
    if (f.retryPending) retryPending_ = k.retypeDeferred > 0;

    // The mesh passes ran out of a heap or the retype list (meshPending): grow it and re-mesh the cubes left
    // over before the frame is published and its deltas are taken, so the frame's mesh is complete.
    const bool incremental = config_.meshMode == MeshMode::Incremental;
    std::vector<Counters> completion;
    if (incremental && config_.growCapacities) {
        Counters last = k;
        // An asynchronous frame's set is not written again (the application may be drawing it): the cubes
        // completed here reach the next frame's set.
        for (int pass = 0; pass < kMaxMeshCompletions && last.meshPending; ++pass) {
            growMeshAfterFrame(last, report);
            completion.push_back(runMeshCompletion(f.timelineValue == 0, true));
            last = completion.back();
        }
        if (f.timelineValue && !completion.empty())
            report.warnings.push_back("frame " + std::to_string(frameNumber_) + ": a mesh heap ran out; the frame's published mesh " +
                                      "lacks the cubes meshed after the heap grew, the next frame's has them");
        if (!last.meshPending) growMeshAfterFrame(last, report);   // a retype list that overflowed without pending work
    }
    report.counters = mergedCounters(k, completion);
    if (config_.publishMesh) {
        meshPublished_ = true;
        // (An asynchronous frame's set fits by construction.)
        if (!f.timelineValue && !exportMesh_->fits(report.counters))
            report.counters = mergedCounters(k, {runExport(nullptr)});   // grows to the exact counts
    }
    if (deltas_) {
        report.delta = deltas_->collect(recorder_);
        report.delta.frame = frameNumber_;
    }
    warnAboutCapacities(report.counters, report);
    return report;
}

const vk::TimelineSemaphore& GpuVolume::timeline() {
    if (!timeline_) timeline_ = std::make_unique<vk::TimelineSemaphore>(context_);
    return *timeline_;
}

// ---- meshes on demand -----------------------------------------------------------------------------

Counters GpuVolume::runBaselinePass(std::vector<std::pair<std::string, double>>* stageMs) {
    VkCommandBuffer cmd = beginSubmission();
    timer_.reset(cmd);
    timer_.mark(cmd, "start");
    blockList_.record(cmd, lastPush_, counters_, config_.hashCapacity);
    baselineMesh_.record(cmd, lastPush_, counters_);
    timer_.mark(cmd, "mesh_baseline");
    counters_.recordReadback(cmd);
    recorder_.submitAndWait();
    if (stageMs) *stageMs = timer_.read();
    return counters_.read();
}

uint32_t GpuVolume::countBaselineVertices() {
    // The GPU counts every vertex the pass wants, whether or not it fit in the buffer.
    return runBaselinePass(nullptr).meshVertices;
}

TriangleSoup GpuVolume::extractBaselineMesh(std::vector<std::pair<std::string, double>>* stageMs) {
    for (int attempt = 0; attempt < 2; ++attempt) {
        const Counters k = runBaselinePass(stageMs);
        if (k.meshVerticesDropped == 0) {
            TriangleSoup soup;
            soup.vertices.resize(k.meshVertices);
            if (k.meshVertices) {
                std::vector<float> raw(size_t(k.meshVertices) * 4);
                vk::downloadFromBuffer(context_, baselineMesh_.vertices(), raw.data(), raw.size() * 4);
                for (size_t i = 0; i < soup.vertices.size(); ++i)
                    soup.vertices[i] = Eigen::Vector3f(raw[4 * i], raw[4 * i + 1], raw[4 * i + 2]);
            }
            return soup;
        }
        // Too small: grow to exactly what the GPU counted and run the pass again.
        baselineMesh_.ensureCapacity(k.meshVertices, params_);
        config_.meshVertexCapacity = k.meshVertices;
    }
    throw Error("baseline mesh extraction did not fit after growing its buffer");
}

Counters GpuVolume::runExport(std::vector<std::pair<std::string, double>>* stageMs) {
    Counters k = counters_.read();
    uint32_t wantVertices = k.verticesInUse, wantTriangles = k.liveTriangles;
    for (int attempt = 0; attempt < 2; ++attempt) {
        exportMesh_->ensureCapacity(wantVertices, wantTriangles, params_);
        VkCommandBuffer cmd = beginSubmission();
        timer_.reset(cmd);
        timer_.mark(cmd, "start");
        recordExport(cmd);
        timer_.mark(cmd, "export");
        counters_.recordReadback(cmd);
        recorder_.submitAndWait();
        if (stageMs) *stageMs = timer_.read();
        k = counters_.read();
        meshPublished_ = true;
        if (exportMesh_->fits(k)) return k;
        // Cannot happen if the live counts are right; grow to what was counted and retry.
        wantVertices = k.exportVertices;
        wantTriangles = k.exportTriangles;
    }
    throw Error("mesh export did not fit after growing its buffers");
}

Counters GpuVolume::runMeshCompletion(bool publish, bool report) {
    VkCommandBuffer cmd = beginSubmission();
    counters_.recordClearFrame(cmd);
    blockList_.record(cmd, lastPush_, counters_, config_.hashCapacity);
    markDirty_.recordPending(cmd, lastPush_, config_.blockCapacity);
    recordMeshPasses(cmd, lastPush_, nullptr);
    if (publish && config_.publishMesh) recordExport(cmd);
    if (report && deltas_) deltas_->record(cmd);
    counters_.recordReadback(cmd);
    recorder_.submitAndWait();
    retryPending_ = false;
    return counters_.read();
}

void GpuVolume::completePendingMesh() {
    // A few passes: each retypes what fits in the retype list, and a heap that ran out grows in between.
    // Their changes reach the next frame's deltas (the shadows are not updated here).
    for (int pass = 0; pass < kMaxMeshCompletions && retryPending_; ++pass) {
        const Counters k = runMeshCompletion(false, false);
        FrameReport ignored;
        if (config_.growCapacities) growMeshAfterFrame(k, ignored);   // sets retryPending_ again if it grew
        else retryPending_ = k.retypeDeferred > 0;
    }
}

ExportedMesh GpuVolume::exportMesh(std::vector<std::pair<std::string, double>>* stageMs) {
    if (config_.meshMode != MeshMode::Incremental) throw Error("exportMesh needs the incremental mesh mode");
    completePendingMesh();
    const Counters k = runExport(stageMs);
    ExportedMesh out;
    out.unreferencedVertices = k.exportUnreferenced;
    out.vertices.resize(k.exportVertices);
    out.triangles.resize(k.exportTriangles);
    if (k.exportVertices)
        vk::downloadFromBuffer(context_, exportMesh_->vertices(), out.vertices.data(), out.vertices.size() * sizeof(Vertex));
    if (k.exportTriangles)
        vk::downloadFromBuffer(context_, exportMesh_->indices(), out.triangles.data(), out.triangles.size() * 12);
    return out;
}

MeshBuffers GpuVolume::meshBuffers() const {
    MeshBuffers b;
    if (!meshPublished_) return b;
    b.vertices = exportMesh_->vertices().handle();
    b.indices = exportMesh_->indices().handle();
    b.drawIndirect = exportMesh_->drawCommand().handle();
    b.drawIndirectOffset = 0;
    b.frame = frameNumber_;
    if (inFlight_) {
        b.readyValue = inFlight_->timelineValue;   // counts unknown until the frame is finished
        return b;
    }
    const Counters k = counters_.read();
    b.vertexCount = std::min(k.exportVertices, exportMesh_->vertexCapacity());
    b.triangleCount = k.drawIndexed[0] / 3;
    return b;
}

void GpuVolume::rebuildMesh() {
    mesh_.reset(counters_);
    // Every cube of every block is listed for retyping; a pass retypes up to retypeCapacity of them and
    // leaves the rest of the bits set, so passes repeat until none is left.
    VkCommandBuffer cmd = beginSubmission();
    lists_.recordReset(cmd);
    vkCmdFillBuffer(cmd, lists_.retypeMasks().handle(), 0, VK_WHOLE_SIZE, MASK_ALL_CUBES);
    vk::memoryBarrier(cmd);
    recorder_.submitAndWait();
    retryPending_ = false;
    const uint32_t maxPasses = 2 + kMaxMeshCompletions + config_.blockCapacity * VOXELS_PER_BLOCK / config_.retypeCapacity;
    for (uint32_t pass = 0; pass < maxPasses; ++pass) {
        cmd = beginSubmission();
        counters_.recordClearFrame(cmd);
        blockList_.record(cmd, lastPush_, counters_, config_.hashCapacity);
        markDirty_.recordAll(cmd, lastPush_, config_.blockCapacity);
        recordMeshPasses(cmd, lastPush_, nullptr);
        counters_.recordReadback(cmd);
        recorder_.submitAndWait();
        const Counters k = counters_.read();
        if (config_.growCapacities && (k.vertexExhausted || k.chunkExhausted || k.retypeDeferred)) {
            FrameReport ignored;
            growMeshAfterFrame(k, ignored);   // INCOMPLETE cubes set their retype bit again: the next pass takes them
            if (k.vertexExhausted || k.chunkExhausted) continue;
        }
        if (k.retypeDeferred == 0) {
            if (config_.publishMesh) runExport(nullptr);   // the published buffers show the rebuilt mesh
            return;
        }
    }
    throw Error("mesh rebuild did not finish in " + std::to_string(maxPasses) + " passes");
}

// ---- downloads ------------------------------------------------------------------------------------

MeshStateSnapshot GpuVolume::downloadMeshState() const { return mesh_.download(counters_.read()); }

std::array<uint64_t, 256> GpuVolume::surfaceCubeTypes() const { return mesh_.surfaceCubeTypes(); }

std::vector<BlockSnapshot> GpuVolume::downloadBlocks() const {
    std::vector<uint32_t> blocks;
    for (const BlockHash::Entry& e : hash_.downloadEntries())
        if (e.block != NO_BLOCK) blocks.push_back(e.block);
    return store_.download(blocks);
}

std::vector<PoolInfo> GpuVolume::pools() const {
    std::vector<PoolInfo> out;
    params_.pools(out);
    counters_.pools(out);
    hash_.pools(out);
    store_.pools(out);
    mesh_.pools(out);
    lists_.pools(out);
    listPools(out, {&depth_, &depthStaging_, &mcTables_});
    baselineMesh_.pools(out);
    exportMesh_->pools(out);
    if (deltas_) deltas_->pools(out);
    return out;
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

}  // namespace vkmesh::gpu
