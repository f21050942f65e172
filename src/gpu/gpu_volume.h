// The GPU program: the data structure's components (src/gpu/structure: block hash, block store, cube mesh,
// per-frame lists, counters, parameters), each owning its buffers, and the stages of the frame pipeline
// (src/gpu/stages), each owning its pipelines. integrate() records one frame (recordFrame: the ordered passes
// with what each reads and writes) into one command buffer; only the small Counters struct is read back.
// Capacities grow between frames (growBeforeFrame, growAfterDeferral), policy included, so every user of
// the library gets it.
#pragma once

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/map_format.h"
#include "core/mesh_delta.h"
#include "core/types.h"
#include "gpu/layout.h"
#include "gpu/paged_blocks.h"
#include "gpu/stages/allocate_blocks_stage.h"
#include "gpu/stages/baseline_mesh_stage.h"
#include "gpu/stages/block_list_stage.h"
#include "gpu/stages/claim_vertices_stage.h"
#include "gpu/stages/export_mesh_stage.h"
#include "gpu/stages/fuse_depth_stage.h"
#include "gpu/stages/mark_dirty_stage.h"
#include "gpu/stages/mesh_delta_stage.h"
#include "gpu/stages/mesh_gc_stage.h"
#include "gpu/stages/model_view_stage.h"
#include "gpu/stages/paging_stage.h"
#include "gpu/stages/recycle_stage.h"
#include "gpu/stages/retype_stage.h"
#include "gpu/stages/triangulate_stage.h"
#include "gpu/stages/update_vertices_stage.h"
#include "gpu/structure/block_hash.h"
#include "gpu/structure/block_store.h"
#include "gpu/structure/counter_buffer.h"
#include "gpu/structure/cube_mesh.h"
#include "gpu/structure/frame_lists.h"
#include "gpu/structure/params_buffer.h"
#include "vk/buffer.h"
#include "vk/commands.h"
#include "vk/context.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

enum class MeshMode {
    Incremental,  // the paper's persistent shared-vertex mesh, updated every frame (docs/MESH.md)
    Baseline,     // no per-frame mesh; marching cubes over everything on demand, 3 vertices per triangle
};

// Capacities are initial sizes: with growCapacities (the default) every one grows between frames when it is
// full or nearly full, up to what the device allows (docs/MESH.md, "Capacities").
struct GpuVolumeConfig {
    VolumeParams params;
    uint32_t blockCapacity = 16384;      // blocks in the pool (512 TSDF corners each)
    uint32_t hashCapacity = 0;           // hash slots; 0: the power of two >= 2 * blockCapacity
    uint32_t touchedCapacity = 0;        // blocks one frame may touch; 0: blockCapacity
    uint32_t meshVertexCapacity = 1u << 20;  // baseline mesh buffer (grown on demand)
    float minMeshWeight = 1.0f;          // a cube is meshed when all its corners have this weight
    MeshMode meshMode = MeshMode::Incremental;
    uint32_t vertexCapacity = 1u << 20;  // shared-vertex heap (36 B each)
    uint32_t chunkCapacity = 1u << 19;   // triangle chunks, 5 triangles each (60 B)
    uint32_t retypeCapacity = 1u << 20;  // cubes one mesh pass can retype (more wait for the next pass)
    // Hamming-distance refinement of cube types (paper §V.F, docs/REFINEMENT.md). Decided per corner: a corner
    // within refineEpsilonVoxels of the surface may flip its sign for meshing, and every cube sharing it sees
    // the same sign, so the mesh has no cracks. On by default (--no-refine turns it off); what it changes and
    // costs is measured in docs/REFINEMENT.md.
    bool refine = true;
    float refineEpsilonVoxels = 0.5f;    // corners within this distance of the surface may be flipped
    bool lockFree = false;               // the paper's lock-free claim: 4 parity-class passes, no slot atomics
    uint32_t vertexUpdate = VERTEX_UPDATE_AUTO;   // no effect any more (the vertex update lists the owned-slot masks); kept for the API and map files
    // Compact the mesh on the GPU at the end of every integrate(), into draw-ready buffers (meshBuffers()):
    // what a renderer embedding vkmesh needs. Incremental mode only.
    bool publishMesh = false;
    // Report every frame's mesh changes (FrameReport::delta, docs/DELTAS.md). Incremental mode only; costs
    // a shadow copy of the vertex heap and the triangle chunks, and one pass over each per frame.
    bool trackDeltas = false;
    uint32_t deltaRecordCapacity = 1u << 14;   // initial size of each delta record list (grown on demand)
    // Bounded maps for long runs (docs/MESH.md, "Recycling blocks"). Off by default: then no recycling pass
    // is recorded and a run is bit-identical to one without these settings.
    float keepRadius = 0.0f;             // metres; > 0: blocks whose centre is farther from the camera are not
                                         // allocated, and those already in the map are freed (with their mesh)
    bool recycle = false;                // starve blocks idle for recycleAfterFrames and free them once empty
    uint32_t recycleAfterFrames = 100;   // frames without a touch before a block starves
    float starveWeight = 4.0f;           // weight an idle block's corners lose per frame (max weight 255: ~64 frames)
    // The hash table is rebuilt on the GPU (tombstones dropped) before a frame when the tombstones of freed keys
    // exceed this fraction of its slots.
    float hashRebuildTombstoneFraction = 0.125f;
    int imageWidth = 640, imageHeight = 480;
    // Paging (docs/PAGING.md): at most this many blocks stay in GPU memory; the others wait on the host, exactly as
    // they were, until a camera may reach them again. 0: every block stays (no paging). A map that pages equals the
    // one that does not, bit for bit. Needs the frame's pose on the host (not FrameInput::recordPose) and the
    // incremental mesh, and excludes the bounded-map settings (keepRadius, recycle), which forget instead. The block
    // pool starts at most at this plus a quarter (at least 1,024 blocks) and grows when the camera reaches more.
    uint32_t residentBlocks = 0;
    // Grow the hash, the block pool, the mesh heaps and the per-frame lists between frames when full or nearly
    // full; a frame whose allocation overflowed is grown past and run again, so nothing is lost. Off: fixed
    // capacities, and what does not fit is reported (FrameReport::warnings) and skipped.
    bool growCapacities = true;
    // GPU timestamps between the stages of every frame (FrameReport::stageMs, and the stage times of mesh
    // extraction and export). Off: no timestamp is recorded and stageMs is empty; on lavapipe the ~8
    // timestamps of a frame cost ~0.3-0.4 ms of its ~18 (`vkmesh fuse` turns them off with -q and no --stats).
    bool timeStages = true;
    // With timeStages, a timestamp after every pass (compute dispatch) of a frame as well (FrameReport::passMs):
    // where a stage's time goes, pass by pass. Off by default: each timestamp costs ~50 us on lavapipe.
    bool timePasses = false;
};

// Paging around one frame (GpuVolumeConfig::residentBlocks): blocks brought back before it, moved out after it.
struct PagingReport {
    uint32_t blocksIn = 0, blocksOut = 0;
    uint64_t bytesIn = 0, bytesOut = 0;
    double milliseconds = 0;      // on the host, copies and their submissions included
    uint32_t blocksPaged = 0;     // blocks on the host after the frame
    uint64_t bytesPaged = 0;
    uint32_t overBudget = 0;      // resident blocks above the budget that the camera's reach kept
};

// What one frame did, from the GPU's counters, and how long each stage took on the GPU.
struct FrameReport {
    Counters counters{};
    std::vector<std::pair<std::string, double>> stageMs;
    // With GpuVolumeConfig::timePasses: (shader name, ms) of every pass of the frame in order, each from the
    // timestamp before it (a stage's time is its passes' and its barriers' and copies'); a pass may repeat.
    std::vector<std::pair<std::string, double>> passMs;
    // Human-readable capacity problems of this frame (empty when none): hash full, pool exhausted, ...
    std::vector<std::string> warnings;
    // What grew before or during this frame ("block pool 16384 -> 32768", ...), and how many times the frame
    // was deferred and run again because its allocation overflowed (growCapacities).
    std::vector<std::string> growth;
    uint32_t deferredAttempts = 0;
    // Compute dispatches the frame's submission recorded (its last attempt's; vk::BindingTable::dispatchesRecorded):
    // the passes per frame, each a fixed cost whatever the map.
    uint32_t dispatches = 0;
    MeshDelta delta;   // this frame's mesh changes when GpuVolumeConfig::trackDeltas (else empty)
    // The frame's pose was recorded on the GPU (FrameInput::recordPose) with "skip": nothing was fused, the map
    // is as it was, and the frame does not count (framesIntegrated(), frameNumber() unchanged).
    bool skipped = false;
    PagingReport paging;
};

// The compacted mesh in GPU buffers, for a renderer to draw without a copy through the host
// (GpuVolumeConfig::publishMesh, or after exportMesh()). Handles stay valid until the next integrate(),
// exportMesh() or rebuildMesh(), which may reallocate them when the mesh outgrows them: query again after
// each. Synchronisation contract: see recordMeshReadBarrier() and api/reconstructor.h.
struct MeshBuffers {
    VkBuffer vertices = VK_NULL_HANDLE;   // Vertex[vertexCount], stride 36: position (3 x float) at 0,
                                          // normal (3 x float) at 16, createdFrame (uint) at 28,
                                          // colour (R8G8B8A8_UNORM, alpha 0 = no colour) at 32
    VkBuffer indices = VK_NULL_HANDLE;    // uint32 triangle list, 3 per triangle
    VkBuffer drawIndirect = VK_NULL_HANDLE;   // a VkDrawIndexedIndirectCommand at drawIndirectOffset
    VkDeviceSize drawIndirectOffset = 0;
    uint32_t vertexCount = 0;             // 0 while an asynchronous frame is in flight (draw indirectly)
    uint32_t triangleCount = 0;
    uint32_t frame = 0;                   // frame number the mesh is from (createdFrame <= frame)
    uint64_t readyValue = 0;              // asynchronous frame in flight: the GpuVolume::timeline() value
                                          // at which these buffers hold its mesh; 0: ready now
    static constexpr uint32_t kStride = sizeof(Vertex);
    static constexpr uint32_t kPositionOffset = 0;
    static constexpr uint32_t kNormalOffset = 16;
    static constexpr uint32_t kCreatedFrameOffset = 28;
    static constexpr uint32_t kColorOffset = 32;
};

// Records the barrier that makes vkmesh's writes of the mesh buffers (compute shaders, transfers of any
// earlier submission on the same queue) visible to vertex input, index reads, indirect draws and vertex
// shaders. An application drawing from MeshBuffers records it before the draw in its own command buffer.
void recordMeshReadBarrier(VkCommandBuffer cmd);

// A triangle soup: 3 vertices per triangle, in order (the baseline mesh).
struct TriangleSoup {
    std::vector<Eigen::Vector3f> vertices;
    size_t triangleCount() const { return vertices.size() / 3; }
};

// The compacted shared-vertex mesh, and what the compaction saw.
struct ExportedMesh {
    std::vector<Vertex> vertices;                 // position, normal, createdFrame, colour (refcount as it was)
    std::vector<std::array<uint32_t, 3>> triangles;
    uint32_t unreferencedVertices = 0;            // allocated vertices with no triangle (0 unless GC fell behind)
};

// A depth or colour image already in the application's GPU memory (docs/EMBEDDING.md), copied on the GPU
// into vkmesh's input buffer: no host copy. Same size and pixel grid as the volume's images. Either
//  - a buffer: width x height values, rows packed, from `offset`: depth as float32 metres (0 = none), colour as
//    RGBA8 words (red in the low byte; alpha 0 = no colour at that pixel); usage TRANSFER_SRC; or
//  - an image: one mip level and layer in `layout` (TRANSFER_SRC_OPTIMAL or GENERAL), usage TRANSFER_SRC;
//    depth R32_SFLOAT or D32_SFLOAT (metres), colour R8G8B8A8_UNORM or _SRGB (the bytes as they are).
// The application's writes must be ordered before the frame: submitted earlier to the same queue (the frame
// starts with a barrier after all prior commands), or a semaphore in the frame's sync.wait.
struct GpuImageInput {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceSize offset = 0;
    VkImage image = VK_NULL_HANDLE;
    VkFormat format = VK_FORMAT_UNDEFINED;
    VkImageLayout layout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    bool empty() const { return !buffer && !image; }
};

// One frame's input: host images (depth, and colour or nullptr) or GPU ones (gpuDepth, gpuColor).
struct FrameInput {
    // A frame from host images (the images must outlive submitFrame(), which copies them).
    static FrameInput fromHost(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics, const Pose& cameraToWorld) {
        FrameInput in;
        in.depth = &depth;
        in.color = color;
        in.intrinsics = intrinsics;
        in.cameraToWorld = cameraToWorld;
        return in;
    }
    const DepthImage* depth = nullptr;
    const ColorImage* color = nullptr;
    GpuImageInput gpuDepth, gpuColor;
    Intrinsics intrinsics;
    Pose cameraToWorld = Pose::Identity();
    vk::SubmitSync sync;
    // Optional: passes that compute the frame's pose on the GPU, recorded at the start of the frame's submission
    // instead of the host's cameraToWorld: they write a FramePoseGpu into `framePose` (shared_layout.h), skip = 1
    // to fuse nothing. Camera tracking fuses a frame in the submission that tracks it this way
    // (PoseTracker::trackAndFuse). Called once, from submitFrame(); a deferred frame's re-run reuses the pose.
    // It must not throw (check its inputs before submitFrame): the frame is half recorded by then.
    std::function<void(VkCommandBuffer cmd, const vk::Buffer& framePose)> recordPose;
    // Take this frame out of the map instead of fusing it (GpuVolume::deintegrate): it must have been fused at
    // cameraToWorld with these very images; the frame subtracts exactly what fusing it added.
    bool deintegrate = false;
    // One of several frames that make one step (a correction's de-integration and re-integration before the
    // frame that follows them, Reconstructor::correct): the mesh is neither exported nor diffed for deltas
    // (the step's last frame does both, and its deltas hold every change since the last ones taken, or
    // publishMesh() after the last intermediate frame).
    bool intermediate = false;
};

// The configuration with its defaults filled in (hashCapacity 0 -> twice the block capacity, a power of two;
// touchedCapacity 0 -> the block capacity, ...), checked without a device: throws Error naming the first
// setting out of range. The GpuVolume constructor starts with it; exposed so that a caller can report a bad
// setting before it has a device or an image (the Python module's constructor).
GpuVolumeConfig resolveConfig(const GpuVolumeConfig& config);

// Checks, before anything is allocated, that every buffer the configuration implies fits in one storage
// buffer binding (maxBufferBytes: maxStorageBufferRange) and that all of them fit in the device's largest
// device-local memory heap. Throws Error naming the buffer, the setting that sizes it (config field and CLI
// option) and the largest value that fits. Called by the GpuVolume constructor; exposed for tests.
// hashKeyBytesPerSlot: BlockHash::keyBytesPerSlot of the device's hash path.
void checkCapacities(const GpuVolumeConfig& config, uint64_t maxBufferBytes, uint64_t deviceMemoryBytes,
                     const std::string& deviceName, uint32_t hashKeyBytesPerSlot = 8);

class GpuVolume {
public:
    GpuVolume(const vk::Context& context, const GpuVolumeConfig& config);
    ~GpuVolume();   // waits for a frame still in flight (submitFrame without finishFrame)
    GpuVolume(const GpuVolume&) = delete;
    GpuVolume& operator=(const GpuVolume&) = delete;

    // Fuses one depth image (metres, 0 = none) seen from `cameraToWorld`. One submission (more only when
    // the frame overflowed a capacity and is run again after growing it).
    // `sync`: semaphores the frame's submission waits on / signals (an application's draws of the last
    // frame's MeshBuffers on another queue); integrate() returns once the GPU has finished the frame.
    FrameReport integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                          const vk::SubmitSync& sync = {});
    // The same with the frame's colour image, registered to the depth image (same size and pixel grid);
    // nullptr or an empty image: this frame fuses depth only. Ignored when colour fusion is off.
    FrameReport integrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                          const Pose& cameraToWorld, const vk::SubmitSync& sync = {});
    // Takes a frame out of the map again: `depth` and `color` must be the images it was fused with and
    // cameraToWorld the pose it was fused at (a FrameStore keeps them). Every corner it updated gets back the
    // exact sum and weight it would have without the frame; blocks left with no observation are freed with
    // their mesh; the mesh is re-meshed where corners changed, as after any frame (deltas included). Throws
    // for a bounded map (keep radius, recycling), which has forgotten what it fused. The report's
    // counters.observationsDropped is 0 when the map held the frame.
    FrameReport deintegrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics, const Pose& cameraToWorld);
    // After intermediate frames (FrameInput::intermediate) with no ordinary frame to follow: exports the mesh
    // (publishMesh) and takes the deltas of everything since the last ones, in one submission.
    FrameReport publishMesh();

    // The same, in two halves, for callers that do not wait for the GPU (Reconstructor::integrateAsync):
    // submitFrame() checks the input, records the frame and submits it, and returns without waiting;
    // finishFrame() waits for it and does what needs its counters (a deferred frame's re-run after growing,
    // the mesh completion after a heap grew, the deltas, the warnings) and returns its report. Between the
    // two nothing else may be called but meshBuffers() and framePending(). With `timelineValue` (non-zero)
    // the frame is published into the other export set than the last one (the application draws the last
    // one meanwhile) and the frame's submission raises timeline() to that value when its mesh is ready.
    void submitFrame(const FrameInput& input, uint64_t timelineValue = 0);
    FrameReport finishFrame();
    bool framePending() const { return inFlight_.has_value(); }
    // The semaphore submitFrame() signals (created on first use; the device needs timelineSemaphore enabled).
    const vk::TimelineSemaphore& timeline();
    // Whether the volume keeps colour (params.colorFusion != Off).
    bool fusesColor() const { return config_.params.colorFusion != ColorFusion::Off; }

    // Marching cubes over every block, each triangle with its own 3 vertices. Never truncated: if the
    // mesh buffer was too small it is grown to the exact size the GPU counted and the pass re-run.
    TriangleSoup extractBaselineMesh(std::vector<std::pair<std::string, double>>* stageMs = nullptr);
    // How many vertices the baseline mesh of the current TSDF has (3 per triangle), without downloading it.
    uint32_t countBaselineVertices();

    // The shared-vertex mesh, compacted on the GPU. Never truncated (buffers grow to the exact counts).
    // Cubes left incomplete by a full heap that has grown since are re-meshed first.
    ExportedMesh exportMesh(std::vector<std::pair<std::string, double>>* stageMs = nullptr);
    // Throws away the mesh state (not the TSDF) and rebuilds it from scratch over every block: the
    // reference an incremental mesh must equal.
    void rebuildMesh();
    // The last compacted mesh (publishMesh, or the last exportMesh()); empty handles before any.
    MeshBuffers meshBuffers() const;
    // Records into `cmd` the listing of the mesh's triangles that can be in the view of a `width` x `height` camera
    // with `intrinsics` at `cameraToWorld` (depths in [near, far]), and returns what draws them: the vertex heap
    // and that list (ModelViewStage; counts unknown on the host: 0). What tracking draws: a drawing of these is
    // the drawing of the whole mesh at that camera, at a cost that follows the view, not the map, and it needs no
    // export. The buffers hold the mesh as the passes recorded before it left it. Incremental mode only.
    // `createdBefore`: only the triangles whose vertices frames before it created (the older map); UINT32_MAX: all.
    MeshBuffers recordModelView(VkCommandBuffer cmd, const Pose& cameraToWorld, const Intrinsics& intrinsics, int width, int height,
                                float nearDepth, float farDepth, uint32_t createdBefore = UINT32_MAX);
    // The triangles the last recordModelView() listed (vertex heap indices), after its submission; for tests.
    std::vector<std::array<uint32_t, 3>> downloadModelView() const;
    MeshStateSnapshot downloadMeshState() const;
    // Grows the vertex heap and the triangle-chunk heap between frames (never shrinks; the mesh is kept: the
    // heaps are copied and the new entries pushed on the free stacks). The next frame also re-meshes every
    // cube left INCOMPLETE while a heap was full, so the missing triangles appear at once. growCapacities
    // does this by itself; this is for callers that size the heaps themselves.
    void growMeshHeaps(uint32_t vertexCapacity, uint32_t chunkCapacity);
    // How many cubes carry triangles of each MC type (the stored, possibly refined, type).
    std::array<uint64_t, 256> surfaceCubeTypes() const;

    // Every block's TSDF: the live ones, then those paged out to the host (index NO_BLOCK), in coordinate order.
    std::vector<BlockSnapshot> downloadBlocks() const;
    // With refinement: the mesh signs buffer, MESH_SIGN_WORDS words per pool block (the meshing signs, then the
    // masks of the TSDF: shared_layout.h), for tests.
    std::vector<uint32_t> downloadMeshSigns() const;
    Counters readCounters() const { return counters_.read(); }
    std::vector<PoolInfo> pools() const;
    // The configuration with the capacities as they are now (they grow with growCapacities).
    const GpuVolumeConfig& config() const { return config_; }
    bool recycling() const { return config_.keepRadius > 0.0f || config_.recycle; }
    uint32_t framesIntegrated() const { return framesIntegrated_; }
    // The GPU's frame number of the last frame (vertices' createdFrame, hash stamps): framesIntegrated() plus
    // the frames run again after a deferral.
    uint32_t frameNumber() const { return frameNumber_; }

    // ---- paging (src/gpu/paging.cpp, docs/PAGING.md) ----
    bool paging() const { return config_.residentBlocks > 0; }
    size_t pagedBlocks() const { return paged_.size(); }
    // Brings back the paged blocks a camera at cameraToWorld may reach, between frames: what a caller that draws the
    // mesh of a view it does not fuse calls first (tracking, before it draws the model: CameraTracker). integrate()
    // does this itself for the frame's own pose. Returns the blocks brought back; they are counted in the next
    // frame's FrameReport::paging (and a pool grown for them in its growth).
    uint32_t pageInView(const Pose& cameraToWorld, const Intrinsics& intrinsics);

    // ---- maps that outlive the process (docs/MAPFILE.md; src/gpu/map_file.cpp) ----
    // Everything between two frames: live blocks (coordinates, TSDF, hash stamps, retype masks), the mesh
    // (cube states, edge slots, vertex heap with refcounts and owners, triangle chunks), the free stacks,
    // the counters, the frame numbers and the settings. Read back from the GPU; changes nothing. Call
    // between frames (before exportMesh(), which may re-mesh cubes left pending, to resume bit-exactly).
    map::MapData saveMap() const;
    // Returns the map's save id (MapData::saveId), drawn anew for this save.
    uint64_t save(const std::filesystem::path& path) const;
    // The configuration a map was saved with (its settings and capacities; the image size it was fused at).
    static GpuVolumeConfig mapConfig(const map::MapData& map);
    // A volume holding the map, ready for the next frame. `config` must agree with the map's settings (voxel
    // size, truncation, weights, allocation stride, mesh mode, refinement, recycling: anything else is an
    // Error naming `name` and the setting); its capacities are used where larger than the map's. Everything is
    // checked before a buffer is created (the map was validated when parsed, map::parse); the hash is rebuilt
    // from the block coordinates by the GPU's own re-insertion pass, so a map saved on a device with 64-bit
    // atomics loads on one without, and into a table of any size.
    static std::unique_ptr<GpuVolume> load(const vk::Context& context, const map::MapData& map, const GpuVolumeConfig& config,
                                           const std::string& name);
    static std::unique_ptr<GpuVolume> load(const vk::Context& context, const std::filesystem::path& path);

private:
    // Follow-up mesh passes after a frame whose mesh passes ran out of a heap or the retype list.
    static constexpr int kMaxMeshCompletions = 4;
    // Paging: the blocks a camera may reach, the two moves, the paged blocks' TSDF.
    ViewReach reachOf(const Pose& cameraToWorld, const Intrinsics& intrinsics) const;
    void pageIn(const Pose& cameraToWorld, const Intrinsics& intrinsics, FrameReport& report);
    void pageOutToBudget(const Pose& cameraToWorld, const Intrinsics& intrinsics, FrameReport& report);
    // Throws an Error naming `what` while blocks are paged out (what reads every block from the GPU's arrays).
    void requireNothingPaged(const char* what) const;
    std::vector<BlockSnapshot> pagedBlockSnapshots() const;
    // Moves what was paged since the last frame's report into `frame` (with the blocks on the host now).
    void finishPagingReport(FrameReport& frame);
    // load(): uploads the map into this freshly created volume and rebuilds the hash.
    void restore(const map::MapData& map, const std::string& name);
    // The frame (frame.cpp): every pass in order, with what it reads and writes (docs/ARCHITECTURE.md draws it).
    // `copyInput`: the frame's first attempt copies its input into depth_; a deferred frame's re-run finds it
    // there (the application's GPU input need not outlive the first submission).
    void recordFrame(VkCommandBuffer cmd, const FramePush& push, bool rebuildHash, bool retryPending, bool copyInput);
    // The frame's pose into framePose_: the host's (push) or, on the first attempt, FrameInput::recordPose's passes.
    void recordFramePose(VkCommandBuffer cmd, const FramePush& push, bool firstAttempt);
    void recordInputCopy(VkCommandBuffer cmd, bool withColor);
    // Submits one attempt of the frame in flight (the first, or a re-run after a deferral).
    void submitAttempt();
    // The incremental mesh passes after the dirty blocks are listed (also a rebuild's and a retry's).
    void recordMeshPasses(VkCommandBuffer cmd, const FramePush& push, vk::StageTimer* timer);
    void recordExport(VkCommandBuffer cmd) { exportMesh_->record(cmd, lastPush_, counters_); }
    // recorder_.begin() followed by the upload of changed parameters: how every submission starts.
    VkCommandBuffer beginSubmission();
    // Growth policy (growCapacities): before a frame from the last counters; after a deferred frame from
    // what overflowed; after a frame whose mesh passes ran out of heap.
    void growBeforeFrame(FrameReport& report);
    void growAfterDeferral(const Counters& k, FrameReport& report);
    void growMeshAfterFrame(const Counters& k, FrameReport& report);
    void growBlockPool(uint32_t blocks, FrameReport& report);
    void growHash(uint32_t slots, FrameReport& report);
    void growTouched(uint32_t entries, FrameReport& report);
    void growRetypeList(uint32_t entries, FrameReport& report);
    void growHeaps(uint32_t vertices, uint32_t chunks, FrameReport* report);
    // One submission re-meshing the cubes left INCOMPLETE or deferred (mark_pending_dirty + the mesh passes),
    // with the export when `publish` and the delta passes when `report`; returns its counters.
    Counters runMeshCompletion(bool publish, bool report);
    // Re-meshes what was left (retryPending_) before an export outside integrate().
    void completePendingMesh();
    Counters runBaselinePass(std::vector<std::pair<std::string, double>>* stageMs);
    // Compacts the mesh in its own submission, growing the buffers until it fits; returns the counters.
    Counters runExport(std::vector<std::pair<std::string, double>>* stageMs);
    void warnAboutCapacities(const Counters& k, FrameReport& report) const;
    // The live block list, then BlockHash::recordRebuild (tombstones dropped).
    void recordRebuildHash(VkCommandBuffer cmd, const FramePush& push);

    const vk::Context& context_;
    GpuVolumeConfig config_;
    vk::BindingTable table_;
    CounterBuffer counters_;
    ParamsBuffer params_;
    BlockHash hash_;
    BlockStore store_;
    CubeMesh mesh_;
    FrameLists lists_;
    // depth_ is what the shaders read; depthStaging_ is what the host writes a frame's images into, absent on a
    // device with unified memory, where the host writes depth_ itself (hostInput()).
    vk::Buffer depth_, depthStaging_, mcTables_;
    vk::Buffer allocTiles_;   // BINDING_ALLOC_TILES: which allocation tiles allocate_tiles covered this frame
    void* hostInput() const { return depthStaging_.handle() ? depthStaging_.mapped() : depth_.mapped(); }
    // FramePoseGpu (BINDING_FRAME_POSE), written at the start of every frame; a frame whose pose the GPU computed
    // copies it back (did the GPU skip the frame?).
    vk::Buffer framePose_, framePoseReadback_;
    AllocateBlocksStage allocate_;
    FuseDepthStage fuse_;
    BlockListStage blockList_;
    BaselineMeshStage baselineMesh_;
    MarkDirtyStage markDirty_;
    RetypeStage retype_;
    ClaimVerticesStage claim_;
    UpdateVerticesStage updateVertices_;
    TriangulateStage triangulate_;
    MeshGcStage meshGc_;
    RecycleStage recycle_;
    std::optional<PagingStage> paging_;   // with residentBlocks only
    std::optional<ExportMeshStage> exportMesh_;
    std::optional<MeshDeltaStage> deltas_;
    std::optional<ModelViewStage> modelView_;   // made by the first recordModelView()
    vk::CommandRecorder recorder_;
    vk::StageTimer timer_;
    bool recordingFrame_ = false;   // submitAttempt is recording a frame: its passes are timed (timePasses)
    uint32_t frameNumber_ = 0, framesIntegrated_ = 0;
    bool touchedFollowsPool_ = false;   // touchedCapacity was left at its default (the pool's size)
    bool meshPublished_ = false;
    // Capacities that reached a device limit and said so (once each; the frames' own warnings still count).
    static constexpr uint32_t kPoolLimit = 1, kHashLimit = 2;
    uint32_t limitsReported_ = 0;
    bool retryPending_ = false;   // next frame: dirty every block with retype bits left (see growMeshHeaps)
    FramePush lastPush_{};
    // The frame between submitFrame() and finishFrame().
    struct InFlight {
        FrameInput input;          // its images' pointers are not used after submitFrame()
        bool withColor = false, fromGpu = false;
        bool rebuildHash = false, retryPending = false;
        FramePush previousPush{};  // lastPush_ and the counters before the frame (restored when the GPU skipped it)
        Counters previousCounters{};
        int attempt = 0;
        bool mayDefer = false, signalled = false;
        uint64_t timelineValue = 0;
        FrameReport report;
    };
    std::optional<InFlight> inFlight_;
    std::unique_ptr<vk::TimelineSemaphore> timeline_;
    PagedBlocks paged_;
    PagingReport pagingSinceFrame_;
    std::vector<std::string> pendingGrowth_;   // what grew for a pageInView() between frames
    bool budgetWarned_ = false;
};

}  // namespace vkmesh::gpu
