// `vkmesh correct MAP --trajectory corrected.txt -o mesh.ply [--save corrected.vkmap]`: re-fuses the frames of a
// saved map whose poses changed (docs/CORRECTION.md). The map and the frame store saved beside it (fuse --save)
// are loaded; every kept frame whose timestamp is in the TUM-format trajectory and whose pose there differs from
// the one it was fused at is de-integrated at the old pose and integrated at the new one; the mesh follows
// incrementally and is written. --stats reports what was re-fused.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "api/exported_mesh.h"
#include "api/mapper.h"
#include "cli_options.h"
#include "commands.h"
#include "core/frame_store.h"
#include "core/map_format.h"
#include "io/mesh_file.h"
#include "io/trajectory.h"
#include "vk/context.h"

namespace vkmesh::cli {

namespace {

using json = nlohmann::json;

// A pose in the trajectory file is written with 9 decimals: a frame whose pose there moved less than this
// (metres + radians, gpu::poseChange) from the one it was fused at is the same pose, not a correction.
constexpr double kSamePose = 1e-6;
// Timestamps are written with 6 decimals (or as frame numbers): matched to the stored ones within this.
constexpr double kSameTimestamp = 5e-6;

struct CorrectArgs {
    std::string map;
    std::string trajectory;
    std::string output;
    std::string savePath;
    std::string statsPath;
    std::string framesPath;   // the frame store (default: beside the map)
    DeviceArgs device;
};

int runCorrect(const CorrectArgs& args) {
    const auto start = std::chrono::steady_clock::now();
    meshFormatOf(args.output);   // a mesh name vkmesh cannot write fails now, not after the correction
    const map::MapData m = map::readFile(args.map);   // checked before a device is opened
    const std::filesystem::path framesPath = args.framesPath.empty() ? gpu::frameStorePathOf(args.map) : std::filesystem::path(args.framesPath);
    if (!std::filesystem::exists(framesPath))
        throw Error(args.map + " has no frame store beside it (" + framesPath.string() + "): save the map with vkmesh fuse ... --save " +
                    "(which keeps the frames) to correct it later");
    FrameStore store = FrameStore::load(framesPath.string(), m.saveId);
    const std::vector<TimedPose> wanted = readTumTrajectory(args.trajectory);

    // Stored frames by timestamp; each line of the trajectory finds its frame or is counted as unmatched.
    std::map<double, uint32_t> byTime;
    for (uint32_t index : store.indices()) byTime.emplace(store.timestamp(index), index);
    std::vector<uint32_t> frames;
    std::vector<Pose> poses;
    size_t unmatched = 0, unchanged = 0;
    for (const TimedPose& p : wanted) {
        auto it = byTime.lower_bound(p.timestamp - kSameTimestamp);
        if (it == byTime.end() || std::abs(it->first - p.timestamp) > kSameTimestamp) {
            ++unmatched;
            continue;
        }
        if (gpu::poseChange(store.pose(it->second), p.cameraToWorld) < kSamePose) {
            ++unchanged;
            continue;
        }
        frames.push_back(it->second);
        poses.push_back(p.cameraToWorld);
    }

    gpu::GpuVolumeConfig config = gpu::GpuVolume::mapConfig(m);
    if (config.meshMode != gpu::MeshMode::Incremental)
        throw Error(args.map + " was fused with --mode baseline; correction keeps the incremental mesh (fuse with --mode incremental)");
    vk::Context context(args.device.contextOptions());
    // The library's frame loop with the map and its kept frames: the corrections re-fused in one go.
    Mapper mapper(context, MapperOptions{});
    mapper.keepFrames(std::move(store));
    mapper.correct(frames, poses);
    mapper.loadMap(m, config, args.map);
    const double loadMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    gpu::CorrectionReport report;
    mapper.finishCorrections(&report, false);   // the mesh is exported below, after the map is saved
    for (const std::string& w : report.warnings) std::cerr << "warning: " << w << "\n";
    const FrameStore& kept = *mapper.frameStore();
    gpu::GpuVolume& volume = mapper.volume();

    double saveMs = 0;
    if (!args.savePath.empty()) {
        const auto t0 = std::chrono::steady_clock::now();
        mapper.save(args.savePath);
        saveMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }
    const Mesh mesh = toMesh(volume.exportMesh(), volume.frameNumber());
    const std::filesystem::path out(args.output);
    writeMesh(out, mesh);
    std::cout << "vkmesh correct: " << report.framesRefused << " of " << kept.size() << " frames re-fused ("
              << unchanged << " unchanged, " << unmatched << " trajectory lines without a frame), " << report.blocksFreed
              << " blocks freed, " << report.milliseconds << " ms: " << mesh.positions.size() << " vertices, " << mesh.triangles.size()
              << " triangles -> " << out.string() << "\n";
    if (!args.statsPath.empty()) {
        const gpu::Counters k = volume.readCounters();
        json stats;
        stats["map"] = args.map;
        stats["frame_store"] = {{"path", framesPath.string()}, {"frames", kept.size()}};
        stats["correction"] = {{"frames_refused", report.framesRefused},
                               {"frames_unchanged", unchanged},
                               {"trajectory_lines_unmatched", unmatched},
                               {"blocks_freed", report.blocksFreed},
                               {"observations_dropped", report.observationsDropped},
                               {"ms", report.milliseconds},
                               {"ms_per_frame", report.framesRefused ? report.milliseconds / report.framesRefused : 0.0}};
        stats["load_ms"] = loadMs;
        stats["save_ms"] = saveMs;
        stats["blocks"] = {{"in_use", k.blocksInUse}};
        stats["mesh"] = {{"vertices", mesh.positions.size()}, {"triangles", mesh.triangles.size()}, {"path", out.string()}};
        stats["warnings"] = report.warnings;
        std::ofstream(args.statsPath) << stats.dump(2) << "\n";
    }
    return report.observationsDropped == 0 ? 0 : 1;
}

}  // namespace

Run addCorrectCommand(CLI::App& app) {
    auto args = std::make_shared<CorrectArgs>();
    auto* cmd = app.add_subcommand("correct", "re-fuse the frames of a saved map whose poses changed (docs/CORRECTION.md)");
    cmd->add_option("MAP", args->map, "map file (.vkmap) saved by vkmesh fuse --save, with its .vkframes beside it")->required();
    cmd->add_option("--trajectory", args->trajectory,
                    "corrected poses, TUM format (timestamp tx ty tz qx qy qz qw); frames are matched by timestamp")
        ->required();
    cmd->add_option("-o,--output", args->output, "mesh file (.ply binary, .obj or .glb binary glTF)")->required();
    cmd->add_option("--save", args->savePath, "save the corrected map (and its frame store beside it)");
    cmd->add_option("--frames", args->framesPath, "the frame store (default: MAP with the extension .vkframes)");
    cmd->add_option("--stats", args->statsPath, "write statistics as JSON (frames re-fused, blocks freed, ms)");
    args->device.add(cmd);
    return [args] { return runCorrect(*args); };
}

}  // namespace vkmesh::cli
