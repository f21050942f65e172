// GpuVolume's frame (docs/ARCHITECTURE.md): recording one frame's passes into one command buffer, the input
// copies for images already in GPU memory, and the submit / finish pair that the blocking integrate() and the
// asynchronous form (Reconstructor::integrateAsync) share, with the re-run of a deferred frame.
#include "gpu/gpu_volume.h"

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/camera.h"
#include "gpu/capacities.h"
#include "vk/check.h"

namespace vkmesh::gpu {
namespace {

// A frame deferred this many times (growing each time) runs the last time without deferral: what still
// does not fit (a device limit reached) is reported and skipped.
constexpr int kMaxDeferrals = 4;

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

void GpuVolume::recordFrame(VkCommandBuffer cmd, const FramePush& push, bool rebuildHash, bool retryPending, bool copyInput) {
    const bool incremental = config_.meshMode == MeshMode::Incremental;
    const bool recycling = this->recycling();
    // Pass                          reads                                     writes
    // (host)   depth upload         staging                                   depth image; per-frame counters cleared
    // pose     (host) or recordPose  [camera tracking: depth, mesh]             frame pose (skip: every pass below idles)
    // rehash   (tombstones > 1/8)   block list, hash                          hash (no tombstones), block coords.w
    // allocate allocate_tiles       depth, hash                               hash keys, stamps, touched list, tiles,
    //                                                                         assign/block dispatch
    //          allocate_blocks      depth, hash, tiles                        the same but tiles
    //          assign_blocks        touched list, free list, hash             hash values, block coords, touched list
    //          commit_allocation    allocRequests, overflow counts            free list top, pool counts; deferral:
    //                                                                         frameDeferred, emptied dispatches
    // fuse     fuse_depth           touched list, depth, block coords         TSDF, retype masks
    // mesh     mark_dirty           touched list, hash                        dirty list, mesh stamps
    //          (block list)         hash                                      live-block list  [recycling, pending]
    //          mark_pending_dirty   block list, retype masks                  dirty list       [after heap growth]
    // recycle  recycle_retire       block list, hash stamps                   weights, retype masks
    //          retype stage         dirty list, retype masks, hash            retype list, block neighbours
    //          claim stage          retype list, TSDF, neighbours, cube state edge slots, vertex heap
    //          update stage         TSDF, edge slots, dirty list, neighbours  moved list, vertex positions, normals
    //          triangulate stage    retype list, TSDF, edge slots, neighbours cube state, chunks, garbage lists
    //          mesh GC stage        garbage lists                             free stacks, edge slots
    // recycle  recycle_free         block list, TSDF, cube state, edge slots  hash (tombstones), free list
    //                               (de-integration: the touched list instead of the block list)
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
    recordFramePose(cmd, push, copyInput);
    timer_.mark(cmd, "start");
    if (rebuildHash) {
        recordRebuildHash(cmd, push);
        timer_.mark(cmd, "rehash");
    }
    allocate_.record(cmd, push, counters_.buffer(), uint32_t(config_.params.allocationStride), config_.params.allocationTiles,
                     inFlight_->input.deintegrate);
    timer_.mark(cmd, "allocate");
    fuse_.record(cmd, push, counters_, inFlight_->input.deintegrate);
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
    } else if (inFlight_->input.deintegrate) {
        // The blocks the de-integration left with no observation, freed with the mesh state the passes released.
        recycle_.recordFree(cmd, push, counters_, true);
        timer_.mark(cmd, "recycle_free");
    }
    if (inFlight_->input.intermediate) return;
    if (config_.publishMesh) {
        recordExport(cmd);
        timer_.mark(cmd, "export");
    }
    if (deltas_) {
        deltas_->record(cmd);
        timer_.mark(cmd, "deltas");
    }
}

void GpuVolume::recordFramePose(VkCommandBuffer cmd, const FramePush& push, bool firstAttempt) {
    if (inFlight_->input.recordPose) {
        // A deferred frame's re-run finds the pose the first attempt computed (and never a skip: a skipped
        // frame allocates nothing, so it cannot overflow).
        if (!firstAttempt) return;
        inFlight_->input.recordPose(cmd, framePose_);
        // Whatever the pose's passes did (draws included) comes before this frame's passes.
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                             0, 0, nullptr, 0, nullptr, 0, nullptr);
        vk::memoryBarrier(cmd);
        return;
    }
    FramePoseGpu pose{};
    std::memcpy(pose.worldToCamera, push.worldToCamera, sizeof(pose.worldToCamera));
    std::memcpy(pose.cameraToWorld, push.cameraToWorld, sizeof(pose.cameraToWorld));
    pose.deintegrate = inFlight_->input.deintegrate ? 1u : 0u;
    vkCmdUpdateBuffer(cmd, framePose_.handle(), 0, sizeof(pose), &pose);
    vk::memoryBarrier(cmd);
}

void GpuVolume::recordInputCopy(VkCommandBuffer cmd, bool withColor) {
    const VkDeviceSize pixelBytes = VkDeviceSize(config_.imageWidth) * config_.imageHeight * 4;
    const FrameInput& in = inFlight_->input;
    if (!inFlight_->fromGpu) {
        if (!depthStaging_.handle()) return;   // the host wrote depth_ itself (unified memory)
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
    FrameInput input = FrameInput::fromHost(depth, color, intrinsics, cameraToWorld);
    input.sync = sync;
    submitFrame(input);
    return finishFrame();
}

FrameReport GpuVolume::deintegrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                   const Pose& cameraToWorld) {
    FrameInput input = FrameInput::fromHost(depth, color, intrinsics, cameraToWorld);
    input.deintegrate = true;
    submitFrame(input);
    return finishFrame();
}

namespace {

std::string sizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

// A colour image's RGB8 pixels as the RGBA8 words fusion reads after the depth samples; alpha 255: every pixel of
// the image has a colour. On the host between a frame's submissions, so its time is the frame's: on a
// little-endian host 4 pixels are read as 3 words (half the time of the byte loop, ~0.1 ms a 640 x 480 frame).
void packRgba(const uint8_t* rgb, uint32_t* words, size_t pixels) {
    size_t i = 0;
    if constexpr (std::endian::native == std::endian::little) {
        for (; i + 4 <= pixels; i += 4) {
            uint32_t a, b, c;   // bytes r0 g0 b0 r1 | g1 b1 r2 g2 | b2 r3 g3 b3
            std::memcpy(&a, rgb + 3 * i, 4);
            std::memcpy(&b, rgb + 3 * i + 4, 4);
            std::memcpy(&c, rgb + 3 * i + 8, 4);
            words[i] = a | 0xFF000000u;
            words[i + 1] = a >> 24 | b << 8 | 0xFF000000u;
            words[i + 2] = b >> 16 | c << 16 | 0xFF000000u;
            words[i + 3] = c >> 8 | 0xFF000000u;
        }
    }
    for (; i < pixels; ++i)
        words[i] = uint32_t(rgb[3 * i]) | uint32_t(rgb[3 * i + 1]) << 8 | uint32_t(rgb[3 * i + 2]) << 16 | 0xFF000000u;
}

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
    if (input.deintegrate && recycling())
        throw Error("a bounded map (keep radius or recycling) forgets what it fused, so a frame cannot be taken out of it exactly; "
                    "correct maps built without --keep-radius and --recycle");
    if (input.deintegrate && input.recordPose) throw Error("a frame to de-integrate comes with the pose it was fused at, not a tracker's");
    if (paging() && input.recordPose)
        throw Error("paging (resident blocks) brings back what a frame's pose reaches before the frame: the pose must be the host's, "
                    "not computed in the frame's submission (PoseTracker::track, then integrate)");
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
        std::memcpy(hostInput(), depth.meters.data(), depth.meters.size() * sizeof(float));
        if (frame.withColor)
            packRgba(color->rgb.data(), static_cast<uint32_t*>(hostInput()) + depth.meters.size(), depth.meters.size());
    }
    frame.input = input;
    frame.input.depth = nullptr;   // the host images are in the staging buffer (or depth_) now
    frame.input.color = nullptr;
    frame.timelineValue = timelineValue;

    if (paging()) pageIn(input.cameraToWorld, input.intrinsics, frame.report);
    if (config_.growCapacities && framesIntegrated_ > 0) growBeforeFrame(frame.report);
    if (config_.publishMesh && !input.intermediate) {
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
    // (Recycling and de-integration free blocks.)
    frame.rebuildHash = double(counters_.read().hashTombstones) >
                                           double(config_.hashRebuildTombstoneFraction) * config_.hashCapacity;
    frame.retryPending = config_.meshMode == MeshMode::Incremental && retryPending_;
    if (frame.rebuildHash && input.recordPose) {
        // The frame may yet be skipped on the GPU, and a skipped frame must leave the map bit-identical: the
        // rebuild (which reorders the table) gets a submission of its own before it.
        VkCommandBuffer cmd = beginSubmission();
        recordRebuildHash(cmd, lastPush_);
        counters_.recordReadback(cmd);
        recorder_.submitAndWait();
        frame.rebuildHash = false;
    }
    frame.previousPush = lastPush_;
    if (input.recordPose) frame.previousCounters = counters_.read();
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
    const uint64_t dispatchesBefore = table_.dispatchesRecorded();
    recordingFrame_ = true;
    recordFrame(cmd, push, f.rebuildHash && f.attempt == 0, f.retryPending, f.attempt == 0);
    recordingFrame_ = false;
    f.report.dispatches = uint32_t(table_.dispatchesRecorded() - dispatchesBefore);
    counters_.recordReadback(cmd);
    if (f.input.recordPose) {
        // Whether the GPU skipped the frame, for finishFrame(); then the flag is cleared, so that passes between
        // frames (re-meshing pending cubes before an export) do not read it. The pose stays for a re-run.
        VkBufferCopy region{0, 0, sizeof(FramePoseGpu)};
        vkCmdCopyBuffer(cmd, framePose_.handle(), framePoseReadback_.handle(), 1, &region);
        vk::memoryBarrier(cmd);
        vkCmdFillBuffer(cmd, framePose_.handle(), offsetof(FramePoseGpu, skip), sizeof(uint32_t), 0);
        vk::memoryBarrier(cmd);
    }
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
    FramePoseGpu pose{};
    if (inFlight_->input.recordPose) {
        framePoseReadback_.invalidate();
        std::memcpy(&pose, framePoseReadback_.mapped(), sizeof(pose));
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
    if (pose.skip) {
        // Tracking lost the frame in its own submission: nothing ran that changes the map (no allocation, so
        // no deferral either). It is not counted: the next frame gets this frame's number, as if it had never
        // been submitted, which keeps the map bit-identical to skipping the frame on the host.
        --frameNumber_;
        lastPush_ = f.previousPush;
        // The frame cleared the per-frame counters (before the GPU decided); a map keeps the last frame's.
        counters_.replace(f.previousCounters);
        report.skipped = true;
        report.counters = k;
        report.stageMs = timer_.read();
        report.passMs = timer_.readPasses();
        if (deltas_) {
            report.delta = deltas_->collect(recorder_);
            report.delta.frame = frameNumber_;
        }
        return report;
    }
    if (!f.input.deintegrate) ++framesIntegrated_;
    report.stageMs = timer_.read();
    report.passMs = timer_.readPasses();
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
            completion.push_back(runMeshCompletion(f.timelineValue == 0 && !f.input.intermediate, !f.input.intermediate));
            last = completion.back();
        }
        if (f.timelineValue && !completion.empty())
            report.warnings.push_back("frame " + std::to_string(frameNumber_) + ": a mesh heap ran out; the frame's published mesh " +
                                      "lacks the cubes meshed after the heap grew, the next frame's has them");
        if (!last.meshPending) growMeshAfterFrame(last, report);   // a retype list that overflowed without pending work
    }
    report.counters = mergedCounters(k, completion);
    if (paging()) {
        pageOutToBudget(f.input.cameraToWorld, f.input.intrinsics, report);
        finishPagingReport(report);   // with what came back for it before (pageInView, submitFrame)
    }
    if (f.input.intermediate) {
        warnAboutCapacities(report.counters, report);
        return report;
    }
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

FrameReport GpuVolume::publishMesh() {
    if (inFlight_) throw Error("publishMesh: a frame is in flight (finishFrame first)");
    FrameReport report;
    if (config_.publishMesh) {
        if (exportMesh_->selected() != 0) exportMesh_->select(0, params_);
        const Counters last = counters_.read();
        exportMesh_->ensureCapacity(last.verticesInUse, last.liveTriangles, params_);
    }
    VkCommandBuffer cmd = beginSubmission();
    if (config_.publishMesh) recordExport(cmd);
    if (deltas_) deltas_->record(cmd);
    counters_.recordReadback(cmd);
    recorder_.submitAndWait();
    report.counters = counters_.read();
    if (config_.publishMesh) {
        meshPublished_ = true;
        if (!exportMesh_->fits(report.counters)) report.counters = runExport(nullptr);
    }
    if (deltas_) {
        report.delta = deltas_->collect(recorder_);
        report.delta.frame = frameNumber_;
    }
    return report;
}

const vk::TimelineSemaphore& GpuVolume::timeline() {
    if (!timeline_) timeline_ = std::make_unique<vk::TimelineSemaphore>(context_);
    return *timeline_;
}

}  // namespace vkmesh::gpu
