#include "api/map_merge.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <random>
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

    t0 = std::chrono::steady_clock::now();   // reading the frame stores counts as reading
    std::vector<FrameStore> stores;
    size_t withoutStore = 0;
    for (size_t i = 0; i < inputs.size(); ++i) {
        MergeInputReport in{inputs[i].string(), maps[i].blocks.size(), maps[i].framesIntegrated, false, 0};
        const std::filesystem::path storePath = gpu::frameStorePathOf(inputs[i]);
        if (options.keepFrames && std::filesystem::exists(storePath)) {
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
        report.warnings.push_back("the loop closers' states (.vkloops) are not merged: a run continuing the merged map with --loop-closure "
                                  "starts with no keyframes");
    report.mergeMs += millisecondsSince(t0);

    // The mesh of the sum, built from scratch on the GPU.
    t0 = std::chrono::steady_clock::now();
    std::optional<vk::Context> own;
    const vk::Context& context = external ? *external : own.emplace(options.device);
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

MergeReport mergeMaps(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output, const MergeOptions& options) {
    return merge(nullptr, inputs, output, options);
}

MergeReport mergeMaps(const vk::Context& context, const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& output,
                      const MergeOptions& options) {
    return merge(&context, inputs, output, options);
}

}  // namespace vkmesh
