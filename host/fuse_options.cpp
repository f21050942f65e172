#include "fuse_options.h"

#include <CLI/CLI.hpp>

#include <array>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "slam/loop_closer.h"

namespace vkmesh::cli {

namespace {

// Continuing a map: every map setting (api/settings.h, SettingKind::Map) the command line did not give is the map's;
// one it gave must agree with the map (GpuVolume::load refuses it otherwise, naming the file and the option).
void takeMapSettings(const FuseArgs& args, const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& c) {
    for (const SettingDescription& d : settingDescriptions()) {
        if (d.kind != SettingKind::Map || !d.fromMap) continue;
        if (args.given(d.cli.c_str()) || (!d.givenWith.empty() && args.given(d.givenWith.c_str()))) continue;
        d.fromMap(map, c);
    }
}

// "10,5,4" -> iterations per pyramid level, finest first. Throws Error naming the value.
std::array<int, gpu::TRACK_LEVELS> parseIterations(const std::string& text) {
    std::array<int, gpu::TRACK_LEVELS> out{};
    std::stringstream stream(text);
    std::string item;
    size_t n = 0;
    while (std::getline(stream, item, ',')) {
        size_t used = 0;
        int v = -1;
        try {
            v = std::stoi(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != item.size() || v < 0 || v > 100 || n >= out.size())
            throw Error("bad --track-iterations '" + text + "': expected " + std::to_string(out.size()) +
                        " numbers 0..100 separated by commas (finest level first), e.g. 10,5,4");
        out[n++] = v;
    }
    if (n != out.size())
        throw Error("bad --track-iterations '" + text + "': expected " + std::to_string(out.size()) + " numbers, got " + std::to_string(n));
    return out;
}

}  // namespace

bool FuseArgs::given(const char* option) const { return cmd->get_option(option)->count() > 0; }

bool FuseArgs::closesLoops(int width, int height) const {
    if (loopClosure) return true;   // asked for: frames too small are an error naming their size (RandomFerns)
    if (!track || noLoopClosure || noKeepFrames) return false;
    return (width == 0 && height == 0) || slam::LoopClosureOptions{}.ferns.fits(width, height);
}

void FuseArgs::check() const {
    output.check();   // the mesh's name and --simplify, before a long run
    if ((!trackIterations.empty() || given("--track-color-weight") || given("--track-solve") || given("--track-downsample") ||
         given("--track-model-reuse")) &&
        !track)
        throw Error("--track-iterations, --track-color-weight, --track-solve, --track-downsample and --track-model-reuse need --track");
    if ((loopClosure || noLoopClosure || !trajectoryOnlinePath.empty()) && !track)
        throw Error("--loop-closure, --no-loop-closure and --trajectory-online need --track (loops are closed over tracked poses)");
    if (loopClosure && noLoopClosure) throw Error("--loop-closure and --no-loop-closure contradict each other");
    if (volume.residentBlocks > 0 && !savePath.empty())
        throw Error("--save with --resident-blocks: saving the blocks paged out to the host is not built yet (docs/PAGING.md)");
    if (given("--resident-blocks") && volume.residentBlocks == 0)
        throw Error("--resident-blocks 0: give the number of blocks to keep in GPU memory (at least what one view reaches; "
                    "docs/PAGING.md), or leave the option out to keep every block");
    for (const char* option : {"--corrections-per-frame", "--loop-place-candidates"})
        if (given(option) && !closesLoops())
            throw Error(std::string(option) + " needs loop closure (on with --track unless --no-loop-closure or --no-keep-frames)");
    if (!trackIterations.empty()) parseIterations(trackIterations);
#ifndef VKMESH_HAVE_VIEWER
    if (serving())
        throw Error("--serve: this vkmesh was built without the browser viewer: it needs libboost-dev and libjs-three at build "
                    "time (scripts/install_deps.sh installs them)");
#endif
    if (renderEvery > 0 && renderDir.empty()) throw Error("--render-every needs --render-dir");
    if (passTimes && noStageTimes) throw Error("--pass-times times the passes inside the stages: it cannot go with --no-stage-times");
    if (keepFrames && savePath.empty()) throw Error("--keep-frames keeps the frames with the map: give --save too");
    if (loopClosure && noKeepFrames) throw Error("--loop-closure re-fuses the frames a loop moves: it cannot go with --no-keep-frames");
}

gpu::GpuVolumeConfig FuseArgs::volumeConfig(const Intrinsics& intrinsics, bool datasetHasColor, const map::MapData* map) const {
    gpu::GpuVolumeConfig config = volume.toConfig(data.maxDepth, intrinsics.width, intrinsics.height, datasetHasColor);
    if (map) takeMapSettings(*this, gpu::GpuVolume::mapConfig(*map), config);
    const bool incremental = config.meshMode == gpu::MeshMode::Incremental;
    if ((renderEvery > 0 || !deltasPath.empty() || serving()) && !incremental)
        throw Error("--render-every, --deltas and --serve need --mode incremental (the baseline keeps no mesh between frames)");
    if (track && !incremental) throw Error("--track needs --mode incremental (it tracks against the mesh)");
    config.publishMesh = renderEvery > 0;   // tracking draws the volume's own mesh (GpuVolume::recordModelView), not the export
    // GPU timestamps only where something reads them (~0.3-0.5 ms a frame on lavapipe): --stats, --pass-times, the
    // progress line and the viewer; `fuse -q` without --stats times nothing (its summary says so).
    config.timeStages = !noStageTimes && (!quiet || !statsPath.empty() || passTimes || serving());
    config.timePasses = passTimes;
    config.trackDeltas = !deltasPath.empty() || serving();
    return config;
}

MapperOptions FuseArgs::mapperOptions(const gpu::GpuVolumeConfig& config) const {
    MapperOptions options;
    options.volume = config;
    options.tracker.maxDepth = data.maxDepth;
    if (!trackIterations.empty()) options.tracker.iterations = parseIterations(trackIterations);
    options.tracker.colorWeight = trackColorWeight;
    options.tracker.solveOnGpu = trackSolve == "gpu";
    options.tracker.downsample = trackDownsample;
    options.tracker.modelReuseFrames = trackModelReuse;
    options.correctionsPerFrame = correctionsPerFrame;
    if (closesLoops(config.imageWidth, config.imageHeight)) {
        slam::LoopClosureOptions loopOptions;
        loopOptions.tracker = options.tracker;
        loopOptions.proximityCandidates = loopPlaceCandidates;
        options.loopClosure = std::make_shared<slam::LoopCloser>(loopOptions);
    }
    return options;
}

FrameStoreOptions FuseArgs::frameStoreOptions() const {
    FrameStoreOptions options;
    options.memoryBudgetBytes = size_t(framesBudgetMb * 1024 * 1024);
    options.spillFolder = framesSpill;
    // Frames kept only because loops are closed by default (--track, no --save): the run is not stopped by a budget
    // for frames the user never asked to keep; those past it go to the system's temporary folder (removed at the end).
    if (framesSpill.empty() && closesLoops() && !loopClosure && savePath.empty())
        options.spillFolder = std::filesystem::temp_directory_path().string();
    return options;
}

void addFuseOptions(CLI::App* cmd, FuseArgs& args) {
    args.data.add(cmd);
    args.output.add(cmd);
    addSetting(cmd, "--stats", args.statsPath);
    args.volume.addCommon(cmd);
    args.volume.addTuning(cmd);
    addSettingFlag(cmd, "--grow-heaps", args.growHeaps);
    args.device.add(cmd);
    addSettingFlag(cmd, "-q,--quiet", args.quiet);
    addSettingFlag(cmd, "--no-stage-times", args.noStageTimes);
    addSettingFlag(cmd, "--pass-times", args.passTimes);
    addSettingFlag(cmd, "--analyse-mesh,--analyze-mesh", args.analyseMesh);
    addSetting(cmd, "--render-every", args.renderEvery);
    addSetting(cmd, "--render-dir", args.renderDir);
    addSetting(cmd, "--render-view", args.renderView);
    addSetting(cmd, "--render-color", args.renderColor);
    addSetting(cmd, "--deltas", args.deltasPath);
    addSetting(cmd, "--save", args.savePath);
    addSettingFlag(cmd, "--keep-frames", args.keepFrames);
    addSettingFlag(cmd, "--no-keep-frames", args.noKeepFrames);
    addSetting(cmd, "--frames-budget", args.framesBudgetMb);
    addSetting(cmd, "--frames-spill", args.framesSpill);
    addSetting(cmd, "--load", args.loadPath);
    addSetting(cmd, "--first-frame", args.firstFrame);
    addSettingFlag(cmd, "--track", args.track);
    addSetting(cmd, "--trajectory", args.trajectoryPath);
    addSettingFlag(cmd, "--loop-closure", args.loopClosure);
    addSettingFlag(cmd, "--no-loop-closure", args.noLoopClosure);
    addSetting(cmd, "--trajectory-online", args.trajectoryOnlinePath);
    addSetting(cmd, "--corrections-per-frame", args.correctionsPerFrame);
    addSetting(cmd, "--loop-place-candidates", args.loopPlaceCandidates);
    addSetting(cmd, "--track-iterations", args.trackIterations);
    addSetting(cmd, "--track-color-weight", args.trackColorWeight);
    addSetting(cmd, "--track-solve", args.trackSolve);
    addSetting(cmd, "--track-downsample", args.trackDownsample);
    addSetting(cmd, "--track-model-reuse", args.trackModelReuse);
    addSetting(cmd, "--serve", args.servePort);
    addSetting(cmd, "--host", args.serveHost);
    addSetting(cmd, "--serve-linger", args.serveLinger);
    args.cmd = cmd;
}

}  // namespace vkmesh::cli
