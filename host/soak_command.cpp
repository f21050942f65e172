// `vkmesh soak`: a long run over the synthetic room with revisits, recording per frame how full the hash,
// the block pool and the mesh heaps are, to show that bounded maps (--keep-radius, --recycle) keep them flat.
//   vkmesh soak -o soak.csv [--frames 3000 --laps 6 --width 160 --height 120 --voxel 0.05]
//               [--keep-radius 2.0] [--recycle] [--summary summary.json] [--track]
// With --track every lap is tracked (its first frame placed at its true pose, the rest tracked against the
// mesh) in a new copy of the room, so tracking's cost per frame can be followed as the map grows.
// bench/soak_plot.py draws the CSVs of several runs.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdio>
#include <tuple>
#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include "api/mapper.h"
#include "cli_options.h"
#include "commands.h"
#include "core/camera.h"
#include "synth/synthetic_scene.h"
#include "vk/context.h"

namespace vkmesh::cli {

namespace {

// FNV-1a over 32-bit words.
struct Digest {
    uint64_t h = 14695981039346656037ull;
    void add(uint32_t w) {
        for (int b = 0; b < 4; ++b) h = (h ^ ((w >> (8 * b)) & 0xFF)) * 1099511628211ull;
    }
    std::string hex() const {
        char text[17];
        std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(h));
        return text;
    }
};

// The map's TSDF (every block's sums and weight bits, by coordinate) and its mesh (the set of triangles, each as its
// vertices' position bits from the smallest, with the vertices' ages): what a paged run must share with an unpaged one.
nlohmann::json mapDigest(gpu::GpuVolume& volume) {
    std::vector<gpu::BlockSnapshot> blocks = volume.downloadBlocks();
    std::sort(blocks.begin(), blocks.end(), [](const auto& a, const auto& b) {
        return std::tie(a.coord.z(), a.coord.y(), a.coord.x()) < std::tie(b.coord.z(), b.coord.y(), b.coord.x());
    });
    Digest tsdf;
    for (const gpu::BlockSnapshot& b : blocks) {
        for (int i = 0; i < 3; ++i) tsdf.add(uint32_t(b.coord[i]));
        for (int32_t v : b.sdfSum) tsdf.add(uint32_t(v));
        for (float w : b.weight) tsdf.add(std::bit_cast<uint32_t>(w));
    }
    const gpu::ExportedMesh mesh = volume.exportMesh();
    std::vector<std::array<uint32_t, 12>> triangles;
    triangles.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) {
        std::array<std::array<uint32_t, 4>, 3> v;
        for (int c = 0; c < 3; ++c) {
            const gpu::Vertex& x = mesh.vertices[t[c]];
            v[c] = {std::bit_cast<uint32_t>(x.px), std::bit_cast<uint32_t>(x.py), std::bit_cast<uint32_t>(x.pz), x.createdFrame};
        }
        const int first = int(std::min_element(v.begin(), v.end()) - v.begin());   // rotated, not reordered: orientation kept
        std::array<uint32_t, 12> canonical;
        for (int c = 0; c < 3; ++c) std::copy(v[(first + c) % 3].begin(), v[(first + c) % 3].end(), canonical.begin() + 4 * c);
        triangles.push_back(canonical);
    }
    std::sort(triangles.begin(), triangles.end());
    Digest mesh_;
    for (const auto& t : triangles)
        for (uint32_t w : t) mesh_.add(w);
    return {{"blocks", blocks.size()}, {"tsdf", tsdf.hex()}, {"triangles", triangles.size()}, {"mesh", mesh_.hex()}};
}

struct SoakArgs {
    std::string output, summaryPath;
    size_t frames = 3000;
    size_t laps = 6;
    size_t rooms = 1;
    int width = 160, height = 120;
    float maxDepth = 5.0f;
    VolumeOptions volume = soakDefaults();
    bool noise = true;
    bool track = false;   // track every lap after its first frame (in a new copy of the room unless --rooms)
    DeviceArgs device;
    CLI::App* cmd = nullptr;

    // A coarser voxel and a smaller pool than fuse's defaults: long runs at small image sizes.
    static VolumeOptions soakDefaults() {
        VolumeOptions v;
        v.voxel = 0.05f;
        v.blocks = 8192;
        return v;
    }
};

// What the CSV records of one frame; the high-water marks per lap are taken over these.
struct Occupancy {
    uint32_t hashEntries, hashTombstones, blocks, vertices, chunks, triangles;
};

int runSoak(const SoakArgs& a) {
    if (a.laps == 0 || a.frames < a.laps) throw Error("soak needs at least one frame per lap");
    vk::Context context(a.device.contextOptions());
    gpu::GpuVolumeConfig config = a.volume.toConfig(a.maxDepth, a.width, a.height);
    if (a.track && config.meshMode != gpu::MeshMode::Incremental)
        throw Error("soak --track needs --mode incremental (it tracks against the mesh)");
    MapperOptions options;
    options.volume = config;
    options.tracker.maxDepth = a.maxDepth;
    Mapper mapper(context, options);
    mapper.createVolume(a.width, a.height);
    const gpu::GpuVolume& volume = mapper.volume();
    // Tracking: a new copy of the room for every lap unless --rooms says otherwise, so the map grows lap after
    // lap and the tracked view never holds more of it than one room.
    const size_t rooms = a.track && a.cmd->get_option("--rooms")->count() == 0 ? a.laps : a.rooms;

    const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    const Intrinsics intrinsics = synth::kinectIntrinsics(a.width, a.height);
    const size_t framesPerLap = a.frames / a.laps;
    // One lap of the room's orbit, driven `laps` times: every later lap revisits the poses of the first.
    const std::vector<Pose> lap = synth::cameraPath(framesPerLap, synth::PathKind::Orbit);
    // With several rooms, lap l is driven in copy l % rooms of the room, kRoomSpacing metres along x: the same
    // depth images fused at another place, so the world is larger than any keep radius and is still revisited.
    constexpr double kRoomSpacing = 8.0;   // the room spans under 5 m along x

    std::ofstream csv(a.output);
    if (!csv) throw Error("cannot write " + a.output);
    // Per-stage GPU ms after the original columns (added, so scripts reading the old ones keep working): how
    // each pass's cost follows the map's size (docs/RESULTS.md, "Speed per frame", the flat-cost target). A stage a frame
    // does not run is 0; a name not listed here (a future pass) goes to ms_other.
    static const std::vector<std::string> kStages = {"rehash",     "allocate",   "fuse",           "mesh_mark",
                                                     "recycle_retire", "mesh_claim", "mesh_update", "mesh_triangulate",
                                                     "mesh_gc",    "recycle_free", "export",       "deltas"};
    csv << "frame,lap,hash_entries,hash_tombstones,hash_rebuilt,blocks_in_use,vertices_in_use,chunks_in_use,live_triangles,"
           "touched_blocks,blocks_freed,blocks_retired,blocks_starved,warnings,gpu_ms,wall_ms";
    for (const std::string& stage : kStages) csv << ",ms_" << stage;
    csv << ",ms_other,track_ms,track_gpu_ms,tracked,track_error_m";   // tracking's columns: 0 without --track
    csv << ",paging_ms,blocks_paged_in,blocks_paged_out,blocks_on_host\n";   // paging's (--resident-blocks): 0 without
    std::vector<Occupancy> highWater(a.laps, Occupancy{0, 0, 0, 0, 0, 0});
    std::vector<std::vector<double>> lapTrackMs(a.laps), lapTrackError(a.laps);   // tracked frames, per lap
    size_t lostFrames = 0;
    size_t warnings = 0, rebuilds = 0;
    uint64_t freed = 0, pagedIn = 0, pagedOut = 0;
    double pagingMs = 0, frameMs = 0;
    const auto start = std::chrono::steady_clock::now();
    for (size_t i = 0; i < framesPerLap * a.laps; ++i) {
        synth::RenderOptions options;
        options.noise = a.noise;
        options.seed = uint32_t(i + 1);
        const Pose& pose = lap[i % framesPerLap];
        DepthImage depth = scene.renderDepth(intrinsics, pose, options);
        Pose placed = pose;
        placed(0, 3) += kRoomSpacing * double((i / framesPerLap) % rooms);
        const size_t lapIndex = i / framesPerLap;
        // Every lap's first frame at its true pose (tracking restarts there), with --track the rest tracked.
        MapperFrame frame;
        frame.index = uint32_t(i);
        frame.timestamp = double(i);
        frame.depth = &depth;
        frame.intrinsics = intrinsics;
        frame.source = "the synthetic room";
        if (!a.track || i % framesPerLap == 0) frame.pose = placed;
        auto t0 = std::chrono::steady_clock::now();
        MapperResult result = mapper.process(frame);
        gpu::FrameReport r = result.fused ? std::move(*result.fused) : gpu::FrameReport{};
        const std::optional<gpu::TrackingReport>& tracking = result.tracking;   // a tracked frame (not a lap's first)
        if (result.status == FrameStatus::Lost) ++lostFrames;
        const double wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        double gpuMs = 0;
        for (const auto& [name, ms] : r.stageMs) gpuMs += ms;
        const gpu::Counters& k = r.counters;
        for (const auto& w : r.warnings) std::cerr << "warning: frame " << i << ": " << w << "\n";
        warnings += r.warnings.size();
        rebuilds += k.hashRebuilt;
        freed += k.blocksFreed;
        Occupancy& hw = highWater[lapIndex];
        hw.hashEntries = std::max(hw.hashEntries, k.hashEntries);
        hw.hashTombstones = std::max(hw.hashTombstones, k.hashTombstones);
        hw.blocks = std::max(hw.blocks, k.blocksInUse);
        hw.vertices = std::max(hw.vertices, k.verticesInUse);
        hw.chunks = std::max(hw.chunks, k.chunksInUse);
        hw.triangles = std::max(hw.triangles, k.liveTriangles);
        csv << i + 1 << "," << lapIndex + 1 << "," << k.hashEntries << "," << k.hashTombstones << "," << k.hashRebuilt << ","
            << k.blocksInUse << "," << k.verticesInUse << "," << k.chunksInUse << "," << k.liveTriangles << "," << k.touchedCount
            << "," << k.blocksFreed << "," << k.blocksRetired << "," << k.blocksStarved << "," << r.warnings.size() << ","
            << gpuMs << "," << wallMs;
        std::vector<double> stageMs(kStages.size() + 1, 0.0);
        for (const auto& [name, ms] : r.stageMs)
            stageMs[size_t(std::find(kStages.begin(), kStages.end(), name) - kStages.begin())] += ms;
        for (double ms : stageMs) csv << "," << ms;
        double trackError = 0;
        if (tracking) {
            trackError = (tracking->cameraToWorld.block<3, 1>(0, 3) - placed.block<3, 1>(0, 3)).norm();
            if (tracking->tracked) lapTrackMs[lapIndex].push_back(tracking->milliseconds), lapTrackError[lapIndex].push_back(trackError);
        }
        csv << "," << (tracking ? tracking->milliseconds : 0.0) << "," << (tracking ? tracking->gpuMilliseconds : 0.0) << ","
            << (tracking && tracking->tracked ? 1 : 0) << "," << trackError;
        csv << "," << r.paging.milliseconds << "," << r.paging.blocksIn << "," << r.paging.blocksOut << "," << r.paging.blocksPaged << "\n";
        pagingMs += r.paging.milliseconds;
        frameMs += wallMs;
        pagedIn += r.paging.blocksIn;
        pagedOut += r.paging.blocksOut;
        if ((i + 1) % 250 == 0)
            std::cerr << "frame " << i + 1 << "/" << framesPerLap * a.laps << "  blocks " << k.blocksInUse << "  vertices "
                      << k.verticesInUse << "\n";
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::cout << "vkmesh soak: " << framesPerLap * a.laps << " frames (" << a.laps << " laps of " << framesPerLap << "), "
              << rooms << " room(s), " << a.width << "x" << a.height << ", voxel " << a.volume.voxel << " m, keep radius "
              << (a.volume.keepRadius > 0 ? std::to_string(a.volume.keepRadius) + " m" : std::string("off")) << ", recycling "
              << (a.volume.recycle ? "on" : "off") << ", " << seconds << " s\n"
              << "  high water per lap: hash entries / tombstones / blocks / vertices / chunks / triangles\n";
    nlohmann::json lapsJson = nlohmann::json::array();
    for (size_t l = 0; l < a.laps; ++l) {
        const Occupancy& h = highWater[l];
        std::cout << "  lap " << l + 1 << ": " << h.hashEntries << " / " << h.hashTombstones << " / " << h.blocks << " / "
                  << h.vertices << " / " << h.chunks << " / " << h.triangles << "\n";
        lapsJson.push_back({{"hash_entries", h.hashEntries}, {"hash_tombstones", h.hashTombstones}, {"blocks", h.blocks},
                            {"vertices", h.vertices}, {"chunks", h.chunks}, {"triangles", h.triangles}});
    }
    std::cout << "  blocks freed " << freed << ", hash rebuilds " << rebuilds << ", warnings " << warnings << "\n";
    if (a.volume.residentBlocks > 0)
        std::cout << "  paging: " << pagedOut << " blocks out, " << pagedIn << " in, " << pagingMs << " ms ("
                  << (frameMs > 0 ? 100.0 * pagingMs / frameMs : 0.0) << " % of the frames' time)\n";
    // Tracking per lap: the median wall time of its tracked frames (the flat-cost check compares the last lap's
    // with the first's) and the largest position error against the true poses.
    auto median = [](std::vector<double> v) {
        if (v.empty()) return 0.0;
        std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
        return v[v.size() / 2];
    };
    nlohmann::json trackingJson;
    if (a.track) {
        nlohmann::json perLap = nlohmann::json::array();
        std::cout << "  tracking per lap: median ms per tracked frame / largest position error (m)\n";
        for (size_t l = 0; l < a.laps; ++l) {
            const double ms = median(lapTrackMs[l]);
            const double worst = lapTrackError[l].empty() ? 0.0 : *std::max_element(lapTrackError[l].begin(), lapTrackError[l].end());
            std::cout << "  lap " << l + 1 << ": " << ms << " / " << worst << "\n";
            perLap.push_back({{"median_ms", ms}, {"tracked_frames", lapTrackMs[l].size()}, {"max_position_error_m", worst}});
        }
        const double first = median(lapTrackMs.front()), last = median(lapTrackMs.back());
        std::cout << "  tracking: last lap / first lap median " << (first > 0 ? last / first : 0.0) << ", lost frames " << lostFrames << "\n";
        trackingJson = {{"per_lap", perLap}, {"last_over_first", first > 0 ? last / first : 0.0}, {"lost_frames", lostFrames}};
    }
    if (!a.summaryPath.empty()) {
        nlohmann::json s = {{"frames", framesPerLap * a.laps}, {"laps", a.laps}, {"rooms", rooms}, {"width", a.width}, {"height", a.height},
                            {"voxel", a.volume.voxel}, {"keep_radius", a.volume.keepRadius}, {"recycle", a.volume.recycle},
                            {"recycle_after_frames", a.volume.recycleAfter}, {"starve_weight", a.volume.starveWeight},
                            {"block_capacity", volume.config().blockCapacity}, {"hash_capacity", volume.config().hashCapacity},
                            {"high_water_per_lap", lapsJson}, {"blocks_freed", freed}, {"hash_rebuilds", rebuilds},
                            {"warnings", warnings}, {"seconds", seconds}, {"device", context.info().name}};
        if (a.track) s["tracking"] = trackingJson;
        if (a.volume.residentBlocks > 0)
            s["paging"] = {{"resident_blocks", a.volume.residentBlocks}, {"blocks_in", pagedIn}, {"blocks_out", pagedOut},
                           {"blocks_on_host", mapper.volume().pagedBlocks()}, {"ms", pagingMs},
                           {"share_of_frame_time", frameMs > 0 ? pagingMs / frameMs : 0.0}};
        // The map at the end, as digests that two runs compare (the same with and without --resident-blocks).
        s["map_digest"] = mapDigest(mapper.volume());
        std::ofstream file(a.summaryPath);
        if (!file) throw Error("cannot write " + a.summaryPath);
        file << s.dump(2) << "\n";
    }
    return 0;
}

}  // namespace

Run addSoakCommand(CLI::App& app) {
    auto args = std::make_shared<SoakArgs>();
    CLI::App* cmd = app.add_subcommand("soak", "long run over the synthetic room with revisits: per-frame occupancy of the "
                                                "hash, block pool and mesh heaps as CSV (bounded maps)");
    cmd->add_option("-o,--output", args->output, "CSV file to write (one row per frame)")->required();
    cmd->add_option("--summary", args->summaryPath, "also write the per-lap high-water marks as JSON");
    cmd->add_option("--frames", args->frames, "frames in all")->check(CLI::PositiveNumber);
    cmd->add_option("--laps", args->laps, "times the camera drives its loop around the room")->check(CLI::PositiveNumber);
    cmd->add_option("--rooms", args->rooms, "copies of the room, 8 m apart; lap l is driven in copy l % N (a world "
                                             "larger than the keep radius, still revisited)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--width", args->width, "image width")->check(CLI::Range(16, 4096));
    cmd->add_option("--height", args->height, "image height")->check(CLI::Range(16, 4096));
    cmd->add_option("--max-depth", args->maxDepth, "ignore depth beyond M metres")->check(CLI::PositiveNumber);
    args->volume.addCommon(cmd);
    cmd->add_flag("--noise,!--no-noise", args->noise, "Kinect-like depth noise (default on)");
    cmd->add_flag("--track", args->track,
                  "track the camera (every lap's first frame at its true pose, the rest against the mesh), each lap in a new "
                  "copy of the room unless --rooms is given: tracking's cost per frame as the map grows (CSV columns "
                  "track_ms, track_gpu_ms, tracked, track_error_m; per-lap medians in the output and --summary)");
    args->cmd = cmd;
    args->device.add(cmd);
    return [args]() { return runSoak(*args); };
}

}  // namespace vkmesh::cli
