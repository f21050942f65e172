// `vkmesh fuse DATASET -o mesh.ply`: opens the dataset, feeds its frames to the library's frame loop (api/mapper.h)
// with the sinks the options ask for (host/fuse_sinks.h), and writes the mesh, the trajectory, the map and the
// --stats JSON (the library's run statistics, api/run_stats_json.h, plus what only this command knows: the
// dataset, the mesh file, map and viewer timings). Options: host/fuse_options.h.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "api/exported_mesh.h"
#include "api/mapper.h"
#include "api/run_stats_json.h"
#include "commands.h"
#include "fuse_options.h"
#include "fuse_sinks.h"
#include "io/dataset.h"
#include "io/trajectory.h"
#include "vk/context.h"
#ifdef VKMESH_HAVE_VIEWER
#include "viewer/viewer_server.h"
#endif

namespace vkmesh::cli {

namespace {

using json = nlohmann::json;

double millisecondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void writeJson(const std::string& path, const json& value) {
    std::ofstream file(path);
    if (!file) throw Error("cannot write " + path);
    file << value.dump(2) << "\n";
}

// The frames' own images for frame i: depth (an unreadable one is skipped) and colour where the volume fuses it or
// tracking's photometric term reads it.
struct LoadedFrame {
    DepthImage depth;
    ColorImage color;
};

int runFuse(const FuseArgs& args) {
#ifdef VKMESH_HAVE_VIEWER
    // With --serve, Ctrl-C stops the run between frames (polled below) instead of killing it: blocked before any
    // thread starts (the Vulkan driver's included), so that no thread takes it with the default action.
    if (args.serving()) viewer::blockStopSignals();
#endif
    args.check();
    // A map to continue is read and checked before anything else is opened.
    std::optional<map::MapData> loaded;
    if (!args.loadPath.empty()) loaded = map::readFile(args.loadPath);
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
    const gpu::GpuVolumeConfig config = args.volumeConfig(intrinsics, dataset->hasColor(), loaded ? &*loaded : nullptr);
    Mapper mapper(context, args.mapperOptions(config));
    double loadMs = 0;
    if (loaded) {
        const auto t0 = std::chrono::steady_clock::now();
        mapper.loadMap(*loaded, config, args.loadPath);
        loadMs = millisecondsSince(t0);
    } else {
        mapper.createVolume(intrinsics.width, intrinsics.height);
    }
    // The frames as fused, for `vkmesh correct` (docs/CORRECTION.md) and loop closure: kept with a saved map. A
    // loaded map's store is continued (and must be the one saved with it).
    if (args.loopClosureDroppedForSize(intrinsics.width, intrinsics.height))
        std::cerr << "vkmesh fuse: note: no loop closure or relocalisation: the " << intrinsics.width << "x" << intrinsics.height
                  << " frames are smaller than place recognition's image (--loop-closure asks for it anyway, and says why it cannot)\n";
    if ((!args.savePath.empty() && !args.noKeepFrames) || args.closesLoops(intrinsics.width, intrinsics.height)) {
        const std::filesystem::path loadedStore = args.loadPath.empty() ? std::filesystem::path() : gpu::frameStorePathOf(args.loadPath);
        if (!loadedStore.empty() && std::filesystem::exists(loadedStore))
            mapper.keepFrames(FrameStore::load(loadedStore.string(), loaded->saveId, args.frameStoreOptions()));
        else
            mapper.keepFrames(FrameStore(args.frameStoreOptions()));
    }
    loaded.reset();   // the host copy is not needed any more
    const bool fuseColor = mapper.volume().fusesColor();

    ProgressSink progress(dataset->size(), args.quiet);
    OnlineTrajectorySink online;
    mapper.addSink(&progress);
    mapper.addSink(&online);
    std::optional<DeltaStreamSink> deltas;
    if (!args.deltasPath.empty()) mapper.addSink(&deltas.emplace(args.deltasPath));
    std::optional<PictureSink> pictures;
    if (args.renderEvery > 0)
        mapper.addSink(&pictures.emplace(context, args.renderDir, args.renderEvery, args.renderView, args.renderColor, fuseColor, intrinsics,
                                         args.data.maxDepth));
#ifdef VKMESH_HAVE_VIEWER
    // The server runs on a thread of its own; this thread only posts each frame's delta to it (a copy), so a
    // page that is slow or gone never holds fusion up. Ctrl-C is taken here between frames (blocked in every
    // thread, polled), so that a stopped run still writes its mesh and stats.
    std::optional<viewer::Server> server;
    std::optional<ViewerSink> viewerSink;
    if (args.serving()) {
        viewer::ServerOptions options;
        options.host = args.serveHost;
        options.port = uint16_t(args.servePort);
        options.quiet = args.quiet;
        server.emplace(options);
        mapper.addSink(&viewerSink.emplace(*server, uint32_t(args.firstFrame), uint32_t(dataset->size())));
        std::cerr << "vkmesh fuse: serving the live viewer at " << server->url() << " (Ctrl-C stops)" << std::endl;
    }
#endif

    bool interrupted = false;
    const bool tracksColor = args.track && args.trackColorWeight > 0 && dataset->hasColor();
    for (size_t i = args.firstFrame; i < dataset->size(); ++i) {
#ifdef VKMESH_HAVE_VIEWER
        if (server && viewer::stopSignalPending()) {
            interrupted = true;
            const std::string w = "stopped by Ctrl-C before frame " + std::to_string(i) + "; the mesh so far is written";
            mapper.warn(w), progress.warn(w);
            break;
        }
#endif
        const FrameInfo& f = dataset->frame(i);
        LoadedFrame images;
        try {
            images.depth = dataset->loadDepth(i);
        } catch (const Error& e) {
            mapper.skip(uint32_t(i), e.what());
            progress.warn("frame " + std::to_string(i) + " skipped: " + e.what());
            continue;
        }
        if (fuseColor || tracksColor) {
            std::string problem;
            images.color = dataset->loadColor(i, &problem, &images.depth);
            if (images.color.empty() && !problem.empty()) {
                const std::string w = "frame " + std::to_string(i) + (fuseColor ? " fused" : " tracked") + " without colour: " + problem;
                mapper.warn(w), progress.warn(w);
            }
        }
        MapperFrame frame;
        frame.index = uint32_t(i);
        frame.timestamp = f.timestamp;
        frame.depth = &images.depth;
        frame.color = &images.color;
        frame.intrinsics = intrinsics;
        frame.source = f.depthPath.string();
        if (!args.track) {
            frame.pose = f.cameraToWorld;
        } else {
            // The first frame starts at the dataset's pose (or identity); the dataset's poses are the reference the
            // tracked ones are measured against (the first is shared, so no alignment is needed).
            frame.startPose = f.hasPose ? f.cameraToWorld : Pose::Identity();
            if (f.hasPose) frame.reference = f.cameraToWorld;
        }
        mapper.process(frame);
    }
    if (progress.tty() && !args.quiet) std::cerr << "\n";
    if (mapper.stats().integrated == 0 && args.loadPath.empty())
        throw Error("none of the " + std::to_string(dataset->size()) + " frames could be fused");
    if (!args.trajectoryOnlinePath.empty()) writeTumTrajectory(args.trajectoryOnlinePath, online.poses());
    // The loops' corrections not yet re-fused, all now; the trajectory takes every frame's latest pose.
    mapper.finish();
    if (!args.trajectoryPath.empty()) {
        std::vector<TimedPose> trajectory;
        for (size_t k = 0; k < mapper.trajectory().size(); ++k)
            if (mapper.trajectory()[k].posed) trajectory.push_back({mapper.trajectory()[k].timestamp, mapper.poses()[k]});
        writeTumTrajectory(args.trajectoryPath, trajectory);
    }

    // The map is saved before the mesh is exported: the export may re-mesh cubes left pending, which a run
    // continuing from the map would otherwise do at another time than an uninterrupted one.
    double saveMs = 0;
    uintmax_t mapBytes = 0;
    if (!args.savePath.empty()) {
        const auto t0 = std::chrono::steady_clock::now();
        mapper.save(args.savePath);
        saveMs = millisecondsSince(t0);
        mapBytes = std::filesystem::file_size(args.savePath);
    }
    const auto t0 = std::chrono::steady_clock::now();
    const RunMesh result = meshOfRun(mapper.volume(), args.analyseMesh);
    const double meshWallMs = millisecondsSince(t0);
    const Mesh& mesh = result.mesh;
    const std::filesystem::path out(args.output.path);
    const auto t1 = std::chrono::steady_clock::now();
    const std::optional<SimplifyReport> simplified = args.output.write(mesh);   // a copy is simplified, never the live mesh
    const double meshWriteMs = millisecondsSince(t1);

    // The library's statistics, and what only this command knows.
    const RunStats run = mapper.stats();
    json stats = runStatsJson(mapper);
    stats["dataset"] = {{"path", std::filesystem::absolute(dataset->folder()).string()},
                        {"kind", toString(dataset->kind())},
                        {"frames_available", dataset->size()}};
    if (!dataset->description().empty()) stats["dataset"]["recording"] = dataset->description();
    stats["color"]["dataset_has_color"] = dataset->hasColor();
    stats["color"]["mesh_has_color"] = !mesh.colors.empty();
    const uint32_t blocksInUse = stats["blocks"]["in_use"].get<uint32_t>();
    // The analyses (--analyse-mesh) are null when not asked for: the keys stay for the scripts that read them.
    auto analysed = [&](auto value) { return result.analysed ? json(value) : json(nullptr); };
    stats["mesh"] = {{"vertices", mesh.positions.size()},
                     {"triangles", mesh.triangles.size()},
                     {"path", out.string()},
                     {"analysed", result.analysed},
                     {"baseline_vertices", analysed(result.baselineVertices)},
                     {"vertices_vs_baseline", analysed(result.baselineVertices ? double(mesh.positions.size()) / result.baselineVertices : 0.0)},
                     {"unreferenced_vertices", result.unreferencedVertices},
                     {"sliver_triangle_share", analysed(result.sliverTriangleShare)},   // smallest angle < 10 degrees
                     {"irregular_cube_share", analysed(result.irregularCubeShare)},
                     {"boundary_edges", analysed(result.boundaryEdges)},
                     {"non_manifold_edges", analysed(result.nonManifoldEdges)},
                     {"coincident_vertices", analysed(result.coincidentVertices)}};
    json meshStage = json::object();
    for (const auto& [name, ms] : result.stageMs) meshStage[name] = ms;
    stats["gpu_ms_mesh_export"] = meshStage;
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
    stats["map"] = {{"loaded", args.loadPath}, {"load_ms", loadMs}, {"first_frame", args.firstFrame}, {"saved", args.savePath},
                    {"save_ms", saveMs}, {"bytes", mapBytes}, {"live_blocks", blocksInUse},
                    {"bytes_per_live_block", blocksInUse ? double(mapBytes) / blocksInUse : 0.0}};
    if (stats.contains("frame_store")) {
        const std::filesystem::path storePath = gpu::frameStorePathOf(args.savePath);
        stats["frame_store"]["path"] = storePath.string();
        stats["frame_store"]["file_bytes"] = std::filesystem::exists(storePath) ? std::filesystem::file_size(storePath) : 0;
    }
    stats["tracking"]["trajectory"] = args.trajectoryPath;
    if (args.track) stats["tracking"]["trajectory_online"] = args.trajectoryOnlinePath;
    if (!args.statsPath.empty()) writeJson(args.statsPath, stats);

    auto median = [&](const char* name) {
        auto it = run.stageMs.find(name);
        return it == run.stageMs.end() ? 0.0 : summarize(it->second).median;
    };
    std::cout << "vkmesh fuse: " << run.integrated << " frames (" << run.skipped << " skipped) from " << args.data.dataset << " on "
              << context.info().name << "\n"
              << "  voxel " << config.params.voxelSize << " m, " << blocksInUse << " blocks, mesh (" << stats["mode"].get<std::string>()
              << "): " << mesh.positions.size() << " vertices"
              << (result.analysed ? " (baseline " + std::to_string(result.baselineVertices) + ")" : std::string()) << ", " << mesh.triangles.size()
              << " triangles -> " << out.string() << "\n"
              << (simplified ? "  " + describe(*simplified) + "\n" : "");
    if (!config.timeStages)
        std::cout << "  per frame (median, GPU stages not timed" << (args.noStageTimes ? "" : ": -q without --stats") << "): ";
    else
        std::cout << "  GPU per frame (median): allocate " << median("allocate") << " ms, fuse " << median("fuse") << " ms, mesh "
                  << median("mesh_total") << " ms; ";
    std::cout << "wall " << summarize(run.frameWallMs).median << " ms/frame\n";
    if (run.tracking.enabled) {
        const json& t = stats["tracking"];
        std::cout << "  tracking: " << t["frames_tracked"] << " frames tracked, " << t["lost_frames"] << " lost"
                  << (t["tentative_frames"] > 0 ? ", " + t["tentative_frames"].dump() + " tentative (not fused)" : std::string()) << "; "
                  << t["ms_per_frame"]["median"] << " ms/frame (median), " << t["iterations"]["mean"] << " iterations/frame (mean)"
                  << (args.trajectoryPath.empty() ? std::string() : " -> " + args.trajectoryPath) << "\n";
    }
    if (run.loopClosure) {
        const json& lc = stats["loop_closure"];
        std::cout << "  loop closure: " << lc["keyframes"] << " keyframes, " << lc["loops_accepted"] << " loops accepted of "
                  << lc["loops_detected"] << " detected, " << lc["relocalisations"] << " relocalisations of " << lc["lost_frames"]
                  << " lost frames, " << lc["frames_refused"] << " frames re-fused\n";
    }
    if (run.tracking.enabled && !run.tracking.positionError.empty()) {
        char line[160];
        std::snprintf(line, sizeof line, "  tracked positions against the dataset's poses: RMSE %.1f mm, largest %.1f mm over %zu frames\n",
                      1000 * stats["tracking"]["position_error_m"]["rmse"].get<double>(),
                      1000 * stats["tracking"]["position_error_m"]["max"].get<double>(), run.tracking.positionError.size());
        std::cout << line;
    }
    if (pictures) std::cout << "  " << pictures->written() << " pictures (" << args.renderView << " view) -> " << args.renderDir << "\n";
    if (deltas) std::cout << "  mesh deltas: " << deltas->bytesWritten() << " bytes -> " << args.deltasPath << "\n";
    if (!args.loadPath.empty()) std::cout << "  map loaded from " << args.loadPath << " (" << loadMs << " ms), frames from " << args.firstFrame << "\n";
    if (!args.savePath.empty())
        std::cout << "  map: " << mapBytes << " bytes (" << (blocksInUse ? mapBytes / blocksInUse : 0) << " per live block) -> "
                  << args.savePath << " (" << saveMs << " ms)\n";
    if (!run.warnings.empty()) std::cout << "  " << run.warnings.size() << " warnings (see stderr)\n";
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
            writeJson(args.statsPath, stats);
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
    addFuseOptions(cmd, *args);
    return [args] { return runFuse(*args); };
}

}  // namespace vkmesh::cli
