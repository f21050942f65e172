// vkmesh's embedding API: one object that fuses depth frames into the TSDF and keeps the persistent
// mesh in GPU buffers that the application draws directly.
//
//   vkmesh::Reconstructor rec(vkmesh::vk::ExternalDevice{instance, physicalDevice, device, queueFamily});
//   for each frame:
//       rec.integrate(depth, intrinsics, cameraToWorld);     // returns when the GPU has finished the frame
//       vkmesh::gpu::MeshBuffers mesh = rec.meshBuffers();    // handles may change from frame to frame
//       // in the application's command buffer, on the same queue family:
//       vkmesh::Reconstructor::recordMeshReadBarrier(cmd);
//       vkCmdBindVertexBuffers(cmd, 0, 1, &mesh.vertices, &zero);      // stride MeshBuffers::kStride
//       vkCmdBindIndexBuffer(cmd, mesh.indices, 0, VK_INDEX_TYPE_UINT32);
//       vkCmdDrawIndexedIndirect(cmd, mesh.drawIndirect, mesh.drawIndirectOffset, 1, 0);
//
// Synchronisation contract (checked by the tests with synchronisation validation on):
//  1. Before the application reads the mesh buffers: integrate() has returned (vkmesh waited for its own
//     submission), and the application's command buffer records recordMeshReadBarrier() before the
//     reads. That barrier covers vkmesh's earlier submissions to the same queue; for another queue of the
//     same family, pass a semaphore in `sync.signal` and wait on it at VK_PIPELINE_STAGE_VERTEX_INPUT_BIT.
//  2. Before the next integrate(): the application's reads of the buffers must be ordered before it:
//     either they were submitted to the same queue earlier (vkmesh's frame starts with an execution
//     barrier after all prior commands), or the application waited for them (fence), or it passes a
//     semaphore its reads signalled in `sync.wait` (with its stage in `sync.waitStages`).
//  3. The buffers belong to vkmesh: never write them; their handles are valid until the next call to
//     integrate(), downloadMesh() or the destructor.
// All calls come from one thread at a time; vkmesh submits to the queue it was given, so the application
// must not submit to that same VkQueue from another thread during a call.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>

#include "api/loop_closure.h"
#include "api/mapper.h"
#include "core/mesh_delta.h"
#include "core/types.h"
#include "core/frame_store.h"
#include "gpu/gpu_volume.h"
#include "gpu/map_corrector.h"
#include "gpu/tracking/pose_tracker.h"
#include "vk/commands.h"
#include "vk/context.h"

namespace vkmesh {

struct ReconstructorOptions {
    // Voxel size, truncation, capacities, ... (GpuVolumeConfig). The image size is taken from the first
    // frame; publishMesh is always on; the mesh mode must be Incremental.
    gpu::GpuVolumeConfig volume;
    // Report each frame's mesh changes (lastDelta(), docs/DELTAS.md).
    bool trackDeltas = false;
    // For the constructor that creates its own Vulkan device: which device, validation layer.
    vk::ContextOptions device;
    // Camera tracking for frames integrated without a pose (docs/TRACKING.md).
    gpu::TrackerOptions tracker;
    // A map that can be corrected (docs/CORRECTION.md): keep what every fused frame fused (depth, colour, pose)
    // in a FrameStore, so that correct() can re-fuse frames whose poses changed. Costs host memory (compressed;
    // docs/RESULTS.md gives the bytes per frame), within frameStore's budget and spill folder.
    bool keepFrames = false;
    FrameStoreOptions frameStore;
    // Queued corrections re-fused by each integrate() before its frame (a de-integration and an integration
    // each); finishCorrections() does all that are left at once.
    uint32_t correctionsPerFrame = 2;
    // Loop closure and relocalisation for frames integrated without a pose (docs/LOOP_CLOSURE.md): an
    // implementation of the LoopClosure interface, slam::LoopCloser from the vkmesh_slam library (which links
    // Ceres; the GPU core does not). Needs keepFrames: the frames a loop moves are re-fused through correct().
    // nullptr (the default): off.
    std::shared_ptr<LoopClosure> loopClosure;
};

// A frame integrated without a pose: the pose tracking found (or predicted, when the frame was lost) and
// what fusing it did (empty when the frame was lost: nothing was fused, the map is as it was).
struct TrackedFrame {
    Pose cameraToWorld = Pose::Identity();
    gpu::TrackingReport tracking;
    std::optional<gpu::FrameReport> fused;
    // With options.loopClosure: tracking lost the frame from its prediction and a keyframe's pose found it again
    // (tracking holds that attempt's report), after this many keyframes were tried (0: not lost);
    bool relocalised = false;
    int relocalisationCandidatesTried = 0;
    // ... and a loop closed at this frame: this many fused frames were queued for correction (their new poses;
    // re-fused correctionsPerFrame per later integrate(), or by finishCorrections()).
    uint32_t loopCorrections = 0;
    bool lost() const { return !fused.has_value(); }
};

// A facade over the library's frame loop (api/mapper.h): every host-image frame goes through Mapper::process, as the
// CLI's do; asynchronous and GPU-image frames are submitted here and recorded with the Mapper.
class Reconstructor {
public:
    // Creates its own Vulkan instance and device (the first suitable device unless options.device says).
    explicit Reconstructor(const ReconstructorOptions& options = {});
    // Runs on the application's instance, device and queue family (see vk::ExternalDevice for the
    // features the device must have enabled). Throws Error naming what is missing.
    explicit Reconstructor(const vk::ExternalDevice& device, const ReconstructorOptions& options = {});
    ~Reconstructor();
    Reconstructor(const Reconstructor&) = delete;
    Reconstructor& operator=(const Reconstructor&) = delete;

    // Fuses one depth image (metres, 0 = no measurement) seen from `cameraToWorld`, updates the mesh and
    // compacts it into meshBuffers(). All frames must have the size of the first. Capacity problems are
    // in the report's warnings (nothing already fused is lost). See the contract above for `sync`.
    gpu::FrameReport integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                               const vk::SubmitSync& sync = {});
    // The same with the frame's colour image registered to the depth image (same size), folded into the
    // corners as options.volume.params.colorFusion says (docs/COLOR.md); nullptr: depth only this frame.
    gpu::FrameReport integrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                               const Pose& cameraToWorld, const vk::SubmitSync& sync = {});
    // Without a pose: the camera is tracked against the mesh fused so far (the very first frame is fused at the
    // identity, or where the last frame given with a pose left the camera), and the frame fused at the tracked
    // pose. A lost frame (TrackedFrame::lost()) is not fused and gets the predicted pose; tracking picks up
    // again when a later frame matches. Frames given with a pose restart tracking from that pose.
    TrackedFrame integrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                           const vk::SubmitSync& sync = {});
    // The camera-to-world pose used for every frame so far (given, tracked, or predicted for a lost frame; a
    // corrected frame's once it has been re-fused).
    const std::vector<Pose>& trajectory() const { return mapper_->poses(); }

    // ---- correcting the map (docs/CORRECTION.md; needs options.keepFrames) ----
    // New camera-to-world poses for frames already fused: frame i is the i-th frame integrated (trajectory()[i];
    // after load(), numbering goes on from the map's). Every index and pose is checked first (an unknown or
    // lost frame, a non-finite or non-rigid pose: Error naming it, and nothing is queued). Each queued frame is
    // de-integrated at the pose it was fused at and integrated at the new one, exactly: the map then equals one
    // fused at the new poses from the start. The largest pose changes go first, correctionsPerFrame of them in
    // each later integrate() (with a host image; an asynchronous frame applies none), the rest by
    // finishCorrections(). The mesh follows through its incremental passes; lastDelta() reports every change.
    void correct(const std::vector<uint32_t>& frames, const std::vector<Pose>& poses);
    size_t pendingCorrections() const;
    // Re-fuses every queued frame now and publishes the mesh (and its delta).
    gpu::CorrectionReport finishCorrections();
    // What the last integrate() or finishCorrections() re-fused.
    const gpu::CorrectionReport& lastCorrections() const { return lastCorrections_; }
    // The kept frames (nullptr unless options.keepFrames).
    const FrameStore* frameStore() const { return mapper_->frameStore(); }

    // ---- asynchronous frames: the application's frame never waits for vkmesh's GPU work ----
    // integrateAsync() checks and copies the input, records the frame and submits it, and returns at once.
    // The frame's mesh is published into the other of two buffer sets than the last frame's, so the
    // application draws frame N while frame N+1 is fused: wait (on the GPU) on `ready` for `readyValue`
    // before reading `mesh` (plus recordMeshReadBarrier as usual). The call first finishes the frame before
    // (it waits on the host only if that frame is still running: the GPU is one frame behind at most) and
    // returns its report in `previous`: counters are one frame late. Contract points 2 and 3 hold per set:
    // the application's reads of frame N's buffers must be ordered before integrateAsync for frame N+2.
    // Deltas (trackDeltas) come with the report. finish() waits for the last frame and returns its report.
    struct AsyncFrame {
        uint32_t frame = 0;                          // frames integrated, this one included
        VkSemaphore ready = VK_NULL_HANDLE;          // vkmesh's timeline semaphore
        uint64_t readyValue = 0;                     // ...the value at which `mesh` holds this frame's mesh
        gpu::MeshBuffers mesh;                       // handles valid until integrateAsync for frame N+2
        std::optional<gpu::FrameReport> previous;    // the frame before, finished during this call
    };
    AsyncFrame integrateAsync(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                              const Pose& cameraToWorld, const vk::SubmitSync& sync = {});
    // Depth (and colour, or an empty input) already in the application's GPU memory: copied on the GPU, no
    // host copy (gpu::GpuImageInput says what is accepted and how its writes must be ordered).
    AsyncFrame integrateAsync(const gpu::GpuImageInput& depth, const gpu::GpuImageInput& color, const Intrinsics& intrinsics,
                              const Pose& cameraToWorld, const vk::SubmitSync& sync = {});
    // The blocking form of the GPU input: returns when the GPU has finished the frame.
    gpu::FrameReport integrate(const gpu::GpuImageInput& depth, const gpu::GpuImageInput& color, const Intrinsics& intrinsics,
                               const Pose& cameraToWorld, const vk::SubmitSync& sync = {});
    std::optional<gpu::FrameReport> finish();

    // The compacted mesh of the last frame (empty handles before the first). While an asynchronous frame is
    // in flight: its set, with readyValue set and the counts 0.
    gpu::MeshBuffers meshBuffers() const;
    // The barrier an application records before reading meshBuffers() (contract, point 1).
    static void recordMeshReadBarrier(VkCommandBuffer cmd) { gpu::recordMeshReadBarrier(cmd); }

    // The mesh copied to the host (for saving it; a renderer does not need this).
    gpu::ExportedMesh downloadMesh();
    // The last frame's changes (trackDeltas), empty otherwise.
    const MeshDelta& lastDelta() const { return lastDelta_; }
    uint32_t framesIntegrated() const;

    // Maps that outlive the process (docs/MAPFILE.md). save() writes everything the reconstruction holds after
    // the last frame (with options.keepFrames also the frame store, beside it: frameStorePath(path)); load()
    // continues it (and loads that store when options.keepFrames: a store saved with another map is refused): the next integrate() gives exactly what an uninterrupted run would
    // have. The map's settings are used (voxel size, truncation, ...); options.volume's capacities where larger
    // than the map's; the image size is the map's. Errors (bad file, a map that does not fit the device) name
    // the file and the problem, and nothing is created.
    void save(const std::filesystem::path& path);   // finishes an asynchronous frame in flight first; with
                                                    // loopClosure re-fuses the queued corrections and keeps its
                                                    // state beside the map (loopClosurePathOf)
    static std::unique_ptr<Reconstructor> load(const std::filesystem::path& path, const ReconstructorOptions& options = {});
    static std::unique_ptr<Reconstructor> load(const std::filesystem::path& path, const vk::ExternalDevice& device,
                                               const ReconstructorOptions& options = {});

    // Where save() puts the frame store of a map: the map's path with the extension .vkframes.
    static std::filesystem::path frameStorePath(const std::filesystem::path& mapPath);
    const vk::Context& context() const { return *context_; }
    vk::Context& context() { return *context_; }   // e.g. to take its validation messages
    // The data structure itself, for what the facade does not cover; nullptr before the first frame.
    gpu::GpuVolume* volume() { return mapper_->volumePtr(); }
    const gpu::GpuVolume* volume() const { return mapper_->volumePtr(); }
    // The run's frame loop and its statistics (runStatsJson, api/run_stats_json.h).
    const Mapper& mapper() const { return *mapper_; }

private:
    void createMapper();
    void loadMap(const map::MapData& map, const std::filesystem::path& path);
    // The number of the next frame: frames integrated so far (a loaded map's first).
    uint32_t nextIndex() const { return firstFrameIndex_ + uint32_t(mapper_->trajectory().size()); }
    MapperFrame frameOf(const DepthImage* depth, const ColorImage* color, const Intrinsics& intrinsics, const vk::SubmitSync& sync) const;
    AsyncFrame submitAsync(const gpu::FrameInput& input);
    uint64_t nextReadyValue_ = 0;
    std::unique_ptr<vk::Context> context_;
    ReconstructorOptions options_;
    std::unique_ptr<Mapper> mapper_;
    MeshDelta lastDelta_;
    uint32_t firstFrameIndex_ = 0;                 // the number of the first frame integrated here (a loaded map's frames come first)
    gpu::CorrectionReport lastCorrections_;
};

}  // namespace vkmesh
