#include "fuse_options.h"

#include <CLI/CLI.hpp>

#include <array>
#include <iostream>
#include <sstream>

#include "slam/loop_closer.h"

namespace vkmesh::cli {

namespace {

// Continuing a map: every setting the command line did not give is the map's; one it gave must agree with the
// map (GpuVolume::load refuses it otherwise, naming the file and the option).
void takeMapSettings(const FuseArgs& args, const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& c) {
    auto given = [&](const char* option) { return args.given(option); };
    if (!given("--voxel")) c.params.voxelSize = map.params.voxelSize;
    if (!given("--trunc")) c.params.truncVoxels = map.params.truncVoxels;
    if (!given("--max-weight")) c.params.maxWeight = map.params.maxWeight;
    if (!given("--min-weight")) c.minMeshWeight = map.minMeshWeight;
    if (!given("--alloc-stride")) c.params.allocationStride = map.params.allocationStride;
    if (!given("--alloc-tiles") && !given("--alloc-pixels")) c.params.allocationTiles = map.params.allocationTiles;
    if (!given("--mode")) c.meshMode = map.meshMode;
    if (!given("--refine")) c.refine = map.refine;
    if (!given("--refine-eps")) c.refineEpsilonVoxels = map.refineEpsilonVoxels;
    if (!given("--keep-radius")) c.keepRadius = map.keepRadius;
    if (!given("--recycle")) c.recycle = map.recycle;
    if (!given("--recycle-after")) c.recycleAfterFrames = map.recycleAfterFrames;
    if (!given("--starve-weight")) c.starveWeight = map.starveWeight;
    // A map keeps its colour (frames without colour images then fuse depth only); --no-color or --color-mode
    // on the command line must agree with it.
    if (!given("--no-color") && !given("--color-mode")) c.params.colorFusion = map.params.colorFusion;
    if (!given("--color-recency")) c.params.colorRecency = map.params.colorRecency;
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

void FuseArgs::check() const {
    output.check();   // the mesh's name and --simplify, before a long run
    if (growHeaps)
        std::cerr << "note: --grow-heaps is deprecated and has no effect: capacities grow by default (--no-grow keeps them fixed)\n";
    if ((!trackIterations.empty() || given("--track-color-weight") || given("--track-solve") || given("--track-downsample") ||
         given("--track-model-reuse")) &&
        !track)
        throw Error("--track-iterations, --track-color-weight, --track-solve, --track-downsample and --track-model-reuse need --track");
    if ((loopClosure || !trajectoryOnlinePath.empty()) && !track)
        throw Error("--loop-closure and --trajectory-online need --track (loops are closed over tracked poses)");
    if (given("--corrections-per-frame") && !loopClosure) throw Error("--corrections-per-frame needs --loop-closure");
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
    config.publishMesh = renderEvery > 0 || track;   // tracking draws the mesh fused so far
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
    if (loopClosure) {
        slam::LoopClosureOptions loopOptions;
        loopOptions.tracker = options.tracker;
        options.loopClosure = std::make_shared<slam::LoopCloser>(loopOptions);
    }
    return options;
}

FrameStoreOptions FuseArgs::frameStoreOptions() const {
    FrameStoreOptions options;
    options.memoryBudgetBytes = size_t(framesBudgetMb * 1024 * 1024);
    options.spillFolder = framesSpill;
    return options;
}

void addFuseOptions(CLI::App* cmd, FuseArgs& args) {
    args.data.add(cmd);
    args.output.add(cmd);
    cmd->add_option("--stats", args.statsPath, "write counts, timings and memory as JSON");
    args.volume.addCommon(cmd);
    args.volume.addTuning(cmd);
    cmd->add_flag("--grow-heaps", args.growHeaps,
                  "deprecated, no effect: every capacity grows by default (--no-grow keeps them fixed)");
    args.device.add(cmd);
    cmd->add_flag("-q,--quiet", args.quiet, "no progress line");
    cmd->add_flag("--no-stage-times", args.noStageTimes,
                  "record no GPU timestamps between stages (~0.3-0.5 ms per frame on lavapipe); the summary and --stats then "
                  "have no GPU stage times, only wall times (-q without --stats records none either)");
    cmd->add_flag("--pass-times", args.passTimes,
                  "also a GPU timestamp after every pass (compute dispatch) of a frame: --stats gains gpu_ms_per_pass, each "
                  "pass's time per frame by shader name (each timestamp costs ~50 us on lavapipe: for profiling)");
    cmd->add_flag("--analyse-mesh,--analyze-mesh", args.analyseMesh,
                  "also analyse the final mesh for --stats: the baseline's vertex count on the same TSDF (mesh.baseline_vertices, "
                  "vertices_vs_baseline), sliver triangles, irregular cubes, boundary and non-manifold edges, coincident "
                  "vertices (the paper's evaluation; without it these keys are null: ~0.3-0.8 s less per run)");
    cmd->add_option("--render-every", args.renderEvery, "write a picture of the mesh every N frames (drawn from the GPU buffers)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--render-dir", args.renderDir, "folder for the --render-every pictures (frame_NNNNNN.png)");
    cmd->add_option("--render-view", args.renderView, "sensor: from the frame's camera; overview: framing the mesh so far")
        ->check(CLI::IsMember({"sensor", "overview"}));
    cmd->add_option("--render-color", args.renderColor,
                    "shade, normal, age (warm = new, cold = old) or rgb (the fused colours); default: rgb when colour is "
                    "fused, else shade")
        ->check(CLI::IsMember({"shade", "normal", "age", "rgb", "auto"}));
    cmd->add_option("--deltas", args.deltasPath, "write every frame's mesh changes to this stream file (docs/DELTAS.md)");
    cmd->add_option("--save", args.savePath, "write the whole state after the last frame to this map file (.vkmap, docs/MAPFILE.md)");
    cmd->add_flag("--keep-frames", args.keepFrames,
                  "keep every frame as fused (compressed) in a frame store saved beside the --save map (MAP.vkframes), so "
                  "that vkmesh correct can re-fuse frames whose poses change (the default with --save)");
    cmd->add_flag("--no-keep-frames", args.noKeepFrames, "with --save: do not keep the frames (the map cannot be corrected later)");
    cmd->add_option("--frames-budget", args.framesBudgetMb, "the frame store's memory budget in MiB (compressed frames)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--frames-spill", args.framesSpill, "folder for the frames beyond --frames-budget (else the run stops there)");
    cmd->add_option("--load", args.loadPath,
                    "continue the map in this file (its settings unless given; with --first-frame, the frames it does not hold yet)");
    cmd->add_option("--first-frame", args.firstFrame, "start at this frame of the dataset (0-based; frames before it are skipped)");
    cmd->add_flag("--track", args.track,
                  "estimate the camera poses: every frame after the first is tracked against the mesh fused so far "
                  "(the first frame's pose is the dataset's, or identity when it has none; its other poses are not used). "
                  "Datasets without poses need it");
    cmd->add_option("--trajectory", args.trajectoryPath,
                    "write the pose used for every frame (tracked or given) in TUM format: timestamp tx ty tz qx qy qz qw; with "
                    "--loop-closure the final poses, every loop's correction applied");
    cmd->add_flag("--loop-closure", args.loopClosure,
                  "with --track: recognise places seen before (keyframes, random ferns), verify them by ICP, optimise a pose graph "
                  "(Ceres) and re-fuse the frames a loop moves; relocalise lost frames from the keyframes (docs/LOOP_CLOSURE.md)");
    cmd->add_option("--trajectory-online", args.trajectoryOnlinePath,
                    "with --track: write the poses as they were when each frame was fused (TUM format), before any loop's correction");
    cmd->add_option("--corrections-per-frame", args.correctionsPerFrame,
                    "with --loop-closure: frames a loop moved that are re-fused before each new frame (default 2; the rest after the last frame)");
    cmd->add_option("--track-iterations", args.trackIterations,
                    "ICP iterations per pyramid level, finest first (default by the finest tracked level's width: 3,4,4 from 320 "
                    "pixels wide, 10,5,4 below)");
    cmd->add_option("--track-color-weight", args.trackColorWeight,
                    "weight of tracking's photometric term (the frame's intensity against the mesh's fused colours; needs "
                    "colour images and colour fusion); 0: geometry only")
        ->check(CLI::Range(0.0, 100.0));
    cmd->add_option("--track-solve", args.trackSolve,
                    "where tracking solves its 6x6 systems: host (in double, one GPU submission per ICP iteration) or gpu (in "
                    "float; the frame's tracking, fusion and meshing in one submission; docs/TRACKING.md)")
        ->check(CLI::IsMember({"host", "gpu"}));
    cmd->add_option("--track-downsample", args.trackDownsample,
                    "track on the frames downsampled by 1, 2 or 4 (fusion keeps the full frames); 0 (default): 2 for frames at "
                    "least 640 pixels wide, else 1 (on 640x480 a quarter of the finest level's work at the same accuracy; "
                    "docs/TRACKING.md)")
        ->check(CLI::IsMember({0, 1, 2, 4}));
    cmd->add_option("--track-model-reuse", args.trackModelReuse,
                    "let up to this many frames in a row (default 2) reuse the model maps (the mesh drawn at an earlier pose) "
                    "while the predicted pose is within 4 cm and 4 degrees of where they were drawn; 0 draws the mesh for "
                    "every frame")
        ->check(CLI::Range(0, 1000));
    cmd->add_option("--serve", args.servePort,
                    "serve the live browser viewer on this port while fusing (docs/VIEWER.md; open the URL it prints)")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--host", args.serveHost, "address --serve listens on (default 127.0.0.1: this machine only; 0.0.0.0: every interface)");
    cmd->add_option("--serve-linger", args.serveLinger,
                    "with --serve: keep serving this many seconds after the last frame (default: until Ctrl-C; 0: stop at once)");
    args.cmd = cmd;
}

}  // namespace vkmesh::cli
