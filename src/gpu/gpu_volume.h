// The GPU data structure (paper §IV): a spatial hash of 8x8x8 blocks, a pool of blocks with a free
// list, and the TSDF at every cube corner; plus the frame pipeline that fuses depth images into it
// and the baseline mesh extraction. One command buffer per frame; only the small Counters struct is
// read back.
#pragma once

#include <Eigen/Core>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh_delta.h"
#include "core/types.h"
#include "gpu/allocate_blocks_stage.h"
#include "gpu/block_hash.h"
#include "gpu/layout.h"
#include "gpu/stages.h"
#include "vk/buffer.h"
#include "vk/commands.h"
#include "vk/context.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

enum class MeshMode {
    Incremental,  // the paper's persistent shared-vertex mesh, updated every frame (docs/MESH.md)
    Baseline,     // no per-frame mesh; marching cubes over everything on demand, 3 vertices per triangle
};

struct GpuVolumeConfig {
    VolumeParams params;
    uint32_t blockCapacity = 16384;      // blocks in the pool (512 TSDF corners each)
    uint32_t hashCapacity = 0;           // hash slots; 0: the power of two >= 2 * blockCapacity
    uint32_t touchedCapacity = 0;        // blocks one frame may touch; 0: blockCapacity
    uint32_t meshVertexCapacity = 1u << 20;  // baseline mesh buffer (grown on demand)
    float minMeshWeight = 1.0f;          // a cube is meshed when all its corners have this weight
    MeshMode meshMode = MeshMode::Incremental;
    uint32_t vertexCapacity = 1u << 20;  // shared-vertex heap (32 B each)
    uint32_t chunkCapacity = 1u << 19;   // triangle chunks, 5 triangles each (60 B)
    uint32_t retypeCapacity = 1u << 20;  // cubes one mesh pass can retype (more wait for the next pass)
    // Hamming-distance refinement of cube types (docs/REFINEMENT.md). Off by default: as the paper specifies
    // it, a refined cube no longer meets its unrefined neighbours on their shared faces (cracks; measured
    // in docs/RESULTS.md).
    bool refine = false;
    float refineEpsilonVoxels = 0.5f;    // corners within this distance of the surface may be flipped
    bool lockFree = false;               // the paper's lock-free claim: 4 parity-class passes, no slot atomics
    uint32_t vertexUpdate = VERTEX_UPDATE_AUTO;   // how vertices are moved (both ways give the same mesh)
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
};

// What one frame did, from the GPU's counters, and how long each stage took on the GPU.
struct FrameReport {
    Counters counters{};
    std::vector<std::pair<std::string, double>> stageMs;
    // Human-readable capacity problems of this frame (empty when none): hash full, pool exhausted, ...
    std::vector<std::string> warnings;
    MeshDelta delta;   // this frame's mesh changes when GpuVolumeConfig::trackDeltas (else empty)
};

// The compacted mesh in GPU buffers, for a renderer to draw without a copy through the host
// (GpuVolumeConfig::publishMesh, or after exportMesh()). Handles stay valid until the next integrate(),
// exportMesh() or rebuildMesh(), which may reallocate them when the mesh outgrows them: query again after
// each. Synchronisation contract: see recordMeshReadBarrier() and api/reconstructor.h.
struct MeshBuffers {
    VkBuffer vertices = VK_NULL_HANDLE;   // Vertex[vertexCount], stride 32: position (3 x float) at 0,
                                          // normal (3 x float) at 16, createdFrame (uint) at 28
    VkBuffer indices = VK_NULL_HANDLE;    // uint32 triangle list, 3 per triangle
    VkBuffer drawIndirect = VK_NULL_HANDLE;   // a VkDrawIndexedIndirectCommand at drawIndirectOffset
    VkDeviceSize drawIndirectOffset = 0;
    uint32_t vertexCount = 0;
    uint32_t triangleCount = 0;
    uint32_t frame = 0;                   // frame number the mesh is from (createdFrame <= frame)
    static constexpr uint32_t kStride = sizeof(Vertex);
    static constexpr uint32_t kPositionOffset = 0;
    static constexpr uint32_t kNormalOffset = 16;
    static constexpr uint32_t kCreatedFrameOffset = 28;
};

// Records the barrier that makes vkmesh's writes of the mesh buffers (compute shaders, transfers of any
// earlier submission on the same queue) visible to vertex input, index reads, indirect draws and vertex
// shaders. An application drawing from MeshBuffers records it before the draw in its own command buffer.
void recordMeshReadBarrier(VkCommandBuffer cmd);

// The TSDF of one block as downloaded (tests, snapshots).
struct BlockSnapshot {
    Eigen::Vector3i coord;
    uint32_t index = 0;               // its block in the pool
    std::vector<float> sdf, weight;   // VOXELS_PER_BLOCK each, x fastest
};

// A triangle soup: 3 vertices per triangle, in order (the baseline mesh).
struct TriangleSoup {
    std::vector<Eigen::Vector3f> vertices;
    size_t triangleCount() const { return vertices.size() / 3; }
};

// The compacted shared-vertex mesh, and what the compaction saw.
struct ExportedMesh {
    std::vector<Vertex> vertices;                 // position, normal, createdFrame (refcount as it was)
    std::vector<std::array<uint32_t, 3>> triangles;
    uint32_t unreferencedVertices = 0;            // allocated vertices with no triangle (0 unless GC fell behind)
};

// The raw mesh state, for tests of its invariants.
struct MeshStateSnapshot {
    std::vector<Vertex> vertices;                 // the whole heap; refcount DEAD_REFCOUNT when free
    std::vector<uint32_t> vertexOwner;
    std::vector<std::array<uint32_t, 3>> liveTriangles;   // raw heap indices
    std::vector<uint32_t> edgeVertex;             // per cube and axis of every pool block
    Counters counters{};
};

struct PoolInfo {
    std::string name;
    size_t bytes;
};

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

    // Fuses one depth image (metres, 0 = none) seen from `cameraToWorld`. One submission.
    // `sync`: semaphores the frame's submission waits on / signals (an application's draws of the last
    // frame's MeshBuffers on another queue); integrate() returns once the GPU has finished the frame.
    FrameReport integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                          const vk::SubmitSync& sync = {});

    // Marching cubes over every block, each triangle with its own 3 vertices. Never truncated: if the
    // mesh buffer was too small it is grown to the exact size the GPU counted and the pass re-run.
    TriangleSoup extractBaselineMesh(std::vector<std::pair<std::string, double>>* stageMs = nullptr);
    // How many vertices the baseline mesh of the current TSDF has (3 per triangle), without downloading it.
    uint32_t countBaselineVertices();

    // The shared-vertex mesh, compacted on the GPU. Never truncated (buffers grow to the exact counts).
    ExportedMesh exportMesh(std::vector<std::pair<std::string, double>>* stageMs = nullptr);
    // Throws away the mesh state (not the TSDF) and rebuilds it from scratch over every block: the
    // reference an incremental mesh must equal.
    void rebuildMesh();
    // The last compacted mesh (publishMesh, or the last exportMesh()); empty handles before any.
    MeshBuffers meshBuffers() const;
    MeshStateSnapshot downloadMeshState() const;
    // Grows the vertex heap and the triangle-chunk heap between frames (never shrinks; the mesh is kept: the
    // heaps are copied and the new entries pushed on the free stacks). The next frame also re-meshes every
    // cube left INCOMPLETE while a heap was full, so the missing triangles appear at once.
    void growMeshHeaps(uint32_t vertexCapacity, uint32_t chunkCapacity);
    // Rehashes the block hash into a table of `hashCapacity` slots (a power of two, larger than now) between
    // frames: every block and its stamp are kept (BlockHash::grow). Throws if some live block found no slot.
    void growHash(uint32_t hashCapacity);
    const BlockHash& blockHash() const { return hash_; }
    // How many cubes carry triangles of each MC type (the stored, possibly refined, type).
    std::array<uint64_t, 256> surfaceCubeTypes() const;

    std::vector<BlockSnapshot> downloadBlocks() const;
    Counters readCounters() const;
    std::vector<PoolInfo> pools() const;
    const GpuVolumeConfig& config() const { return config_; }
    bool recycling() const { return config_.keepRadius > 0.0f || config_.recycle; }
    uint32_t framesIntegrated() const { return frameNumber_; }

private:
    vk::Buffer makeBuffer(VkDeviceSize size, VkBufferUsageFlags extraUsage, const std::string& name, uint32_t binding);
    void recordCountersReadback(VkCommandBuffer cmd);
    Counters runBaselinePass(std::vector<std::pair<std::string, double>>* stageMs);
    void resetMeshState();
    void setParam(uint32_t VolumeParamsGpu::*field, uint32_t value);
    // Export buffers hold at least this many vertices and triangles (grown with headroom, params updated).
    void ensureExportCapacity(uint32_t vertices, uint32_t triangles);
    void recordExport(VkCommandBuffer cmd);
    bool exportFits(const Counters& k) const;
    // Compacts the mesh in its own submission, growing the buffers until it fits; returns the counters.
    Counters runExport(std::vector<std::pair<std::string, double>>* stageMs);
    // Records the delta passes and the copy of their state to the host.
    void recordDeltas(VkCommandBuffer cmd);
    // After a submission with recordDeltas: downloads the records, growing the lists and re-running the
    // passes until everything fitted.
    MeshDelta collectDeltas();

    const vk::Context& context_;
    GpuVolumeConfig config_;
    vk::BindingTable layout_;
    BlockHash hash_;
    vk::Buffer params_, counters_, blockCoords_, voxelSdf_, voxelWeight_,
        freeList_, touched_, depth_, mcTables_, blockList_, meshVertices_;
    vk::Buffer cubeState_, edgeVertexX_, edgeVertexY_, edgeVertexZ_, meshStamps_, dirtyList_, vertices_, vertexOwner_, vertexFree_, garbage_,
        chunkTriangles_, chunkFree_, exportVertices_, exportIndices_, vertexRemap_, retypeMask_, retypeList_;
    vk::Buffer depthStaging_, countersReadback_;
    // Mesh deltas (trackDeltas only).
    std::optional<vk::BindingTable> deltaLayout_;
    std::optional<MeshDeltaStage> deltaStage_;
    vk::Buffer prevVertices_, prevChunks_, deltaState_, deltaVertexRecords_, deltaTriangleRecords_, deltaStateReadback_;
    uint32_t exportVertexCapacity_ = 0, exportTriangleCapacity_ = 0;
    bool meshPublished_ = false;
    AllocateBlocksStage allocate_;
    FuseDepthStage fuse_;
    BaselineMeshStage baselineMesh_;
    IncrementalMeshStage incrementalMesh_;
    ExportMeshStage exportMesh_;
    RecycleStage recycle_;
    vk::CommandRecorder recorder_;
    vk::StageTimer timer_;
    uint32_t frameNumber_ = 0;
    bool retryPending_ = false;   // next frame: dirty every block with retype bits left (see growMeshHeaps)
    FramePush lastPush_{};
};

}  // namespace vkmesh::gpu
