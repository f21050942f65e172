#include "api/map_merge.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <system_error>

#include "api/exported_mesh.h"
#include "api/loop_closure.h"
#include "core/map_format.h"
#include "core/map_merge.h"
#include "gpu/gpu_volume.h"
#include "gpu/map_corrector.h"

namespace vkmesh {

namespace {

double millisecondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The inputs' frame stores, in one store. Indices are kept when no two inputs share one (split runs of one
// dataset, fused with its frame numbers); otherwise each input's are moved past the previous one's.
FrameStore mergeFrameStores(std::vector<FrameStore>& stores, const MergeOptions& options, MergeReport& report) {
    bool overlap = false;
    std::map<uint32_t, size_t> owner;
    for (size_t i = 0; i < stores.size() && !overlap; ++i)
        for (uint32_t index : stores[i].indices())
            if (!owner.emplace(index, i).second) overlap = true;
    FrameStore merged(options.frames);
    uint64_t offset = 0;
    for (FrameStore& s : stores) {
        const std::vector<uint32_t> indices = s.indices();
        const uint64_t next = indices.empty() ? offset : offset + indices.back() + 1;
        merged.absorb(std::move(s), overlap ? uint32_t(offset) : 0u);
        if (overlap) offset = next;
    }
    report.framesRenumbered = overlap;
    // Correction matches trajectory lines to frames by timestamp: two frames with one timestamp cannot both be corrected.
    std::map<double, uint32_t> byTime;
    size_t repeated = 0;
    for (uint32_t index : merged.indices())
        if (!byTime.emplace(merged.timestamp(index), index).second) ++repeated;
    if (repeated)
        report.warnings.push_back(std::to_string(repeated) + " kept frames share a timestamp with another: vkmesh correct matches trajectory "
                                  "lines by timestamp and will re-fuse only the first of each");
    return merged;
}

// ---- tiles ---------------------------------------------------------------------------------------------------

// The tile (TileKey) of a block: its origin's metres divided by the tile size, rounded down, per axis. Tiles hold
// whole blocks.
int32_t tileOfBlock(int32_t block, double blockMetres, double tileSize) { return int32_t(std::floor(double(block) * blockMetres / tileSize)); }

TileKey tileOf(int32_t x, int32_t y, int32_t z, double blockMetres, double tileSize) {
    return {tileOfBlock(x, blockMetres, tileSize), tileOfBlock(y, blockMetres, tileSize), tileOfBlock(z, blockMetres, tileSize)};
}

void checkTileSize(double tileSize) {
    if (!(tileSize > 0) || !std::isfinite(tileSize))
        throw Error("merge: tile size " + std::to_string(tileSize) + " must be a positive number of metres (0: no tiles)");
}

// A tile's blocks and the blocks it is meshed from: its own (`own`, whose cubes' triangles it keeps) and one block
// around them (every cube of the tile reads corners at most one block away: its own corners, refinement's window, the
// normals' gradients). Both clamped to the block coordinates a map holds; `empty` when the tile holds none of them.
struct TileBlocks {
    map::BlockBox own, meshed;
    bool empty = false;
};
TileBlocks blocksOfTile(const TileKey& tile, double blockMetres, double tileSize) {
    const int64_t lowest = -int64_t(gpu::KEY_BIAS), highest = int64_t(gpu::KEY_BIAS) - 1;
    TileBlocks out;
    for (int a = 0; a < 3; ++a) {
        const int32_t t = tile[a];
        // Along this axis, the first block whose tile is at least t and the last whose tile is at most t (tileOfBlock
        // grows with the block): a guess from the tile's metres, then stepped to the exact ends, since the division
        // rounds. A tile outside the coordinates stops the steps at their ends.
        const double guess = std::clamp(std::floor(double(t) * tileSize / blockMetres), double(lowest - 2), double(highest + 2));
        auto tileOfWide = [&](int64_t b) { return std::floor(double(b) * blockMetres / tileSize); };
        int64_t first = int64_t(guess), last = int64_t(guess);
        while (first > lowest - 2 && tileOfWide(first - 1) >= t) --first;
        while (first < highest + 2 && tileOfWide(first) < t) ++first;
        while (last < highest + 2 && tileOfWide(last + 1) <= t) ++last;
        while (last > lowest - 2 && tileOfWide(last) > t) --last;
        const int64_t ownLo = std::max(first, lowest), ownHi = std::min(last, highest);
        const int64_t lo = std::max(first - 1, lowest), hi = std::min(last + 1, highest);
        if (ownLo > ownHi || lo > hi) {
            out.empty = true;
            return out;
        }
        out.own.lo[a] = int32_t(ownLo), out.own.hi[a] = int32_t(ownHi);
        out.meshed.lo[a] = int32_t(lo), out.meshed.hi[a] = int32_t(hi);
    }
    return out;
}

// The block a triangle belongs to: the one holding its centroid (its three vertices lie strictly inside edges of one
// cube; the centroid is taken in a fixed order of the vertices' bits, so every tile computes the same one).
std::array<int32_t, 3> blockOfTriangle(const Mesh& m, const std::array<uint32_t, 3>& t, float voxel) {
    std::array<Eigen::Vector3f, 3> p = {m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]};
    std::sort(p.begin(), p.end(), [](const Eigen::Vector3f& a, const Eigen::Vector3f& b) { return std::memcmp(a.data(), b.data(), 12) < 0; });
    const Eigen::Vector3f c = (p[0] + p[1] + p[2]) / 3.0f;
    std::array<int32_t, 3> block;
    for (int a = 0; a < 3; ++a) block[a] = int32_t(std::floor(std::floor(c[a] / voxel) / float(gpu::BLOCK_SIDE)));
    return block;
}

// The triangles of `mesh` that belong to `tile`, with the vertices they use.
Mesh trianglesOfTile(const Mesh& mesh, const TileKey& tile, float voxel, double tileSize) {
    const double blockMetres = double(voxel) * gpu::BLOCK_SIDE;
    Mesh out;
    std::vector<uint32_t> remap(mesh.positions.size(), UINT32_MAX);
    auto vertex = [&](uint32_t v) {
        if (remap[v] == UINT32_MAX) {
            remap[v] = uint32_t(out.positions.size());
            out.positions.push_back(mesh.positions[v]);
            if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[v]);
            if (!mesh.colors.empty()) out.colors.push_back(mesh.colors[v]);
            if (!mesh.vertexAge.empty()) out.vertexAge.push_back(mesh.vertexAge[v]);
        }
        return remap[v];
    };
    for (const auto& t : mesh.triangles) {
        const std::array<int32_t, 3> b = blockOfTriangle(mesh, t, voxel);
        if (tileOf(b[0], b[1], b[2], blockMetres, tileSize) != tile) continue;
        out.triangles.push_back({vertex(t[0]), vertex(t[1]), vertex(t[2])});
    }
    return out;
}

// A part of the sum (a tile's blocks and those around it), loaded alone, meshed from scratch and cut to the tile's
// own triangles.
Mesh meshTileOfPart(const vk::Context& context, map::MapData part, const TileKey& tile, double tileSize) {
    const float voxel = part.settings.voxelSize;
    // Capacities for this part, not for the inputs' whole maps; the heaps grow as the mesh needs.
    const uint32_t n = uint32_t(part.blocks.size());
    uint32_t slots = 1024;
    while (slots < 2 * n) slots *= 2;
    part.capacities = {std::max(n, 64u), slots, 0, 1u << 16, std::max(n * 128, 4096u), std::max(n * 64, 2048u)};
    gpu::GpuVolumeConfig config = gpu::GpuVolume::mapConfig(part);
    config.growCapacities = true;
    std::unique_ptr<gpu::GpuVolume> volume = gpu::GpuVolume::load(context, part, config, tileFileName(tile));
    volume->rebuildMesh();
    return trianglesOfTile(toMesh(volume->exportMesh(), volume->frameNumber()), tile, voxel, tileSize);
}

// Meshes the sum tile by tile from inputs held whole: each tile's part added from them, meshed alone. The GPU holds
// one tile at a time.
void meshTiles(const vk::Context& context, const std::vector<map::MergeInput>& inputs, const MergeOptions& options, MergeReport& report) {
    const double blockMetres = double(inputs[0].map->settings.voxelSize) * gpu::BLOCK_SIDE, size = options.tileSize;
    std::set<TileKey> tiles;
    for (const map::MergeInput& in : inputs)
        for (const map::Block& b : in.map->blocks) tiles.insert(tileOf(b.x, b.y, b.z, blockMetres, size));
    for (const TileKey& tile : tiles) {
        const map::BlockBox box = blocksOfTile(tile, blockMetres, size).meshed;   // the tile holds a block: not empty
        map::MapData part = map::merge(inputs, nullptr, [&](int32_t x, int32_t y, int32_t z) { return box.contains(x, y, z); });
        report.tileBlocksMax = std::max<size_t>(report.tileBlocksMax, part.blocks.size());
        const Mesh mesh = meshTileOfPart(context, std::move(part), tile, size);
        if (mesh.triangles.empty()) continue;
        ++report.tiles;
        report.tileTriangles += mesh.triangles.size();
        options.tileSink(tile, mesh);
    }
}

// The inputs opened for partial reads (header and block table each), checked to add up: map::merge of their
// headers alone (no block) makes every refusal that needs no corner, before any tile is read.
std::vector<map::BlockReader> openForTiles(const std::vector<std::filesystem::path>& inputs) {
    if (inputs.empty()) throw Error("merge: no maps given");
    std::vector<map::BlockReader> readers;
    readers.reserve(inputs.size());
    for (const std::filesystem::path& p : inputs) readers.emplace_back(p);
    std::vector<map::MapData> headers;
    headers.reserve(readers.size());
    for (map::BlockReader& r : readers) headers.push_back(r.read([](int32_t, int32_t, int32_t) { return false; }));
    std::vector<map::MergeInput> named;
    for (size_t i = 0; i < readers.size(); ++i) named.push_back({readers[i].name(), &headers[i]});
    map::merge(named);
    return readers;
}

TilesReport makeTiles(const vk::Context* external, const std::vector<std::filesystem::path>& inputs, const std::vector<TileKey>& tiles,
                      const TileOptions& options) {
    checkTileSize(options.tileSize);
    if (!options.tileSink) throw Error("merge: tiles asked for with no tileSink to take them");
    TilesReport report;
    auto t0 = std::chrono::steady_clock::now();
    std::vector<map::BlockReader> readers = openForTiles(inputs);
    for (const map::BlockReader& r : readers) report.tableBlocks += r.blocks().size();
    const double blockMetres = double(readers[0].header().settings.voxelSize) * gpu::BLOCK_SIDE, size = options.tileSize;
    std::optional<vk::Context> own;
    const vk::Context& context = external ? *external : own.emplace(options.device);
    report.openMs = millisecondsSince(t0);

    for (const TileKey& tile : tiles) {
        TileReport& r = report.tiles.emplace_back();
        r.tile = tile;
        const TileBlocks blocks = blocksOfTile(tile, blockMetres, size);
        if (blocks.empty) continue;
        t0 = std::chrono::steady_clock::now();
        std::vector<map::MapData> parts;
        parts.reserve(readers.size());
        bool ownBlock = false;   // a triangle belongs to a block of the tile: without one, nothing to mesh
        for (map::BlockReader& reader : readers) {
            parts.push_back(reader.read(blocks.meshed));
            r.blocksRead += parts.back().blocks.size();
            for (const map::Block& b : parts.back().blocks) ownBlock = ownBlock || blocks.own.contains(b.x, b.y, b.z);
        }
        report.hostBlocksMax = std::max(report.hostBlocksMax, r.blocksRead);
        if (!ownBlock) continue;
        std::vector<map::MergeInput> named;
        for (size_t i = 0; i < readers.size(); ++i) named.push_back({readers[i].name(), &parts[i]});
        map::MapData sum = map::merge(named);
        r.blocksMeshed = sum.blocks.size();
        report.hostBlocksMax = std::max(report.hostBlocksMax, r.blocksRead + r.blocksMeshed);
        report.gpuBlocksMax = std::max(report.gpuBlocksMax, r.blocksMeshed);
        parts.clear();   // the parts are in the sum: the GPU work below holds the sum only
        r.readMs = millisecondsSince(t0);

        t0 = std::chrono::steady_clock::now();
        const Mesh mesh = meshTileOfPart(context, std::move(sum), tile, size);
        r.vertices = mesh.positions.size();
        r.triangles = mesh.triangles.size();
        if (!mesh.triangles.empty()) options.tileSink(tile, mesh);
        r.meshMs = millisecondsSince(t0);
    }
    return report;
}

// `external`: the caller's device; nullptr: options.device, opened after every check on the host.
MergeReport merge(const vk::Context* external, const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output,
                  const MergeOptions& options) {
    if (inputs.empty()) throw Error("merge: no maps given");
    MergeReport report;
    auto t0 = std::chrono::steady_clock::now();
    std::vector<map::MapData> maps;
    maps.reserve(inputs.size());
    for (const std::filesystem::path& p : inputs) maps.push_back(map::readFile(p));   // every file checked
    std::vector<map::MergeInput> named;
    for (size_t i = 0; i < maps.size(); ++i) named.push_back({inputs[i].string(), &maps[i]});
    report.readMs = millisecondsSince(t0);

    t0 = std::chrono::steady_clock::now();
    map::MergeSummary summary;
    map::MapData merged = map::merge(named, &summary);   // every refusal, before a device is opened
    report.blocks = summary.blocks, report.sharedBlocks = summary.sharedBlocks, report.corners = summary.corners;
    report.framesIntegrated = merged.framesIntegrated;
    report.mergeMs = millisecondsSince(t0);

    if (options.tileSize > 0 && !options.tileSink) throw Error("merge: tiles asked for (MergeOptions::tileSize) with no tileSink to take them");
    if (output.empty() && !(options.tileSize > 0)) throw Error("merge: no output map and no tiles: nothing to write");
    if (!(options.tileSize >= 0) || !std::isfinite(options.tileSize))
        throw Error("merge: tile size " + std::to_string(options.tileSize) + " must be a positive number of metres (0: no tiles)");

    t0 = std::chrono::steady_clock::now();   // reading the frame stores counts as reading
    std::vector<FrameStore> stores;
    size_t withoutStore = 0;
    for (size_t i = 0; i < inputs.size(); ++i) {
        MergeInputReport in{inputs[i].string(), maps[i].blocks.size(), maps[i].framesIntegrated, false, 0};
        const std::filesystem::path storePath = gpu::frameStorePathOf(inputs[i]);
        if (output.empty()) {
            // tiles only: no map, so no frames to keep beside it
        } else if (options.keepFrames && std::filesystem::exists(storePath)) {
            stores.push_back(FrameStore::load(storePath.string(), maps[i].saveId, options.frames));
            in.frameStore = true;
            in.framesStored = stores.back().size();
        } else if (maps[i].framesIntegrated > 0) {
            ++withoutStore;
        }
        report.inputs.push_back(in);
    }
    report.readMs += millisecondsSince(t0);
    t0 = std::chrono::steady_clock::now();
    FrameStore store = mergeFrameStores(stores, options, report);
    if (!stores.empty() && withoutStore)
        report.warnings.push_back(std::to_string(withoutStore) + " of the maps have no frame store beside them: their frames are in the merged "
                                  "map but cannot be corrected there (vkmesh correct re-fuses kept frames only)");
    if (std::any_of(inputs.begin(), inputs.end(), [](const auto& p) {
            return std::filesystem::exists(loopClosurePathOf(p));
        }))
        report.warnings.push_back("the loop closers' states (.vkloops) are not merged: a run continuing the merged map with loop closure (--track) "
                                  "starts with no keyframes");
    report.mergeMs += millisecondsSince(t0);

    std::optional<vk::Context> own;
    const vk::Context& context = external ? *external : own.emplace(options.device);
    if (options.tileSize > 0) {
        t0 = std::chrono::steady_clock::now();
        meshTiles(context, named, options, report);
        report.tilesMs = millisecondsSince(t0);
    }
    if (output.empty()) return report;

    // The mesh of the sum, built from scratch on the GPU.
    t0 = std::chrono::steady_clock::now();
    gpu::GpuVolumeConfig config = gpu::GpuVolume::mapConfig(merged);
    config.growCapacities = true;   // the mesh of the union may need larger heaps than any input's
    std::unique_ptr<gpu::GpuVolume> volume = gpu::GpuVolume::load(context, merged, config, output.string());
    volume->rebuildMesh();
    const gpu::ExportedMesh exported = volume->exportMesh();
    report.meshVertices = exported.vertices.size();
    report.meshTriangles = exported.triangles.size();
    if (options.returnMesh) report.mesh = toMesh(exported, volume->frameNumber());
    report.rebuildMs = millisecondsSince(t0);

    // The store first, then the map: a map is only used with the store of its own save id.
    t0 = std::chrono::steady_clock::now();
    map::MapData saved = volume->saveMap();
    std::random_device random;
    saved.saveId = uint64_t(random()) << 32 | random();
    const std::filesystem::path storePath = gpu::frameStorePathOf(output);
    std::error_code ignored;   // what an earlier map under this name kept beside it belongs to that map, not to this one
    std::filesystem::remove(loopClosurePathOf(output), ignored);
    if (store.size()) {
        store.save(storePath.string(), saved.saveId);
        report.frameStorePath = storePath.string();
        report.framesStored = store.size();
    } else {
        std::filesystem::remove(storePath, ignored);
    }
    map::writeFile(output, saved);
    report.saveMs = millisecondsSince(t0);
    return report;
}

}  // namespace

TilePlan planTiles(const std::vector<std::filesystem::path>& inputs, double tileSize) {
    checkTileSize(tileSize);
    const std::vector<map::BlockReader> readers = openForTiles(inputs);
    const double blockMetres = double(readers[0].header().settings.voxelSize) * gpu::BLOCK_SIDE;
    std::vector<std::array<int32_t, 3>> coords;   // 12 bytes a block: the sum's blocks are counted once
    for (const map::BlockReader& r : readers)
        for (const map::BlockReader::TableEntry& e : r.blocks()) coords.push_back({e.x, e.y, e.z});
    std::sort(coords.begin(), coords.end());
    coords.erase(std::unique(coords.begin(), coords.end()), coords.end());
    std::set<TileKey> tiles;
    for (const auto& c : coords) tiles.insert(tileOf(c[0], c[1], c[2], blockMetres, tileSize));
    TilePlan plan{std::vector<TileKey>(tiles.begin(), tiles.end()), coords.size(), 0};
    for (const map::BlockReader& r : readers) plan.framesIntegrated += r.header().framesIntegrated;
    return plan;
}

TilesReport mergeTiles(const std::vector<std::filesystem::path>& inputs, const std::vector<TileKey>& tiles, const TileOptions& options) {
    return makeTiles(nullptr, inputs, tiles, options);
}

TilesReport mergeTiles(const vk::Context& context, const std::vector<std::filesystem::path>& inputs, const std::vector<TileKey>& tiles,
                       const TileOptions& options) {
    return makeTiles(&context, inputs, tiles, options);
}

MergeReport mergeMaps(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output, const MergeOptions& options) {
    return merge(nullptr, inputs, output, options);
}

MergeReport mergeMaps(const vk::Context& context, const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output,
                      const MergeOptions& options) {
    return merge(&context, inputs, output, options);
}

}  // namespace vkmesh
