// GpuVolume (gpu_volume.h): construction of the data structure's components and stages, meshes on demand
// (baseline, export, completion, rebuild) and downloads. The frame itself is in frame.cpp, capacities and growth
// in capacities.cpp, map files in map_file.cpp.
#include "gpu/gpu_volume.h"

#include "gpu/capacities.h"

#include <algorithm>
#include <iterator>

#include "core/marching_cubes.h"
#include "core/tsdf_corner.h"
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

static_assert(VolumeParams{}.allocationTileRules == int(ALLOC_TILE_RULES), "a new volume decides its tiles by the current rules");

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
    if (p.allocationTileRules != int(ALLOC_TILE_RULES_FIRST) && p.allocationTileRules != int(ALLOC_TILE_RULES))
        throw Error("allocation tile rules " + std::to_string(p.allocationTileRules) + " are not " +
                    std::to_string(ALLOC_TILE_RULES_FIRST) + " or " + std::to_string(ALLOC_TILE_RULES));
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
    // Paging: the pool need not start larger than the budget and the quarter it keeps free (it grows past that when
    // the camera's reach needs more).
    if (c.residentBlocks > 0) c.blockCapacity = std::min(c.blockCapacity, std::max(1024u, c.residentBlocks + c.residentBlocks / 4));
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
    if (c.residentBlocks > 0 && c.meshMode != MeshMode::Incremental)
        throw Error("paging (resident blocks " + std::to_string(c.residentBlocks) +
                    ") needs the incremental mesh: the baseline mesh is extracted from every block at once");
    if (c.residentBlocks > 0 && (c.keepRadius > 0.0f || c.recycle))
        throw Error("paging (resident blocks " + std::to_string(c.residentBlocks) +
                    ") keeps every block and a bounded map (keep radius, recycling) forgets them: choose one");
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
    const TsdfFixedPoint fixed = tsdfFixedPoint(c.params.truncation());
    gp.sdfStepsPerMetre = fixed.stepsPerMetre;
    gp.sdfMetresPerStep = fixed.metresPerStep;
    gp.minMeshWeight = c.minMeshWeight;
    gp.hashCapacity = c.hashCapacity;
    gp.blockCapacity = c.blockCapacity;
    gp.touchedCapacity = c.touchedCapacity;
    gp.meshVertexCapacity = c.meshVertexCapacity;
    gp.allocationStride = uint32_t(c.params.allocationStride);
    gp.allocationTiles = c.params.allocationTiles ? uint32_t(c.params.allocationTileRules) : 0u;
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
      timer_(context, config.timePasses ? 192 : 32) {
    const GpuVolumeConfig& c = config_;
    timer_.setEnabled(c.timeStages);
    if (c.timeStages && c.timePasses)
        table_.setDispatchObserver([this](VkCommandBuffer cmd, const std::string& pass) {
            if (recordingFrame_) timer_.markPass(cmd, pass);
        });
    touchedFollowsPool_ = config.touchedCapacity == 0;
    // The depth image, then (when colour is fused) the colour image's RGBA8 words: one binding for both.
    const VkDeviceSize pixels = VkDeviceSize(c.imageWidth) * c.imageHeight;
    // On a device with unified memory the host writes the images into it directly; elsewhere they go through a
    // staging buffer and a copy (on lavapipe the copy and the second write were ~0.5 ms of a ~15 ms frame).
    const VkDeviceSize inputBytes = pixels * 4 * (fusesColor() ? 2 : 1);
    if (context.unifiedMemory()) {
        depth_ = vk::Buffer(context, inputBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, vk::MemoryUse::DeviceMapped, "depth image");
        table_.bind(BINDING_DEPTH, depth_);
    } else {
        depth_ = makeStorage(context, table_, BINDING_DEPTH, inputBytes, "depth image");   // name kept: a --stats key
        depthStaging_ = vk::Buffer(context, inputBytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::Upload, "depth staging");
    }
    // A word per allocation tile (allocate_tiles, shared_layout.h ALLOC_TILE), rewritten every frame.
    const auto tilesAlong = [&](int pixelsAlong) {
        const uint32_t stride = uint32_t(c.params.allocationStride), samples = (uint32_t(pixelsAlong) + stride - 1) / stride;
        return VkDeviceSize((samples + ALLOC_TILE - 1) / ALLOC_TILE);
    };
    allocTiles_ = makeStorage(context, table_, BINDING_ALLOC_TILES,
                              std::max<VkDeviceSize>(1, tilesAlong(c.imageWidth) * tilesAlong(c.imageHeight)) * 4, "allocation tiles");
    mcTables_ = vk::Buffer(context, MC_TABLE_WORDS * 4, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, vk::MemoryUse::Device, "marching cubes tables");
    table_.bind(BINDING_MC_TABLES, mcTables_);
    framePose_ = vk::Buffer(context, sizeof(FramePoseGpu),
                            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                            vk::MemoryUse::Device, "frame pose");
    table_.bind(BINDING_FRAME_POSE, framePose_);
    framePoseReadback_ = vk::Buffer(context, sizeof(FramePoseGpu), VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::Readback,
                                    "frame pose readback");
    const auto tables = packMarchingCubesTables();
    vk::uploadToBuffer(context, mcTables_, tables.data(), tables.size() * 4);
    exportMesh_.emplace(context, table_, params_);
    if (c.trackDeltas) deltas_.emplace(context, counters_, mesh_, c.deltaRecordCapacity);
    if (c.residentBlocks > 0) paging_.emplace(context, table_);
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
    requireNothingPaged("countBaselineVertices");
    // The GPU counts every vertex the pass wants, whether or not it fit in the buffer.
    return runBaselinePass(nullptr).meshVertices;
}

TriangleSoup GpuVolume::extractBaselineMesh(std::vector<std::pair<std::string, double>>* stageMs) {
    requireNothingPaged("extractBaselineMesh");
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

MeshBuffers GpuVolume::recordModelView(VkCommandBuffer cmd, const Pose& cameraToWorld, const Intrinsics& intrinsics, int width, int height,
                                        float nearDepth, float farDepth, uint32_t createdBefore) {
    if (config_.meshMode != MeshMode::Incremental) throw Error("the model in a view needs the incremental mesh mode (it lists its chunks)");
    if (!modelView_) modelView_.emplace(context_, store_, hash_, mesh_, config_.params.voxelSize);
    modelView_->record(cmd, cameraToWorld, intrinsics, width, height, nearDepth, farDepth, createdBefore);
    recordMeshReadBarrier(cmd);   // the list and its command, for the draw
    MeshBuffers b;
    b.vertices = mesh_.vertices().handle();
    b.indices = modelView_->indices().handle();
    b.drawIndirect = modelView_->state().handle();
    b.drawIndirectOffset = ModelViewStage::drawOffset();
    b.frame = frameNumber_;
    return b;
}

std::vector<std::array<uint32_t, 3>> GpuVolume::downloadModelView() const {
    return modelView_ ? modelView_->downloadList() : std::vector<std::array<uint32_t, 3>>{};
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
    requireNothingPaged("rebuildMesh");
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

std::vector<uint32_t> GpuVolume::downloadMeshSigns() const {
    std::vector<uint32_t> words(size_t(lists_.capacities().blocks) * MESH_SIGN_WORDS);
    vk::downloadFromBuffer(context_, lists_.meshSigns(), words.data(), words.size() * 4);
    return words;
}

std::vector<BlockSnapshot> GpuVolume::downloadBlocks() const {
    std::vector<uint32_t> blocks;
    for (const BlockHash::Entry& e : hash_.downloadEntries())
        if (e.block != NO_BLOCK) blocks.push_back(e.block);
    std::vector<BlockSnapshot> out = store_.download(blocks, tsdfFixedPoint(config_.params.truncation()).metresPerStep);
    // Paged-out blocks as they wait on the host (index NO_BLOCK).
    std::vector<BlockSnapshot> paged = pagedBlockSnapshots();
    out.insert(out.end(), std::make_move_iterator(paged.begin()), std::make_move_iterator(paged.end()));
    return out;
}

std::vector<PoolInfo> GpuVolume::pools() const {
    std::vector<PoolInfo> out;
    params_.pools(out);
    counters_.pools(out);
    hash_.pools(out);
    store_.pools(out);
    mesh_.pools(out);
    if (paging_) paging_->pools(out);
    lists_.pools(out);
    listPools(out, {&depth_, &depthStaging_, &allocTiles_, &mcTables_});
    // Listed with no bytes where the host writes depth_ in place: --stats keeps the key users' scripts read.
    if (!depthStaging_.handle()) out.push_back({"depth staging", 0});
    baselineMesh_.pools(out);
    exportMesh_->pools(out);
    if (deltas_) deltas_->pools(out);
    if (modelView_) modelView_->pools(out);
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
