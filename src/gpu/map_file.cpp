// GpuVolume's map files (docs/MAPFILE.md): the volume asks each component for its sections (BlockStore: the
// live blocks' per-corner arrays and the free list; CubeMesh: per-cube arrays, heaps, free stacks; FrameLists:
// retype masks; BlockHash: the live blocks' coordinates and stamps) and adds what it keeps itself (settings,
// counters, frame numbers). The byte layout and the checks of a file are in src/core/map_format.cpp.
//
// The hash is not stored as slots: their key words differ between the 64-bit and the 32-bit hash path and
// their order depends on the table size. A loaded map lists its live blocks (block list) with each one's
// hash stamp in its coordinate's w, which is exactly what the GPU's own rehash pass (rehash_insert, used by
// hash growth and rebuilds) reads, so the table is rebuilt by the code that builds it every day, on any
// device and at any capacity, without a shader or a host copy of the key layout.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <random>
#include <set>

#include "core/map_merge.h"
#include "gpu/capacities.h"
#include "gpu/gpu_volume.h"

namespace vkmesh::gpu {

namespace {

// What a map file records of a configuration (map::Settings).
map::Settings settingsOf(const GpuVolumeConfig& c, bool touchedFollowsPool) {
    const VolumeParams& p = c.params;
    return {p.voxelSize, p.truncVoxels, p.maxWeight, p.minDepth, p.maxDepth, uint32_t(p.allocationStride), c.minMeshWeight,
            c.meshMode == MeshMode::Incremental ? 1u : 0u, c.refine ? 1u : 0u, c.refineEpsilonVoxels, c.lockFree ? 1u : 0u,
            c.vertexUpdate, c.keepRadius, c.recycle ? 1u : 0u, c.recycleAfterFrames, c.starveWeight,
            c.hashRebuildTombstoneFraction, uint32_t(c.imageWidth), uint32_t(c.imageHeight), c.growCapacities ? 1u : 0u,
            touchedFollowsPool ? 1u : 0u, uint32_t(p.colorFusion), p.colorRecency,
            p.allocationTiles ? uint32_t(p.allocationTileRules) : 0u};
}

}  // namespace

map::MapData GpuVolume::saveMap() const {
    requireNothingPaged("saving a map");
    map::MapData m;
    const GpuVolumeConfig& c = config_;
    m.features = (c.meshMode == MeshMode::Incremental ? map::FEATURE_INCREMENTAL_MESH : 0u) |
                 (c.params.colorFusion != ColorFusion::Off ? map::FEATURE_COLOR : 0u);
    m.settings = settingsOf(c, touchedFollowsPool_);
    m.capacities = {c.blockCapacity, c.hashCapacity, c.touchedCapacity, c.retypeCapacity, c.vertexCapacity, c.chunkCapacity};
    m.frameNumber = frameNumber_;
    m.framesIntegrated = framesIntegrated_;
    m.retryPending = retryPending_ ? 1u : 0u;
    vk::downloadFromBuffer(context_, counters_.buffer(), &m.counters, sizeof(Counters));
    m.lastPush = lastPush_;
    // The live blocks, in pool order (the same file whatever the hash's slot order was).
    std::vector<BlockHash::Entry> entries = hash_.downloadEntries();
    std::erase_if(entries, [](const BlockHash::Entry& e) { return e.block == NO_BLOCK; });
    std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.block < b.block; });
    std::vector<uint32_t> blocks;
    for (const BlockHash::Entry& e : entries) {
        m.blocks.push_back({e.x, e.y, e.z, e.block, e.stamp, {}});
        blocks.push_back(e.block);
    }
    store_.save(m, blocks, m.counters.freeTop);
    mesh_.save(m, blocks, m.counters);
    lists_.saveRetypeMasks(m, blocks);
    return m;
}

uint64_t GpuVolume::save(const std::filesystem::path& path) const {
    map::MapData m = saveMap();
    std::random_device random;
    m.saveId = uint64_t(random()) << 32 | random();
    map::writeFile(path, m);
    return m.saveId;
}

GpuVolumeConfig GpuVolume::mapConfig(const map::MapData& m) {
    const map::Settings& s = m.settings;
    GpuVolumeConfig c;
    c.params.voxelSize = s.voxelSize;
    c.params.truncVoxels = s.truncVoxels;
    c.params.maxWeight = s.maxWeight;
    c.params.minDepth = s.minDepth;
    c.params.maxDepth = s.maxDepth;
    c.params.allocationStride = int(s.allocationStride);
    c.params.allocationTiles = s.allocationTiles != 0;
    if (s.allocationTiles != 0) c.params.allocationTileRules = int(s.allocationTiles);
    c.params.colorFusion = ColorFusion(s.colorMode);
    c.params.colorRecency = s.colorRecency;
    c.minMeshWeight = s.minMeshWeight;
    c.meshMode = s.incrementalMesh ? MeshMode::Incremental : MeshMode::Baseline;
    c.refine = s.refine != 0;
    c.refineEpsilonVoxels = s.refineEpsilonVoxels;
    c.lockFree = s.lockFree != 0;
    c.vertexUpdate = s.vertexUpdate;
    c.keepRadius = s.keepRadius;
    c.recycle = s.recycle != 0;
    c.recycleAfterFrames = s.recycleAfterFrames;
    c.starveWeight = s.starveWeight;
    c.hashRebuildTombstoneFraction = s.hashRebuildTombstoneFraction;
    c.imageWidth = int(s.imageWidth);
    c.imageHeight = int(s.imageHeight);
    c.growCapacities = s.growCapacities != 0;
    const map::Capacities& k = m.capacities;
    c.blockCapacity = k.blocks;
    c.hashCapacity = k.hashSlots;
    c.touchedCapacity = s.touchedFollowsPool ? 0 : k.touched;   // 0: follows the block pool, as it did
    c.retypeCapacity = k.retype;
    c.vertexCapacity = k.vertices;
    c.chunkCapacity = k.chunks;
    return c;
}

namespace {

// The settings that change what a frame computes (map::settingDifferences): a volume continuing a map must have
// the map's. It follows the map's allocation rules, so allocation by tiles is compared as on or off.
void checkSettings(const GpuVolumeConfig& want, const GpuVolumeConfig& map, const std::string& name) {
    const std::vector<map::SettingDifference> d = map::settingDifferences(settingsOf(map, true), settingsOf(want, true),
                                                                          map::AllocationRules::OnOrOff);
    if (!d.empty())
        throw Error(name + ": the map was fused with " + d[0].what + " " + std::to_string(d[0].a) + " but " + std::to_string(d[0].b) +
                    " was asked for (" + d[0].option + "); continue a map with its own settings");
}

}  // namespace

std::unique_ptr<GpuVolume> GpuVolume::load(const vk::Context& context, const map::MapData& m, const GpuVolumeConfig& config,
                                           const std::string& name) {
    const GpuVolumeConfig saved = mapConfig(m);
    checkSettings(config, saved, name);
    // Every per-corner array this build keeps must be in the map, and the map must hold none it does not know.
    std::set<uint32_t> known(CubeMesh::kCornerTags.begin(), CubeMesh::kCornerTags.end());
    for (const BlockStore::CornerArray& a : BlockStore::kCornerArrays)
        if (!a.colorOnly || saved.params.colorFusion != ColorFusion::Off) known.insert(a.tag);
    for (uint32_t t : known)
        if (!m.corners(t)) throw Error(name + ": the map has no section '" + map::tagName(t) + "'");
    for (const map::CornerArray& a : m.cornerArrays)
        if (!known.count(a.tag)) throw Error(name + ": the map has a per-block section '" + map::tagName(a.tag) + "' this build does not know");
    // Capacities: the larger of the map's and the caller's (a map loads into a bigger configuration).
    GpuVolumeConfig c = config;
    c.params.allocationTileRules = saved.params.allocationTileRules;   // the rules its frames were allocated with
    c.blockCapacity = std::max(c.blockCapacity, saved.blockCapacity);
    const uint32_t hashSlots = c.hashCapacity ? c.hashCapacity : nextPowerOfTwo(std::max(2u * c.blockCapacity, 1024u));
    c.hashCapacity = std::max(hashSlots, saved.hashCapacity);
    if (c.touchedCapacity != 0 || saved.touchedCapacity != 0)
        c.touchedCapacity = std::max(c.touchedCapacity ? c.touchedCapacity : c.blockCapacity, m.capacities.touched);
    c.retypeCapacity = std::max(c.retypeCapacity, saved.retypeCapacity);
    c.vertexCapacity = std::max(c.vertexCapacity, saved.vertexCapacity);
    c.chunkCapacity = std::max(c.chunkCapacity, saved.chunkCapacity);
    std::unique_ptr<GpuVolume> volume;
    try {
        volume = std::make_unique<GpuVolume>(context, c);   // checks the configuration and every capacity against the device
    } catch (const Error& e) {
        throw Error(name + ": " + e.what());
    }
    volume->restore(m, name);
    return volume;
}

std::unique_ptr<GpuVolume> GpuVolume::load(const vk::Context& context, const std::filesystem::path& path) {
    const map::MapData m = map::readFile(path);
    return load(context, m, mapConfig(m), path.string());
}

void GpuVolume::restore(const map::MapData& m, const std::string& name) {
    std::vector<uint32_t> blocks;
    blocks.reserve(m.blocks.size());
    for (const map::Block& b : m.blocks) blocks.push_back(b.index);
    store_.load(m, blocks, counters_);
    mesh_.load(m, blocks, counters_);
    lists_.loadRetypeMasks(m, blocks);
    lists_.uploadBlockList(blocks);
    // The counters as saved, except what belongs to this volume's capacities (free-stack tops, set by the
    // loads above) and the hash's counts, which the re-insertion sets (hashEntries = live blocks).
    counters_.update([&](Counters& k) {
        Counters saved = m.counters;
        saved.freeTop = k.freeTop;
        saved.vertexFreeTop = k.vertexFreeTop;
        saved.chunkFreeTop = k.chunkFreeTop;
        saved.liveBlockCount = uint32_t(blocks.size());
        saved.rehashLost = 0;
        k = saved;
    });
    frameNumber_ = m.frameNumber;
    framesIntegrated_ = m.framesIntegrated;
    retryPending_ = m.retryPending != 0;
    lastPush_ = m.lastPush;
    VkCommandBuffer cmd = beginSubmission();
    hash_.recordReinsert(cmd, lastPush_, config_.blockCapacity);
    counters_.recordReadback(cmd);
    recorder_.submitAndWait();
    const Counters k = counters_.read();
    if (k.rehashLost)
        throw Error(name + ": " + std::to_string(k.rehashLost) + " blocks found no hash slot within " + std::to_string(HASH_MAX_PROBES) +
                    " probes in a table of " + std::to_string(config_.hashCapacity) + " slots (give more --hash-slots)");
    if (config_.refine && config_.meshMode == MeshMode::Incremental) {
        // The meshing signs and the masks of the TSDF are not saved (they follow from the TSDF): the masks are
        // set from the TSDF and the signs decided here for every corner of every block (all blocks dirty), so
        // that a dirty block's cube reading a clean neighbour's corner finds its sign. The mesh was built with the same signs, so the masks are then put back as saved,
        // and so are the counters.
        cmd = beginSubmission();
        counters_.recordClearFrame(cmd);
        vkCmdFillBuffer(cmd, lists_.retypeMasks().handle(), 0, VK_WHOLE_SIZE, MASK_ALL_CUBES);
        vk::memoryBarrier(cmd);
        markDirty_.recordAll(cmd, lastPush_, config_.blockCapacity);
        retype_.recordMeshSigns(cmd, lastPush_, counters_, true);
        vkCmdFillBuffer(cmd, lists_.retypeMasks().handle(), 0, VK_WHOLE_SIZE, 0);
        vk::memoryBarrier(cmd);
        recorder_.submitAndWait();
        lists_.loadRetypeMasks(m, blocks);
        counters_.update([&](Counters& now) { now = k; });
    }
    if (config_.publishMesh && config_.meshMode == MeshMode::Incremental) runExport(nullptr);
}

}  // namespace vkmesh::gpu
