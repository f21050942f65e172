// `vkmesh soak`: a long run over the synthetic room with revisits, recording per frame how full the hash,
// the block pool and the mesh heaps are, to show that bounded maps (--keep-radius, --recycle) keep them flat.
//   vkmesh soak -o soak.csv [--frames 3000 --laps 6 --width 160 --height 120 --voxel 0.05]
//               [--keep-radius 2.0] [--recycle] [--summary summary.json]
// bench/soak_plot.py draws the CSVs of several runs.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>

#include "cli_options.h"
#include "commands.h"
#include "gpu/gpu_volume.h"
#include "synth/synthetic_scene.h"
#include "vk/context.h"

namespace vkmesh::cli {

namespace {

struct SoakArgs {
    std::string output, summaryPath;
    size_t frames = 3000;
    size_t laps = 6;
    size_t rooms = 1;
    int width = 160, height = 120;
    float maxDepth = 5.0f;
    VolumeOptions volume = soakDefaults();
    bool noise = true;
    DeviceArgs device;

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
    gpu::GpuVolume volume(context, a.volume.toConfig(a.maxDepth, a.width, a.height));

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
    // each pass's cost follows the map's size (docs/RESULTS.md, issue 14's flat-cost target). A stage a frame
    // does not run is 0; a name not listed here (a future pass) goes to ms_other.
    static const std::vector<std::string> kStages = {"rehash",     "allocate",   "fuse",           "mesh_mark",
                                                     "recycle_retire", "mesh_claim", "mesh_update", "mesh_triangulate",
                                                     "mesh_gc",    "recycle_free", "export",       "deltas"};
    csv << "frame,lap,hash_entries,hash_tombstones,hash_rebuilt,blocks_in_use,vertices_in_use,chunks_in_use,live_triangles,"
           "touched_blocks,blocks_freed,blocks_retired,blocks_starved,warnings,gpu_ms,wall_ms";
    for (const std::string& stage : kStages) csv << ",ms_" << stage;
    csv << ",ms_other\n";
    std::vector<Occupancy> highWater(a.laps, Occupancy{0, 0, 0, 0, 0, 0});
    size_t warnings = 0, rebuilds = 0;
    uint64_t freed = 0;
    const auto start = std::chrono::steady_clock::now();
    for (size_t i = 0; i < framesPerLap * a.laps; ++i) {
        synth::RenderOptions options;
        options.noise = a.noise;
        options.seed = uint32_t(i + 1);
        const Pose& pose = lap[i % framesPerLap];
        DepthImage depth = scene.renderDepth(intrinsics, pose, options);
        Pose placed = pose;
        placed(0, 3) += kRoomSpacing * double((i / framesPerLap) % a.rooms);
        auto t0 = std::chrono::steady_clock::now();
        gpu::FrameReport r = volume.integrate(depth, intrinsics, placed);
        const double wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        double gpuMs = 0;
        for (const auto& [name, ms] : r.stageMs) gpuMs += ms;
        const gpu::Counters& k = r.counters;
        for (const auto& w : r.warnings) std::cerr << "warning: frame " << i << ": " << w << "\n";
        warnings += r.warnings.size();
        rebuilds += k.hashRebuilt;
        freed += k.blocksFreed;
        const size_t lapIndex = i / framesPerLap;
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
        csv << "\n";
        if ((i + 1) % 250 == 0)
            std::cerr << "frame " << i + 1 << "/" << framesPerLap * a.laps << "  blocks " << k.blocksInUse << "  vertices "
                      << k.verticesInUse << "\n";
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::cout << "vkmesh soak: " << framesPerLap * a.laps << " frames (" << a.laps << " laps of " << framesPerLap << "), "
              << a.rooms << " room(s), " << a.width << "x" << a.height << ", voxel " << a.volume.voxel << " m, keep radius "
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
    if (!a.summaryPath.empty()) {
        nlohmann::json s = {{"frames", framesPerLap * a.laps}, {"laps", a.laps}, {"rooms", a.rooms}, {"width", a.width}, {"height", a.height},
                            {"voxel", a.volume.voxel}, {"keep_radius", a.volume.keepRadius}, {"recycle", a.volume.recycle},
                            {"recycle_after_frames", a.volume.recycleAfter}, {"starve_weight", a.volume.starveWeight},
                            {"block_capacity", volume.config().blockCapacity}, {"hash_capacity", volume.config().hashCapacity},
                            {"high_water_per_lap", lapsJson}, {"blocks_freed", freed}, {"hash_rebuilds", rebuilds},
                            {"warnings", warnings}, {"seconds", seconds}, {"device", context.info().name}};
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
    args->device.add(cmd);
    return [args]() { return runSoak(*args); };
}

}  // namespace vkmesh::cli
