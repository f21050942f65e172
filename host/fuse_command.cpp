// `vkmesh fuse DATASET -o mesh.ply`: fuses a depth sequence on the GPU and writes its mesh, optionally with
// the --stats JSON (counts, timings, memory: keys read by users' scripts, never renamed or dropped), pictures
// while fusing (--render-every) and the mesh-delta stream (--deltas).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <sstream>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "api/exported_mesh.h"
#include "cli_options.h"
#include "commands.h"
#include "fuse_loop_closure.h"
#include "core/map_format.h"
#include "core/mesh_analysis.h"
#include "core/refinement.h"
#include "core/frame_store.h"
#include "gpu/gpu_volume.h"
#include "gpu/map_corrector.h"
#include "gpu/tracking/pose_tracker.h"
#include "io/dataset.h"
#include "io/delta_stream.h"
#include "io/ply.h"
#include "io/png.h"
#include "io/trajectory.h"
#include "render/mesh_renderer.h"
#include "vk/context.h"
#ifdef VKMESH_HAVE_VIEWER
#include "viewer/viewer_server.h"
#endif

namespace vkmesh::cli {

namespace {

using json = nlohmann::json;

struct FuseArgs {
    DatasetArgs data;
    VolumeOptions volume;
    DeviceArgs device;
    MeshOutputArgs output;   // -o, --simplify
    std::string statsPath;
    bool growHeaps = false;
    bool quiet = false;
    bool noStageTimes = false;
    bool passTimes = false;
    // Pictures while fusing (drawn from the GPU mesh buffers) and the mesh-delta stream.
    uint32_t renderEvery = 0;
    std::string renderDir;
    std::string renderView = "sensor";
    std::string renderColor = "auto";
    std::string deltasPath;
    // The live browser viewer (docs/VIEWER.md): port (0: not serving), address, how long to keep serving after
    // the last frame (< 0: until Ctrl-C).
    int servePort = -1;
    std::string serveHost = "127.0.0.1";
    double serveLinger = -1;
    // Maps (docs/MAPFILE.md): continue from one, skip the frames it holds, save the state after the last frame.
    std::string loadPath;
    std::string savePath;
    size_t firstFrame = 0;
    // The frame store (docs/CORRECTION.md): kept with a saved map so that `vkmesh correct` can re-fuse frames.
    bool keepFrames = false, noKeepFrames = false;
    double framesBudgetMb = 1024;
    std::string framesSpill;
    // Camera tracking (docs/TRACKING.md): estimate every pose after the first against the mesh.
    bool track = false;
    std::string trajectoryPath;        // the pose used for every frame, TUM format
    std::string trackIterations;       // "3,4,4": ICP iterations per level, finest first (empty: by size)
    float trackColorWeight = gpu::TrackerOptions{}.colorWeight;   // the photometric term's weight (0: off)
    std::string trackSolve = "host";   // where the ICP systems are solved: host (double, a wait per iteration) or gpu
    int trackDownsample = gpu::TrackerOptions{}.downsample;   // track on frames downsampled by 1, 2 or 4 (0: by width)
    int trackModelReuse = gpu::TrackerOptions{}.modelReuseFrames;   // frames in a row that may reuse the model maps
    // Loop closure and relocalisation (docs/LOOP_CLOSURE.md).
    bool loopClosure = false;
    std::string trajectoryOnlinePath;  // the poses as they were when each frame was fused
    size_t correctionsPerFrame = 2;    // queued corrections re-fused before each frame
    const CLI::App* cmd = nullptr;   // which options were given (a loaded map's settings fill the others)
};

// Continuing a map: every setting the command line did not give is the map's; one it gave must agree with the
// map (GpuVolume::load refuses it otherwise, naming the file and the option).
void takeMapSettings(const CLI::App& cmd, const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& c) {
    auto given = [&](const char* option) { return cmd.get_option(option)->count() > 0; };
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

// The value below which `share` of the values lie (nearest rank).
double percentile(std::vector<double> values, double share) {
    if (values.empty()) return 0;
    std::sort(values.begin(), values.end());
    size_t rank = size_t(std::ceil(share * double(values.size())));
    return values[std::clamp<size_t>(rank, 1, values.size()) - 1];
}

json statsOf(std::vector<double> values) {
    if (values.empty()) return json{{"median", nullptr}, {"mean", nullptr}, {"max", nullptr}};
    double mean = std::accumulate(values.begin(), values.end(), 0.0) / values.size();
    std::sort(values.begin(), values.end());
    double median = values.size() % 2 ? values[values.size() / 2]
                                      : 0.5 * (values[values.size() / 2 - 1] + values[values.size() / 2]);
    return json{{"median", median}, {"mean", mean}, {"max", values.back()}};
}

int runFuse(const FuseArgs& args) {
#ifdef VKMESH_HAVE_VIEWER
    // With --serve, Ctrl-C stops the run between frames (polled below) instead of killing it: blocked before any
    // thread starts (the Vulkan driver's included), so that no thread takes it with the default action.
    if (args.servePort >= 0) viewer::blockStopSignals();
#endif
    args.output.check();   // the mesh's name and --simplify, before a long run
    // A map to continue is read and checked before anything else is opened.
    std::optional<map::MapData> loaded;
    if (!args.loadPath.empty()) loaded = map::readFile(args.loadPath);
    if (args.growHeaps)
        std::cerr << "note: --grow-heaps is deprecated and has no effect: capacities grow by default (--no-grow keeps them fixed)\n";
    if ((!args.trackIterations.empty() || args.cmd->get_option("--track-color-weight")->count() > 0 ||
         args.cmd->get_option("--track-solve")->count() > 0 || args.cmd->get_option("--track-downsample")->count() > 0 ||
         args.cmd->get_option("--track-model-reuse")->count() > 0) &&
        !args.track)
        throw Error("--track-iterations, --track-color-weight, --track-solve, --track-downsample and --track-model-reuse need --track");
    if ((args.loopClosure || !args.trajectoryOnlinePath.empty()) && !args.track)
        throw Error("--loop-closure and --trajectory-online need --track (loops are closed over tracked poses)");
    if (args.cmd->get_option("--corrections-per-frame")->count() > 0 && !args.loopClosure)
        throw Error("--corrections-per-frame needs --loop-closure");
    std::optional<std::array<int, gpu::TRACK_LEVELS>> iterations;
    if (!args.trackIterations.empty()) iterations = parseIterations(args.trackIterations);
    DatasetArgs data = args.data;
    data.posesOptional = args.track;
    auto dataset = data.open();
    for (const auto& w : dataset->warnings()) std::cerr << "warning: " << w << "\n";
    if (dataset->size() == 0) throw Error("no usable frame in " + args.data.dataset);
    const Intrinsics& intrinsics = dataset->intrinsics();

    if (args.firstFrame > 0 && args.firstFrame >= dataset->size())
        throw Error("--first-frame " + std::to_string(args.firstFrame) + " but " + args.data.dataset + " has " +
                    std::to_string(dataset->size()) + " usable frames");

    vk::Context context(args.device.contextOptions());
    gpu::GpuVolumeConfig config = args.volume.toConfig(args.data.maxDepth, intrinsics.width, intrinsics.height, dataset->hasColor());
    VolumeOptions vo = args.volume;   // what the run uses: a loaded map's settings where the command line gave none
    if (loaded) {
        takeMapSettings(*args.cmd, gpu::GpuVolume::mapConfig(*loaded), config);
        vo.voxel = config.params.voxelSize, vo.truncVoxels = config.params.truncVoxels, vo.allocStride = config.params.allocationStride;
        vo.mode = config.meshMode == gpu::MeshMode::Incremental ? "incremental" : "baseline";
        vo.refine = config.refine, vo.refineEps = config.refineEpsilonVoxels, vo.keepRadius = config.keepRadius;
        vo.recycle = config.recycle, vo.recycleAfter = config.recycleAfterFrames, vo.starveWeight = config.starveWeight;
        vo.colorMode = config.params.colorFusion == ColorFusion::Recent ? "recent" : "average";
        vo.colorRecency = config.params.colorRecency;
    }
    const bool fuseColor = config.params.colorFusion != ColorFusion::Off;
    const bool rendering = args.renderEvery > 0;
    const bool serving = args.servePort >= 0;
#ifndef VKMESH_HAVE_VIEWER
    if (serving)
        throw Error("--serve: this vkmesh was built without the browser viewer: it needs libboost-dev and libjs-three at build "
                    "time (scripts/install_deps.sh installs them)");
#endif
    if ((rendering || !args.deltasPath.empty() || serving) && config.meshMode != gpu::MeshMode::Incremental)
        throw Error("--render-every, --deltas and --serve need --mode incremental (the baseline keeps no mesh between frames)");
    if (rendering && args.renderDir.empty()) throw Error("--render-every needs --render-dir");
    config.publishMesh = rendering || args.track;   // tracking draws the mesh fused so far
    // GPU timestamps only where something reads them (issue 33, step 5: ~0.3-0.5 ms a frame on lavapipe): --stats,
    // --pass-times, the progress line and the viewer; `fuse -q` without --stats times nothing (its summary says so).
    config.timeStages = !args.noStageTimes && (!args.quiet || !args.statsPath.empty() || args.passTimes || serving);
    if (args.passTimes && args.noStageTimes) throw Error("--pass-times times the passes inside the stages: it cannot go with --no-stage-times");
    config.timePasses = args.passTimes;
    config.trackDeltas = !args.deltasPath.empty() || serving;
    double loadMs = 0;
    std::unique_ptr<gpu::GpuVolume> volumeOwner;
    const uint64_t loadedSaveId = loaded ? loaded->saveId : 0;
    if (loaded) {
        const auto t0 = std::chrono::steady_clock::now();
        volumeOwner = gpu::GpuVolume::load(context, *loaded, config, args.loadPath);
        loadMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        loaded.reset();   // the host copy is not needed any more
    } else {
        volumeOwner = std::make_unique<gpu::GpuVolume>(context, config);
    }
    gpu::GpuVolume& volume = *volumeOwner;
    // The frames as fused, for `vkmesh correct` (docs/CORRECTION.md): kept with a saved map. A loaded map's
    // store is continued (and must be the one saved with it).
    if (args.keepFrames && args.savePath.empty()) throw Error("--keep-frames keeps the frames with the map: give --save too");
    std::optional<gpu::MapCorrector> corrector;
    if (args.loopClosure && args.noKeepFrames) throw Error("--loop-closure re-fuses the frames a loop moves: it cannot go with --no-keep-frames");
    if ((!args.savePath.empty() && !args.noKeepFrames) || args.loopClosure) {
        FrameStoreOptions storeOptions;
        storeOptions.memoryBudgetBytes = size_t(args.framesBudgetMb * 1024 * 1024);
        storeOptions.spillFolder = args.framesSpill;
        const std::filesystem::path loadedStore = args.loadPath.empty() ? std::filesystem::path() : gpu::frameStorePathOf(args.loadPath);
        if (!loadedStore.empty() && std::filesystem::exists(loadedStore))
            corrector.emplace(FrameStore::load(loadedStore.string(), loadedSaveId, storeOptions));
        else
            corrector.emplace(FrameStore(storeOptions));
    }
    std::optional<render::MeshRenderer> renderer;
    render::RenderOptions renderOptions;
    if (rendering) {
        std::filesystem::create_directories(args.renderDir);
        renderer.emplace(context);
        renderOptions.width = intrinsics.width;
        renderOptions.height = intrinsics.height;
        renderOptions.color = render::parseColorMode(args.renderColor);
        if (renderOptions.color == render::ColorMode::Auto) renderOptions.color = fuseColor ? render::ColorMode::Rgb : render::ColorMode::Shade;
    }
    std::optional<gpu::PoseTracker> tracker;
    if (args.track) {
        if (config.meshMode != gpu::MeshMode::Incremental) throw Error("--track needs --mode incremental (it tracks against the mesh)");
        gpu::TrackerOptions trackerOptions;
        trackerOptions.maxDepth = args.data.maxDepth;
        if (iterations) trackerOptions.iterations = *iterations;
        trackerOptions.colorWeight = args.trackColorWeight;
        trackerOptions.solveOnGpu = args.trackSolve == "gpu";
        trackerOptions.downsample = args.trackDownsample;
        trackerOptions.modelReuseFrames = args.trackModelReuse;
        tracker.emplace(context, trackerOptions);
    }
    std::optional<FuseLoopClosure> loopClosure;
    if (args.loopClosure) {
        slam::LoopClosureOptions loopOptions;
        loopOptions.tracker = tracker->options();
        loopClosure.emplace(loopOptions, args.correctionsPerFrame);
        // A continued map: the keyframes and the pose graph saved with it (absent: the loop closer starts empty).
        if (!args.loadPath.empty() && std::filesystem::exists(loopClosurePathOf(args.loadPath)))
            loopClosure->load(loopClosurePathOf(args.loadPath), loadedSaveId);
    }
    std::vector<size_t> trajectoryFrames;   // the dataset frame of each trajectory entry
    std::vector<TimedPose> trajectory;   // the pose used for every frame (tracked, predicted or given)
    std::vector<double> trackMs, trackGpuMs, trackIterations, trackSubmissions, trackRmse, trackInlierShare;
    size_t modelDraws = 0;   // tracked frames that drew the mesh (the others reused the last model maps)
    std::vector<double> trackPositionError;   // metres from the dataset's pose, frames that have one
    std::map<std::string, std::vector<double>> trackStageMs;   // per tracking stage (timestamps)
    size_t lostFrames = 0;
    size_t relocalisedFrames = 0;   // lost by tracking from the prediction, then relocalised (--loop-closure)
    std::vector<json> lostList;
    std::optional<DeltaStreamWriter> deltaStream;
    if (!args.deltasPath.empty()) deltaStream.emplace(args.deltasPath);
#ifdef VKMESH_HAVE_VIEWER
    // The server runs on a thread of its own; this thread only posts each frame's delta to it (a copy), so a
    // page that is slow or gone never holds fusion up. Ctrl-C is taken here between frames (blocked in every
    // thread, polled), so that a stopped run still writes its mesh and stats.
    std::optional<viewer::Server> server;
    if (serving) {
        viewer::ServerOptions options;
        options.host = args.serveHost;
        options.port = uint16_t(args.servePort);
        options.quiet = args.quiet;
        server.emplace(options);
        std::cerr << "vkmesh fuse: serving the live viewer at " << server->url() << " (Ctrl-C stops)" << std::endl;
    }
#endif
    bool interrupted = false;
    size_t picturesWritten = 0;
    // Near/far planes of the sensor view: everything the sensor can see lies within maxDepth of a camera.
    Eigen::Vector3f seenMin = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), seenMax = -seenMin;

    const bool tty = isatty(STDERR_FILENO);
    std::map<std::string, std::vector<double>> stageMs, perFrame, passMs;
    std::vector<double> frameWallMs;
    size_t integrated = 0, skipped = 0, framesWithColor = 0;
    uint64_t hashFull = 0, poolExhausted = 0, touchedOverflow = 0;
    // Every other capacity event and the recycling counts, summed over the frames (the --stats JSON).
    std::map<std::string, uint64_t> events;
    size_t framesDeferred = 0;
    std::vector<std::string> growth;   // what grew, frame by frame (the library's policy, --stats "capacity_growth")
    std::vector<std::string> warnings;
    auto warn = [&](const std::string& w) {
        if (warnings.size() < 1000) warnings.push_back(w);
        if (tty && !args.quiet) std::cerr << "\n";
        std::cerr << "warning: " << w << "\n";
    };
    const auto start = std::chrono::steady_clock::now();
    for (size_t i = args.firstFrame; i < dataset->size(); ++i) {
#ifdef VKMESH_HAVE_VIEWER
        if (server && viewer::stopSignalPending()) {
            interrupted = true;
            warn("stopped by Ctrl-C before frame " + std::to_string(i) + "; the mesh so far is written");
            break;
        }
#endif
        DepthImage depth;
        try {
            depth = dataset->loadDepth(i);
        } catch (const Error& e) {
            warn(std::string("frame ") + std::to_string(i) + " skipped: " + e.what());
            ++skipped;
            continue;
        }
        size_t valid = std::count_if(depth.meters.begin(), depth.meters.end(), [&](float d) { return d > 0.0f; });
        // Colour: fused, and read by tracking's photometric term.
        ColorImage color;
        if (fuseColor || (tracker && tracker->options().colorWeight > 0 && dataset->hasColor())) {
            std::string problem;
            color = dataset->loadColor(i, &problem, &depth);
            if (color.empty() && !problem.empty()) warn("frame " + std::to_string(i) + (fuseColor ? " fused" : " tracked") + " without colour: " + problem);
            framesWithColor += fuseColor && !color.empty();
        }
        // The pose to fuse at: the dataset's, or with --track the first frame's (the dataset's or identity) and
        // then the tracked one. A lost frame is not fused (the map stays as it was) and gets the predicted pose.
        Pose pose = dataset->frame(i).cameraToWorld;
        std::optional<gpu::TrackedFusion> trackedFusion;   // a tracked frame: already fused when tracked
        if (tracker) {
            gpu::TrackingReport tr;
            if (!tracker->started()) {
                if (valid == 0) {
                    warn("frame " + std::to_string(i) + " skipped: no valid depth in " + dataset->frame(i).depthPath.string());
                    ++skipped;
                    continue;
                }
                tr = tracker->start(dataset->frame(i).hasPose ? dataset->frame(i).cameraToWorld : Pose::Identity());
            } else {
                if (loopClosure) loopClosure->beforeFrame(volume, *corrector);
                trackedFusion = tracker->trackAndFuse(volume, depth, intrinsics, &color, fuseColor ? &color : nullptr);
                tr = trackedFusion->tracking;
                if (!tr.tracked && loopClosure && valid > 0) {
                    // Relocalisation: tracked again from the keyframes that look like this frame.
                    std::optional<gpu::TrackedFusion> found =
                        loopClosure->relocalise(uint32_t(i), volume, *tracker, depth, &color, fuseColor ? &color : nullptr, intrinsics, tr.cameraToWorld);
                    if (found) {
                        trackedFusion = std::move(found);
                        tr = trackedFusion->tracking;
                        ++relocalisedFrames;
                    }
                }
                trackMs.push_back(tr.milliseconds);
                trackGpuMs.push_back(tr.gpuMilliseconds);
                for (const auto& [name, ms] : tr.gpuStageMilliseconds) trackStageMs[name].push_back(ms);
                trackIterations.push_back(tr.iterations);
                trackSubmissions.push_back(tr.submissions);
                modelDraws += tr.modelDrawn;
                if (tr.tracked) {
                    trackRmse.push_back(tr.rmse);
                    trackInlierShare.push_back(tr.validPixels > 0 ? tr.inliers / tr.validPixels : 0.0);
                }
            }
            pose = tr.cameraToWorld;
            trajectory.push_back({dataset->frame(i).timestamp, pose});
            trajectoryFrames.push_back(i);
            // The dataset's own pose (ground truth), where it has one, against the tracked one: the first frame's
            // is shared, so no alignment is needed (bench/ate.py aligns, as TUM's tools do).
            if (dataset->frame(i).hasPose)
                trackPositionError.push_back((pose.block<3, 1>(0, 3) - dataset->frame(i).cameraToWorld.block<3, 1>(0, 3)).norm());
            if (!tr.tracked) {
                ++lostFrames;
                if (lostList.size() < 1000) lostList.push_back({{"frame", i}, {"reason", tr.lostReason}});
                warn("frame " + std::to_string(i) + " lost (not fused): " + tr.lostReason);
                continue;
            }
        } else {
            trajectory.push_back({dataset->frame(i).timestamp, pose});
        }
        if (valid == 0) {
            warn("frame " + std::to_string(i) + " skipped: no valid depth in " + dataset->frame(i).depthPath.string());
            ++skipped;
            continue;
        }
        gpu::FrameReport report;
        if (trackedFusion) {
            // Fused by trackAndFuse (with --track-solve gpu in tracking's own submission: the wall time is the
            // whole frame's).
            report = std::move(*trackedFusion->fused);
            frameWallMs.push_back(trackedFusion->fuseMilliseconds);
        } else {
            auto t0 = std::chrono::steady_clock::now();
            report = volume.integrate(depth, fuseColor ? &color : nullptr, intrinsics, pose);
            frameWallMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        }
        ++integrated;
        if (corrector) corrector->keep(uint32_t(i), dataset->frame(i).timestamp, intrinsics, pose, depth, fuseColor ? &color : nullptr);
        if (loopClosure) loopClosure->frameFused(uint32_t(i), depth, &color, intrinsics, pose, *corrector, *tracker);
        double meshMs = 0;
        for (const auto& [name, ms] : report.stageMs) {
            stageMs[name].push_back(ms);
            if (name.rfind("mesh_", 0) == 0) meshMs += ms;
        }
        if (config.meshMode == gpu::MeshMode::Incremental && !report.stageMs.empty()) stageMs["mesh_total"].push_back(meshMs);
        std::map<std::string, double> framePassMs;   // a pass recorded more than once in the frame: its sum
        for (const auto& [name, ms] : report.passMs) framePassMs[name] += ms;
        for (const auto& [name, ms] : framePassMs) passMs[name].push_back(ms);
        perFrame["touched_blocks"].push_back(report.counters.touchedCount);
        perFrame["dispatches"].push_back(report.dispatches);
        // Allocation's work: blocks the band walks visited, and the visits that had to ask the hash.
        perFrame["block_visits"].push_back(report.counters.blockRequests);
        perFrame["hash_requests"].push_back(report.counters.blockRequests - report.counters.blocksShared);
        perFrame["dirty_blocks"].push_back(report.counters.dirtyCount);
        perFrame["cubes_retyped"].push_back(report.counters.cubesRetyped);
        perFrame["cubes_listed"].push_back(report.counters.retypeCount);   // the candidates claim classified
        perFrame["triangles_created"].push_back(report.counters.trianglesCreated);
        perFrame["vertices_moved"].push_back(report.counters.movedCount);
        hashFull += report.counters.hashFull;
        poolExhausted += report.counters.poolExhausted;
        touchedOverflow += report.counters.touchedCount > volume.config().touchedCapacity;
        const gpu::Counters& c = report.counters;
        for (const auto& [name, value] :
             {std::pair<const char*, uint32_t>{"vertex_heap_exhausted", c.vertexExhausted},
              {"chunk_heap_exhausted", c.chunkExhausted},
              {"triangles_not_built", c.trianglesInvalid},
              {"retype_deferred", c.retypeDeferred},
              {"gc_candidates_dropped", c.candidateCount > volume.config().vertexCapacity ? c.candidateCount - volume.config().vertexCapacity : 0u},
              {"out_of_range", c.outOfRange},
              {"ray_truncated", c.rayTruncated},
              {"outside_keep_radius", c.outsideRadius},
              {"blocks_retired", c.blocksRetired},
              {"blocks_starved", c.blocksStarved},
              {"blocks_freed", c.blocksFreed},
              {"recycle_deferred", c.recycleDeferred},
              {"hash_rebuilds", c.hashRebuilt},
              {"rehash_lost", c.rehashLost}})
            events[name] += value;
        for (const auto& w : report.warnings) warn("frame " + std::to_string(i) + ": " + w);
        for (const auto& g : report.growth) {
            growth.push_back("frame " + std::to_string(i) + ": " + g);
            if (report.growth.size() + growth.size() < 1000 && !args.quiet) {
                if (tty) std::cerr << "\n";
                std::cerr << "note: frame " << i << ": grew " << g << "\n";
            }
        }
        events["heap_growths"] += std::count_if(report.growth.begin(), report.growth.end(),
                                                [](const std::string& g) { return g.rfind("mesh heaps", 0) == 0; });
        framesDeferred += report.deferredAttempts;
        if (deltaStream) deltaStream->write(report.delta);
#ifdef VKMESH_HAVE_VIEWER
        if (server) {
            server->publish(report.delta, viewer::fusedFrameInfo(uint32_t(i + 1 - args.firstFrame), uint32_t(dataset->size() - args.firstFrame),
                                                                  frameWallMs.back(), report.counters.blocksInUse, pose, intrinsics));
        }
#endif
        if (rendering) {
            Eigen::Vector3f eye = pose.block<3, 1>(0, 3).cast<float>();
            seenMin = seenMin.cwiseMin(eye - Eigen::Vector3f::Constant(args.data.maxDepth));
            seenMax = seenMax.cwiseMax(eye + Eigen::Vector3f::Constant(args.data.maxDepth));
        }
        if (rendering && integrated % args.renderEvery == 0 && volume.meshBuffers().triangleCount > 0) {
            Eigen::Vector3f lo = seenMin, hi = seenMax;
            if (args.renderView == "sensor") {
                renderOptions.camera = render::sensorCamera(pose, intrinsics);
            } else {
                // The overview frames the mesh built so far, so its bounds are read (one small download).
                gpu::ExportedMesh sofar = volume.exportMesh();
                lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
                for (const auto& v : sofar.vertices) lo = lo.cwiseMin(Eigen::Vector3f(v.px, v.py, v.pz)), hi = hi.cwiseMax(Eigen::Vector3f(v.px, v.py, v.pz));
                renderOptions.camera = render::defaultCamera(lo, hi, renderOptions.width, renderOptions.height);
            }
            char name[32];
            std::snprintf(name, sizeof(name), "frame_%06zu.png", i);
            io::writePng(std::filesystem::path(args.renderDir) / name, renderer->render(volume.meshBuffers(), lo, hi, renderOptions));
            ++picturesWritten;
        }
        if (!args.quiet && (tty || (i + 1) % 50 == 0 || i + 1 == dataset->size())) {
            std::fprintf(stderr, "%sframe %zu/%zu  blocks %u  %.1f ms/frame%s", tty ? "\r" : "", i + 1, dataset->size(),
                         report.counters.blocksInUse, frameWallMs.back(), tty ? "   " : "\n");
        }
    }
    if (tty && !args.quiet) std::cerr << "\n";
    if (integrated == 0 && args.loadPath.empty()) throw Error("none of the " + std::to_string(dataset->size()) + " frames could be fused");
    if (!args.trajectoryOnlinePath.empty()) writeTumTrajectory(args.trajectoryOnlinePath, trajectory);
    if (loopClosure) {
        // The loops' corrections not yet re-fused, all now; the trajectory takes every frame's latest pose.
        loopClosure->finish(volume, *corrector);
        for (size_t k = 0; k < trajectory.size(); ++k) {
            Pose latest;
            if (loopClosure->latestPose(uint32_t(trajectoryFrames[k]), latest)) trajectory[k].cameraToWorld = latest;
        }
    }
    const double fuseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!args.trajectoryPath.empty()) writeTumTrajectory(args.trajectoryPath, trajectory);

    // The map is saved before the mesh is exported: the export may re-mesh cubes left pending, which a run
    // continuing from the map would otherwise do at another time than an uninterrupted one.
    double saveMs = 0;
    uintmax_t mapBytes = 0;
    if (!args.savePath.empty()) {
        const auto t0 = std::chrono::steady_clock::now();
        const uint64_t saveId = volume.save(args.savePath);
        if (corrector) corrector->store().save(gpu::frameStorePathOf(args.savePath).string(), saveId);
        if (loopClosure) loopClosure->save(loopClosurePathOf(args.savePath), saveId);
        saveMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        mapBytes = std::filesystem::file_size(args.savePath);
    }

    // The mesh: the persistent shared-vertex mesh compacted on the GPU, or the baseline soup. The baseline's
    // vertex count is measured on the same TSDF either way (the paper's memory comparison).
    std::vector<std::pair<std::string, double>> meshMs;
    auto t0 = std::chrono::steady_clock::now();
    Mesh mesh;
    size_t baselineVertices = 0;
    uint32_t unreferenced = 0;
    double sliverTriangleShare = 0, irregularCubeShare = 0;
    size_t boundaryEdges = 0, nonManifoldEdges = 0;   // of the shared-vertex mesh (a soup has no shared edges)
    size_t coincidentVertices = 0;                    // vertices at exactly the position of another (0 by design)
    if (config.meshMode == gpu::MeshMode::Incremental) {
        gpu::ExportedMesh exported = volume.exportMesh(&meshMs);
        unreferenced = exported.unreferencedVertices;
        mesh = toMesh(exported, volume.frameNumber());   // ages in the GPU's frame numbers, as createdFrame
        baselineVertices = volume.countBaselineVertices();
        // Regularity (what refinement improves): sliver triangles, and surface cubes whose type is not one of
        // the six half-cube types.
        sliverTriangleShare = triangleRegularity(mesh).sliverShare();
        auto types = volume.surfaceCubeTypes();
        uint64_t surface = 0, irregular = 0;
        for (int t = 0; t < 256; ++t) {
            surface += types[t];
            if (!isRegularType(t)) irregular += types[t];
        }
        irregularCubeShare = surface ? double(irregular) / double(surface) : 0.0;
        // Cracks (what refinement must not open): edges with one triangle.
        const TopologyReport topology = analyzeTopology(mesh);
        boundaryEdges = topology.boundaryEdges;
        nonManifoldEdges = topology.nonManifoldEdges;
        coincidentVertices = countDuplicatePositions(mesh);
    } else {
        gpu::TriangleSoup soup = volume.extractBaselineMesh(&meshMs);
        mesh.positions = soup.vertices;
        for (uint32_t t = 0; t < soup.triangleCount(); ++t) mesh.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
        baselineVertices = soup.vertices.size();
    }
    double meshWallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const std::filesystem::path out(args.output.path);
    const auto t1 = std::chrono::steady_clock::now();
    const std::optional<SimplifyReport> simplified = args.output.write(mesh);   // a copy is simplified, never the live mesh
    const double meshWriteMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();

    gpu::Counters k = volume.readCounters();
    json stats;
    stats["dataset"] = {{"path", std::filesystem::absolute(dataset->folder()).string()},
                        {"kind", toString(dataset->kind())},
                        {"frames_available", dataset->size()}};
    if (!dataset->description().empty()) stats["dataset"]["recording"] = dataset->description();
    stats["device"] = context.info().name;
    stats["unified_memory"] = context.unifiedMemory();   // the frame's images written in place, no staging copy
    stats["int64_atomics"] = context.int64Atomics();   // the block hash's path (docs/HASH.md)
    stats["mode"] = vo.mode;
    stats["refine"] = vo.refine;
    stats["refine_epsilon_voxels"] = vo.refineEps;
    stats["lock_free"] = vo.lockFree;
    stats["frames"] = {{"integrated", integrated}, {"skipped", skipped}};
    stats["voxel_size"] = vo.voxel;
    stats["truncation_m"] = config.params.truncation();
    stats["allocation_stride"] = vo.allocStride;
    stats["allocation_tiles"] = config.params.allocationTiles;
    stats["max_depth"] = args.data.maxDepth;
    stats["blocks"] = {{"in_use", k.blocksInUse}, {"capacity", volume.config().blockCapacity},
                       {"hash_capacity", volume.config().hashCapacity}, {"hash_entries", k.hashEntries},
                       {"hash_tombstones", k.hashTombstones}};
    stats["recycling"] = {{"keep_radius", vo.keepRadius}, {"recycle", vo.recycle},
                          {"recycle_after_frames", vo.recycleAfter}, {"starve_weight", vo.starveWeight}};
    stats["mesh"] = {{"vertices", mesh.positions.size()},
                     {"triangles", mesh.triangles.size()},
                     {"path", out.string()},
                     {"baseline_vertices", baselineVertices},
                     {"vertices_vs_baseline", baselineVertices ? double(mesh.positions.size()) / baselineVertices : 0.0},
                     {"unreferenced_vertices", unreferenced},
                     {"sliver_triangle_share", sliverTriangleShare},   // smallest angle < 10 degrees
                     {"irregular_cube_share", irregularCubeShare},
                     {"boundary_edges", boundaryEdges},
                     {"non_manifold_edges", nonManifoldEdges},
                     {"coincident_vertices", coincidentVertices}};
    if (config.meshMode == gpu::MeshMode::Incremental) {
        const gpu::GpuVolumeConfig& c = volume.config();
        stats["heaps"] = {{"vertices", {{"capacity", c.vertexCapacity}, {"live", k.verticesInUse}, {"free", k.vertexFreeTop},
                                        {"high_water", k.vertexHighWater}}},
                          {"triangle_chunks", {{"capacity", c.chunkCapacity}, {"live", k.chunksInUse}, {"free", k.chunkFreeTop},
                                               {"high_water", k.chunkHighWater}}},
                          {"live_triangles", k.liveTriangles}};
    }
    // Persistent state per cube: TSDF (sdf + weight) + cube state + 3 edge-vertex slots (+ colour).
    stats["bytes_per_cube"] = (config.meshMode == gpu::MeshMode::Incremental ? 24 : 8) + (fuseColor ? 4 : 0);
    stats["color"] = {{"fused", fuseColor},
                      {"mode", fuseColor ? args.volume.colorMode : std::string("off")},
                      {"recency", args.volume.colorRecency},
                      {"dataset_has_color", dataset->hasColor()},
                      {"frames_with_color", framesWithColor},
                      {"mesh_has_color", !mesh.colors.empty()}};
    json gpuMs = json::object();
    for (const auto& [name, values] : stageMs) gpuMs[name] = statsOf(values);
    stats["gpu_ms_per_frame"] = gpuMs;
    if (args.passTimes) {
        json perPass = json::object();
        for (const auto& [name, values] : passMs) perPass[name] = statsOf(values);
        stats["gpu_ms_per_pass"] = perPass;
    }
    if (stageMs.count("mesh_total")) {
        // The end of the sequence: the mesh is largest there (the peer's full extraction is timed there too).
        const auto& m = stageMs["mesh_total"];
        std::vector<double> tail(m.end() - std::max<ptrdiff_t>(1, ptrdiff_t(m.size()) / 10), m.end());
        stats["gpu_ms_mesh_last_10pct_frames"] = statsOf(tail);
    }
    json counts = json::object();
    for (const auto& [name, values] : perFrame) counts[name] = statsOf(values);
    stats["per_frame_counts"] = counts;
    json meshStage = json::object();
    for (const auto& [name, ms] : meshMs) meshStage[name] = ms;
    stats["gpu_ms_mesh_export"] = meshStage;
    stats["wall_ms_per_frame"] = statsOf(frameWallMs);
    stats["wall_ms_mesh_export"] = meshWallMs;
    stats["wall_ms_mesh_write"] = meshWriteMs;   // simplification (--simplify) and the file
    // "mesh" above describes the fused mesh; with --simplify the file holds the simplified copy described here.
    if (simplified)
        stats["simplify"] = {{"enabled", true},
                             {"ratio", simplified->ratio},
                             {"triangles_before", simplified->trianglesBefore},
                             {"triangles_after", simplified->trianglesAfter},
                             {"error_m", simplified->errorMetres},
                             {"max_relative_error", kSimplifyMaxRelativeError}};
    else
        stats["simplify"] = {{"enabled", false}};
    stats["wall_s_fusion_total"] = fuseSeconds;
    json pools = json::object();
    size_t total = 0;
    for (const auto& p : volume.pools()) pools[p.name] = p.bytes, total += p.bytes;
    stats["gpu_pool_bytes"] = pools;
    stats["gpu_bytes_total"] = total;
    json capacityEvents = {{"hash_full", hashFull}, {"pool_exhausted", poolExhausted},
                           {"frames_touching_more_than_capacity", touchedOverflow}};
    for (const auto& [name, total] : events) capacityEvents[name] = total;
    capacityEvents["frames_deferred"] = framesDeferred;   // run again after growing what their allocation overflowed
    stats["capacity_events"] = capacityEvents;
    stats["capacity_growth"] = growth;
    const gpu::GpuVolumeConfig& grownTo = volume.config();
    stats["capacities"] = {{"grow", grownTo.growCapacities}, {"blocks", grownTo.blockCapacity}, {"hash_slots", grownTo.hashCapacity},
                           {"touched", grownTo.touchedCapacity}, {"retype", grownTo.retypeCapacity},
                           {"vertices", grownTo.vertexCapacity}, {"triangle_chunks", grownTo.chunkCapacity}};
    stats["map"] = {{"loaded", args.loadPath}, {"load_ms", loadMs}, {"first_frame", args.firstFrame}, {"saved", args.savePath},
                    {"save_ms", saveMs}, {"bytes", mapBytes}, {"live_blocks", k.blocksInUse},
                    {"bytes_per_live_block", k.blocksInUse ? double(mapBytes) / k.blocksInUse : 0.0}};
    if (corrector) {
        const FrameStoreStats fs = corrector->store().stats();
        const std::filesystem::path storePath = gpu::frameStorePathOf(args.savePath);
        stats["frame_store"] = {{"path", storePath.string()}, {"frames", fs.frames}, {"frames_spilled", fs.framesSpilled},
                                {"raw_bytes", fs.rawBytes}, {"compressed_bytes", fs.compressedBytes},
                                {"bytes_in_memory", fs.bytesInMemory}, {"bytes_on_disk", fs.bytesOnDisk},
                                {"file_bytes", std::filesystem::exists(storePath) ? std::filesystem::file_size(storePath) : 0},
                                {"bytes_per_frame", fs.frames ? double(fs.compressedBytes) / fs.frames : 0.0}};
    }
    if (tracker) {
        json ms = statsOf(trackMs);
        ms["p90"] = percentile(trackMs, 0.9);
        json gpuTrackMs = statsOf(trackGpuMs);
        gpuTrackMs["p90"] = percentile(trackGpuMs, 0.9);
        json stages = json::object();
        for (const auto& [name, values] : trackStageMs) stages[name] = statsOf(values);
        double squared = 0;
        for (double e : trackPositionError) squared += e * e;
        json positionError = {{"frames", trackPositionError.size()},
                              {"rmse", trackPositionError.empty() ? 0.0 : std::sqrt(squared / double(trackPositionError.size()))},
                              {"max", trackPositionError.empty() ? 0.0 : *std::max_element(trackPositionError.begin(), trackPositionError.end())}};
        json its = statsOf(trackIterations);
        its["total"] = std::accumulate(trackIterations.begin(), trackIterations.end(), 0.0);
        stats["tracking"] = {{"enabled", true},
                             {"frames_tracked", trackMs.size() - lostFrames},
                             {"lost_frames", lostFrames},
                             {"lost", lostList},
                             {"ms_per_frame", ms},
                             {"gpu_ms_per_frame", gpuTrackMs},
                             {"gpu_ms_stages", stages},
                             {"iterations", its},
                             {"submissions_per_frame", statsOf(trackSubmissions)},
                             {"rmse_m", statsOf(trackRmse)},
                             {"inlier_share", statsOf(trackInlierShare)},
                             {"color_weight", args.trackColorWeight},
                             {"solve", args.trackSolve},
                             // --track-solve gpu: tracking, fusion and meshing are one submission per frame, so
                             // ms_per_frame (wall) holds the fusion and meshing too
                             {"fused_in_tracking_submission", args.trackSolve == "gpu"},
                             {"downsample", gpu::trackingDownsample(tracker->options(), intrinsics.width)},
                             // frames whose tracking drew the mesh; the others reused the last maps (--track-model-reuse)
                             {"model_draws", modelDraws},
                             {"model_reuse_frames", args.trackModelReuse},
                             // against the dataset's poses where it has them (the first frame's is shared: no
                             // alignment); metres
                             {"position_error_m", positionError},
                             {"relocalised_frames", relocalisedFrames},
                             {"trajectory", args.trajectoryPath},
                             {"trajectory_online", args.trajectoryOnlinePath}};
    } else {
        stats["tracking"] = {{"enabled", false}, {"trajectory", args.trajectoryPath}};
    }
    if (loopClosure) {
        json lc = loopClosure->stats();
        // The final poses (every loop's correction applied) against the dataset's, as position_error_m above.
        std::vector<double> errors;
        for (size_t k = 0; k < trajectory.size(); ++k)
            if (dataset->frame(trajectoryFrames[k]).hasPose)
                errors.push_back((trajectory[k].cameraToWorld.block<3, 1>(0, 3) - dataset->frame(trajectoryFrames[k]).cameraToWorld.block<3, 1>(0, 3)).norm());
        double squared = 0;
        for (double e : errors) squared += e * e;
        lc["position_error_m"] = {{"frames", errors.size()},
                                  {"rmse", errors.empty() ? 0.0 : std::sqrt(squared / double(errors.size()))},
                                  {"max", errors.empty() ? 0.0 : *std::max_element(errors.begin(), errors.end())}};
        lc["corrections_per_frame"] = args.correctionsPerFrame;
        stats["loop_closure"] = lc;
    } else {
        stats["loop_closure"] = {{"enabled", false}};
    }
    stats["warnings"] = warnings;
    if (!args.statsPath.empty()) {
        std::ofstream file(args.statsPath);
        if (!file) throw Error("cannot write " + args.statsPath);
        file << stats.dump(2) << "\n";
    }
    auto median = [&](const char* name) { return stageMs.count(name) ? statsOf(stageMs[name])["median"].get<double>() : 0.0; };
    std::cout << "vkmesh fuse: " << integrated << " frames (" << skipped << " skipped) from " << args.data.dataset << " on "
              << context.info().name << "\n"
              << "  voxel " << vo.voxel << " m, " << k.blocksInUse << " blocks, mesh (" << vo.mode << "): "
              << mesh.positions.size() << " vertices (baseline " << baselineVertices << "), " << mesh.triangles.size()
              << " triangles -> " << out.string() << "\n"
              << (simplified ? "  " + describe(*simplified) + "\n" : "");
    if (!config.timeStages)
        std::cout << "  per frame (median, GPU stages not timed" << (args.noStageTimes ? "" : ": -q without --stats") << "): ";
    else
        std::cout << "  GPU per frame (median): allocate " << median("allocate") << " ms, fuse " << median("fuse") << " ms, mesh "
                  << median("mesh_total") << " ms; ";
    std::cout << "wall " << statsOf(frameWallMs)["median"].get<double>() << " ms/frame\n";
    if (tracker)
        std::cout << "  tracking: " << trackMs.size() - lostFrames << " frames tracked, " << lostFrames << " lost; "
                  << statsOf(trackMs)["median"] << " ms/frame (median), " << statsOf(trackIterations)["mean"] << " iterations/frame (mean)"
                  << (args.trajectoryPath.empty() ? std::string() : " -> " + args.trajectoryPath) << "\n";
    if (loopClosure) {
        const json& lc = stats["loop_closure"];
        std::cout << "  loop closure: " << lc["keyframes"] << " keyframes, " << lc["loops_accepted"] << " loops accepted of "
                  << lc["loops_detected"] << " detected, " << lc["relocalisations"] << " relocalisations of " << lc["lost_frames"]
                  << " lost frames, " << lc["frames_refused"] << " frames re-fused\n";
    }
    if (tracker && !trackPositionError.empty()) {
        char line[160];
        std::snprintf(line, sizeof line, "  tracked positions against the dataset's poses: RMSE %.1f mm, largest %.1f mm over %zu frames\n",
                      1000 * stats["tracking"]["position_error_m"]["rmse"].get<double>(),
                      1000 * stats["tracking"]["position_error_m"]["max"].get<double>(), trackPositionError.size());
        std::cout << line;
    }
    if (rendering) std::cout << "  " << picturesWritten << " pictures (" << args.renderView << " view) -> " << args.renderDir << "\n";
    if (deltaStream) std::cout << "  mesh deltas: " << deltaStream->bytesWritten() << " bytes -> " << args.deltasPath << "\n";
    if (!args.loadPath.empty()) std::cout << "  map loaded from " << args.loadPath << " (" << loadMs << " ms), frames from " << args.firstFrame << "\n";
    if (!args.savePath.empty())
        std::cout << "  map: " << mapBytes << " bytes (" << (k.blocksInUse ? mapBytes / k.blocksInUse : 0) << " per live block) -> "
                  << args.savePath << " (" << saveMs << " ms)\n";
    if (!warnings.empty()) std::cout << "  " << warnings.size() << " warnings (see stderr)\n";
#ifdef VKMESH_HAVE_VIEWER
    if (server) {
        std::cout << std::flush;
        if (!interrupted && args.serveLinger != 0) {
            std::cerr << "vkmesh fuse: done; still serving at " << server->url()
                      << (args.serveLinger < 0 ? " (Ctrl-C stops)" : " for " + std::to_string(args.serveLinger) + " s") << std::endl;
            viewer::waitForStopSignal(args.serveLinger);
        }
        server->stop();
        const viewer::ServerStats v = server->stats();
        std::cout << "  viewer: " << v.pagesConnected << " pages, " << v.messagesSent << " messages, " << v.bytesSent
                  << " bytes sent, " << v.framesCoalesced << " frame updates coalesced for slow pages\n";
        if (!args.statsPath.empty()) {
            // Written again with the viewer's counts, known only now that serving has ended.
            uint32_t maxLag = 0;
            double sumLag = 0;
            for (uint32_t l : v.lagAtAck) maxLag = std::max(maxLag, l), sumLag += l;
            stats["viewer"] = {{"url", server->url()}, {"pages", v.pagesConnected}, {"messages_sent", v.messagesSent},
                               {"bytes_sent", v.bytesSent}, {"frames_published", v.framesPublished},
                               {"frames_coalesced", v.framesCoalesced}, {"pages_closed_malformed", v.pagesClosedMalformed},
                               {"acks", v.lagAtAck.size()}, {"lag_frames_max", maxLag},
                               {"lag_frames_mean", v.lagAtAck.empty() ? 0.0 : sumLag / v.lagAtAck.size()}};
            std::ofstream file(args.statsPath);
            if (!file) throw Error("cannot write " + args.statsPath);
            file << stats.dump(2) << "\n";
        }
    }
#endif
    (void)interrupted;
    return 0;
}

}  // namespace

Run addFuseCommand(CLI::App& app) {
    auto args = std::make_shared<FuseArgs>();
    auto* cmd = app.add_subcommand("fuse", "fuse a depth sequence into a TSDF on the GPU and write its mesh");
    args->data.add(cmd);
    args->output.add(cmd);
    cmd->add_option("--stats", args->statsPath, "write counts, timings and memory as JSON");
    args->volume.addCommon(cmd);
    args->volume.addTuning(cmd);
    cmd->add_flag("--grow-heaps", args->growHeaps,
                  "deprecated, no effect: every capacity grows by default (--no-grow keeps them fixed)");
    args->device.add(cmd);
    cmd->add_flag("-q,--quiet", args->quiet, "no progress line");
    cmd->add_flag("--no-stage-times", args->noStageTimes,
                  "record no GPU timestamps between stages (~0.3-0.5 ms per frame on lavapipe); the summary and --stats then "
                  "have no GPU stage times, only wall times (-q without --stats records none either)");
    cmd->add_flag("--pass-times", args->passTimes,
                  "also a GPU timestamp after every pass (compute dispatch) of a frame: --stats gains gpu_ms_per_pass, each "
                  "pass's time per frame by shader name (each timestamp costs ~50 us on lavapipe: for profiling)");
    cmd->add_option("--render-every", args->renderEvery, "write a picture of the mesh every N frames (drawn from the GPU buffers)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--render-dir", args->renderDir, "folder for the --render-every pictures (frame_NNNNNN.png)");
    cmd->add_option("--render-view", args->renderView, "sensor: from the frame's camera; overview: framing the mesh so far")
        ->check(CLI::IsMember({"sensor", "overview"}));
    cmd->add_option("--render-color", args->renderColor,
                    "shade, normal, age (warm = new, cold = old) or rgb (the fused colours); default: rgb when colour is "
                    "fused, else shade")
        ->check(CLI::IsMember({"shade", "normal", "age", "rgb", "auto"}));
    cmd->add_option("--deltas", args->deltasPath, "write every frame's mesh changes to this stream file (docs/DELTAS.md)");
    cmd->add_option("--save", args->savePath, "write the whole state after the last frame to this map file (.vkmap, docs/MAPFILE.md)");
    cmd->add_flag("--keep-frames", args->keepFrames,
                  "keep every frame as fused (compressed) in a frame store saved beside the --save map (MAP.vkframes), so "
                  "that vkmesh correct can re-fuse frames whose poses change (the default with --save)");
    cmd->add_flag("--no-keep-frames", args->noKeepFrames, "with --save: do not keep the frames (the map cannot be corrected later)");
    cmd->add_option("--frames-budget", args->framesBudgetMb, "the frame store's memory budget in MiB (compressed frames)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--frames-spill", args->framesSpill, "folder for the frames beyond --frames-budget (else the run stops there)");
    cmd->add_option("--load", args->loadPath,
                    "continue the map in this file (its settings unless given; with --first-frame, the frames it does not hold yet)");
    cmd->add_option("--first-frame", args->firstFrame, "start at this frame of the dataset (0-based; frames before it are skipped)");
    cmd->add_flag("--track", args->track,
                  "estimate the camera poses: every frame after the first is tracked against the mesh fused so far "
                  "(the first frame's pose is the dataset's, or identity when it has none; its other poses are not used). "
                  "Datasets without poses need it");
    cmd->add_option("--trajectory", args->trajectoryPath,
                    "write the pose used for every frame (tracked or given) in TUM format: timestamp tx ty tz qx qy qz qw; with "
                    "--loop-closure the final poses, every loop's correction applied");
    cmd->add_flag("--loop-closure", args->loopClosure,
                  "with --track: recognise places seen before (keyframes, random ferns), verify them by ICP, optimise a pose graph "
                  "(Ceres) and re-fuse the frames a loop moves; relocalise lost frames from the keyframes (docs/LOOP_CLOSURE.md)");
    cmd->add_option("--trajectory-online", args->trajectoryOnlinePath,
                    "with --track: write the poses as they were when each frame was fused (TUM format), before any loop's correction");
    cmd->add_option("--corrections-per-frame", args->correctionsPerFrame,
                    "with --loop-closure: frames a loop moved that are re-fused before each new frame (default 2; the rest after the last frame)");
    cmd->add_option("--track-iterations", args->trackIterations,
                    "ICP iterations per pyramid level, finest first (default by the finest tracked level's width: 3,4,4 from 320 "
                    "pixels wide, 10,5,4 below)");
    cmd->add_option("--track-color-weight", args->trackColorWeight,
                    "weight of tracking's photometric term (the frame's intensity against the mesh's fused colours; needs "
                    "colour images and colour fusion); 0: geometry only")
        ->check(CLI::Range(0.0, 100.0));
    cmd->add_option("--track-solve", args->trackSolve,
                    "where tracking solves its 6x6 systems: host (in double, one GPU submission per ICP iteration) or gpu (in "
                    "float; the frame's tracking, fusion and meshing in one submission; docs/TRACKING.md)")
        ->check(CLI::IsMember({"host", "gpu"}));
    cmd->add_option("--track-downsample", args->trackDownsample,
                    "track on the frames downsampled by 1, 2 or 4 (fusion keeps the full frames); 0 (default): 2 for frames at "
                    "least 640 pixels wide, else 1 (on 640x480 a quarter of the finest level's work at the same accuracy; "
                    "docs/TRACKING.md)")
        ->check(CLI::IsMember({0, 1, 2, 4}));
    cmd->add_option("--track-model-reuse", args->trackModelReuse,
                    "let up to this many frames in a row (default 2) reuse the model maps (the mesh drawn at an earlier pose) "
                    "while the predicted pose is within 4 cm and 4 degrees of where they were drawn; 0 draws the mesh for "
                    "every frame")
        ->check(CLI::Range(0, 1000));
    cmd->add_option("--serve", args->servePort,
                    "serve the live browser viewer on this port while fusing (docs/VIEWER.md; open the URL it prints)")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--host", args->serveHost, "address --serve listens on (default 127.0.0.1: this machine only; 0.0.0.0: every interface)");
    cmd->add_option("--serve-linger", args->serveLinger,
                    "with --serve: keep serving this many seconds after the last frame (default: until Ctrl-C; 0: stop at once)");
    args->cmd = cmd;
    return [args] { return runFuse(*args); };
}

}  // namespace vkmesh::cli
