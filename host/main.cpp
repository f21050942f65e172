// vkmesh: the command-line program.
//   vkmesh devices                      list Vulkan devices and whether vkmesh can use them
//   vkmesh synth OUT_DIR                render a synthetic RGB-D sequence with ground truth (TUM layout)
//   vkmesh fuse DATASET -o mesh.ply     fuse a depth sequence on the GPU and write its mesh
//   vkmesh frames DATASET -o f.json     the frames (paths, poses, intrinsics) fuse would use, for peers
//   vkmesh eval MESH --gt GT.ply        accuracy, completeness, precision/recall/F-score against ground truth
//   vkmesh render MESH -o view.png      render a mesh offscreen (Vulkan graphics pipeline) to a PNG
//   vkmesh soak -o soak.csv             long synthetic run with revisits: hash/pool/heap occupancy per frame
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <numeric>
#include <optional>

#include "api/exported_mesh.h"
#include "core/mesh_analysis.h"
#include "core/mesh_delta.h"
#include "io/delta_stream.h"
#include "render/mesh_renderer.h"
#include "eval_command.h"
#include "render_command.h"
#include "soak_command.h"
#include "core/refinement.h"
#include "gpu/gpu_volume.h"
#include "io/dataset.h"
#include "io/ply.h"
#include "synth/synthetic_scene.h"
#include "vk/context.h"

namespace {

using namespace vkmesh;
using json = nlohmann::json;

struct CommonDatasetArgs {
    std::string dataset;
    size_t frames = 0;
    float maxDepth = 4.0f;
    std::string intrinsics;
    double depthScale = 0;

    void add(CLI::App* cmd) {
        cmd->add_option("DATASET", dataset, "dataset folder (TUM, ICL-NUIM, Redwood, 7-Scenes layout)")->required();
        cmd->add_option("--frames", frames, "use at most N frames (0 = all)");
        cmd->add_option("--max-depth", maxDepth, "ignore depth beyond M metres")->check(CLI::PositiveNumber);
        cmd->add_option("--intrinsics", intrinsics, "override the camera: fx,fy,cx,cy");
        cmd->add_option("--depth-scale", depthScale, "raw depth units per metre (5000 TUM, 1000 mm)")->check(CLI::PositiveNumber);
    }
    std::unique_ptr<Dataset> open() const {
        DatasetOptions options;
        if (!intrinsics.empty()) options.intrinsics = parseIntrinsics(intrinsics);
        if (depthScale > 0) options.depthScale = depthScale;
        options.maxDepth = maxDepth;
        options.maxFrames = frames;
        return Dataset::open(dataset, options);
    }
};

json statsOf(std::vector<double> values) {
    if (values.empty()) return json{{"median", nullptr}, {"mean", nullptr}, {"max", nullptr}};
    double mean = std::accumulate(values.begin(), values.end(), 0.0) / values.size();
    std::sort(values.begin(), values.end());
    double median = values.size() % 2 ? values[values.size() / 2]
                                      : 0.5 * (values[values.size() / 2 - 1] + values[values.size() / 2]);
    return json{{"median", median}, {"mean", mean}, {"max", values.back()}};
}

int commandDevices() {
    auto devices = vk::Context::listDevices();
    if (devices.empty()) {
        std::cout << "No Vulkan device. Install a driver (apt-get install mesa-vulkan-drivers gives lavapipe).\n";
        return 1;
    }
    for (const auto& d : devices) {
        std::cout << d.index << ": " << d.name << " (" << d.type << ", Vulkan " << d.apiVersion << ", " << d.driver << ")"
                  << (d.suitable ? "; block hash: " + d.hashPath : "  NOT USABLE: " + d.whyNot) << "\n";
    }
    return 0;
}

int commandSynth(const std::string& out, size_t frames, int width, int height, bool noise, uint32_t seed,
                 const std::string& path) {
    synth::SequenceOptions options;
    options.frames = frames;
    options.width = width;
    options.height = height;
    options.intrinsics = synth::kinectIntrinsics(width, height);
    options.noise = noise;
    options.seed = seed;
    options.path = path == "revisit" ? synth::PathKind::Revisit : synth::PathKind::Orbit;
    synth::writeTumSequence(out, synth::SyntheticScene::defaultRoom(), options);
    std::cerr << "wrote " << frames << " frames of the synthetic room to " << out << "\n";
    return 0;
}

int commandFrames(const CommonDatasetArgs& args, const std::string& out) {
    auto dataset = args.open();
    const Intrinsics& k = dataset->intrinsics();
    json j;
    j["dataset"] = std::filesystem::absolute(dataset->folder()).string();
    j["kind"] = toString(dataset->kind());
    j["depth_scale"] = dataset->depthScale();
    j["max_depth"] = args.maxDepth;
    j["intrinsics"] = {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}, {"width", k.width}, {"height", k.height}};
    j["frames"] = json::array();
    for (size_t i = 0; i < dataset->size(); ++i) {
        const FrameInfo& f = dataset->frame(i);
        std::vector<double> m(16);
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) m[r * 4 + c] = f.cameraToWorld(r, c);
        j["frames"].push_back({{"index", f.index}, {"timestamp", f.timestamp},
                               {"depth_path", std::filesystem::absolute(f.depthPath).string()}, {"camera_to_world", m}});
    }
    std::ofstream file(out);
    if (!file) throw Error("cannot write " + out);
    file << j.dump(1) << "\n";
    std::cerr << "wrote " << dataset->size() << " frames to " << out << "\n";
    return 0;
}

struct FuseArgs {
    CommonDatasetArgs data;
    std::string output;
    std::string statsPath;
    std::string mode = "incremental";
    float voxel = 0.03f;
    float truncVoxels = 4.0f;
    float maxWeight = 255.0f;
    float minWeight = 1.0f;
    bool refine = false;
    float refineEps = gpu::GpuVolumeConfig{}.refineEpsilonVoxels;
    bool lockFree = false;
    uint32_t blocks = 16384;
    uint32_t vertices = gpu::GpuVolumeConfig{}.vertexCapacity;
    uint32_t chunks = gpu::GpuVolumeConfig{}.chunkCapacity;
    uint32_t hashSlots = 0;   // 0: twice the block capacity, rounded up to a power of two
    float keepRadius = 0.0f;
    bool recycle = false;
    uint32_t recycleAfter = gpu::GpuVolumeConfig{}.recycleAfterFrames;
    float starveWeight = gpu::GpuVolumeConfig{}.starveWeight;
    bool growHeaps = false;
    int allocStride = VolumeParams{}.allocationStride;
    int device = -1;
    bool validation = false;
    bool quiet = false;
    // Pictures while fusing (drawn from the GPU mesh buffers) and the mesh-delta stream.
    uint32_t renderEvery = 0;
    std::string renderDir;
    std::string renderView = "sensor";
    std::string renderColor = "shade";
    std::string deltasPath;
};

int commandFuse(const FuseArgs& args) {
    auto dataset = args.data.open();
    for (const auto& w : dataset->warnings()) std::cerr << "warning: " << w << "\n";
    if (dataset->size() == 0) throw Error("no usable frame in " + args.data.dataset);
    const Intrinsics& intrinsics = dataset->intrinsics();

    vk::Context context({args.device, args.validation});
    gpu::GpuVolumeConfig config;
    config.params.voxelSize = args.voxel;
    config.params.truncVoxels = args.truncVoxels;
    config.params.maxWeight = args.maxWeight;
    config.minMeshWeight = args.minWeight;
    config.refine = args.refine;
    config.refineEpsilonVoxels = args.refineEps;
    config.lockFree = args.lockFree;
    config.params.maxDepth = args.data.maxDepth;
    config.params.allocationStride = args.allocStride;
    config.blockCapacity = args.blocks;
    config.meshMode = args.mode == "baseline" ? gpu::MeshMode::Baseline : gpu::MeshMode::Incremental;
    config.vertexCapacity = args.vertices;
    config.chunkCapacity = args.chunks;
    config.hashCapacity = args.hashSlots;
    config.keepRadius = args.keepRadius;
    config.recycle = args.recycle;
    config.recycleAfterFrames = args.recycleAfter;
    config.starveWeight = args.starveWeight;
    config.imageWidth = intrinsics.width;
    config.imageHeight = intrinsics.height;
    const bool rendering = args.renderEvery > 0;
    if ((rendering || !args.deltasPath.empty()) && config.meshMode != gpu::MeshMode::Incremental)
        throw Error("--render-every and --deltas need --mode incremental (the baseline keeps no mesh between frames)");
    if (rendering && args.renderDir.empty()) throw Error("--render-every needs --render-dir");
    config.publishMesh = rendering;
    config.trackDeltas = !args.deltasPath.empty();
    gpu::GpuVolume volume(context, config);
    std::optional<render::MeshRenderer> renderer;
    render::RenderOptions renderOptions;
    if (rendering) {
        std::filesystem::create_directories(args.renderDir);
        renderer.emplace(context);
        renderOptions.width = intrinsics.width;
        renderOptions.height = intrinsics.height;
        renderOptions.color = render::parseColorMode(args.renderColor);
    }
    std::optional<DeltaStreamWriter> deltaStream;
    if (!args.deltasPath.empty()) deltaStream.emplace(args.deltasPath);
    size_t picturesWritten = 0;
    // Near/far planes of the sensor view: everything the sensor can see lies within maxDepth of a camera.
    Eigen::Vector3f seenMin = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), seenMax = -seenMin;

    const bool tty = isatty(STDERR_FILENO);
    std::map<std::string, std::vector<double>> stageMs, perFrame;
    std::vector<double> frameWallMs;
    size_t integrated = 0, skipped = 0;
    uint64_t hashFull = 0, poolExhausted = 0, touchedOverflow = 0;
    // Every other capacity event and the recycling counts, summed over the frames (the --stats JSON).
    std::map<std::string, uint64_t> events;
    bool grownSinceLastFrame = false;   // --grow-heaps: the heaps grew and no frame has re-meshed since
    std::vector<std::string> warnings;
    auto warn = [&](const std::string& w) {
        if (warnings.size() < 1000) warnings.push_back(w);
        if (tty && !args.quiet) std::cerr << "\n";
        std::cerr << "warning: " << w << "\n";
    };
    const auto start = std::chrono::steady_clock::now();
    for (size_t i = 0; i < dataset->size(); ++i) {
        DepthImage depth;
        try {
            depth = dataset->loadDepth(i);
        } catch (const Error& e) {
            warn(std::string("frame ") + std::to_string(i) + " skipped: " + e.what());
            ++skipped;
            continue;
        }
        size_t valid = std::count_if(depth.meters.begin(), depth.meters.end(), [&](float d) { return d > 0.0f; });
        if (valid == 0) {
            warn("frame " + std::to_string(i) + " skipped: no valid depth in " + dataset->frame(i).depthPath.string());
            ++skipped;
            continue;
        }
        auto t0 = std::chrono::steady_clock::now();
        gpu::FrameReport report = volume.integrate(depth, intrinsics, dataset->frame(i).cameraToWorld);
        grownSinceLastFrame = false;
        frameWallMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        ++integrated;
        double meshMs = 0;
        for (const auto& [name, ms] : report.stageMs) {
            stageMs[name].push_back(ms);
            if (name.rfind("mesh_", 0) == 0) meshMs += ms;
        }
        if (config.meshMode == gpu::MeshMode::Incremental) stageMs["mesh_total"].push_back(meshMs);
        perFrame["touched_blocks"].push_back(report.counters.touchedCount);
        perFrame["dirty_blocks"].push_back(report.counters.dirtyCount);
        perFrame["cubes_retyped"].push_back(report.counters.cubesRetyped);
        perFrame["triangles_created"].push_back(report.counters.trianglesCreated);
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
        if (args.growHeaps && config.meshMode == gpu::MeshMode::Incremental && (c.vertexExhausted || c.chunkExhausted)) {
            // Grow the heap that ran out by what the frame could not get, at least doubling it, within what one
            // storage buffer may hold; the next frame re-meshes the cubes left incomplete.
            const gpu::GpuVolumeConfig& now = volume.config();
            auto grown = [&](uint32_t capacity, uint32_t missing, uint64_t bytesEach) {
                if (!missing) return capacity;
                const uint64_t wanted = std::max<uint64_t>(2ull * capacity, uint64_t(capacity) + 2ull * missing);
                return uint32_t(std::min<uint64_t>(wanted, context.maxStorageBufferRange() / bytesEach));
            };
            const uint32_t vertices = grown(now.vertexCapacity, c.vertexExhausted, sizeof(gpu::Vertex));
            const uint32_t chunks = grown(now.chunkCapacity, c.chunkExhausted, gpu::CHUNK_WORDS * 4);
            if (vertices > now.vertexCapacity || chunks > now.chunkCapacity) {
                volume.growMeshHeaps(vertices, chunks);
                grownSinceLastFrame = true;
                warn("frame " + std::to_string(i) + ": mesh heaps grown to " + std::to_string(vertices) + " vertices, " +
                     std::to_string(chunks) + " triangle chunks");
                ++events["heap_growths"];
            }
        }
        if (deltaStream) deltaStream->write(report.delta);
        if (rendering) {
            const Pose& pose = dataset->frame(i).cameraToWorld;
            Eigen::Vector3f eye = pose.block<3, 1>(0, 3).cast<float>();
            seenMin = seenMin.cwiseMin(eye - Eigen::Vector3f::Constant(args.data.maxDepth));
            seenMax = seenMax.cwiseMax(eye + Eigen::Vector3f::Constant(args.data.maxDepth));
        }
        if (rendering && integrated % args.renderEvery == 0 && volume.meshBuffers().triangleCount > 0) {
            Eigen::Vector3f lo = seenMin, hi = seenMax;
            if (args.renderView == "sensor") {
                renderOptions.camera = render::sensorCamera(dataset->frame(i).cameraToWorld, intrinsics);
            } else {
                // The overview frames the mesh built so far, so its bounds are read (one small download).
                gpu::ExportedMesh sofar = volume.exportMesh();
                lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
                for (const auto& v : sofar.vertices) lo = lo.cwiseMin(Eigen::Vector3f(v.px, v.py, v.pz)), hi = hi.cwiseMax(Eigen::Vector3f(v.px, v.py, v.pz));
                renderOptions.camera = render::defaultCamera(lo, hi, renderOptions.width, renderOptions.height);
            }
            char name[32];
            std::snprintf(name, sizeof(name), "frame_%06zu.png", i);
            render::writePng(std::filesystem::path(args.renderDir) / name, renderer->render(volume.meshBuffers(), lo, hi, renderOptions));
            ++picturesWritten;
        }
        if (!args.quiet && (tty || (i + 1) % 50 == 0 || i + 1 == dataset->size())) {
            std::fprintf(stderr, "%sframe %zu/%zu  blocks %u  %.1f ms/frame%s", tty ? "\r" : "", i + 1, dataset->size(),
                         report.counters.blocksInUse, frameWallMs.back(), tty ? "   " : "\n");
        }
    }
    if (tty && !args.quiet) std::cerr << "\n";
    if (integrated == 0) throw Error("none of the " + std::to_string(dataset->size()) + " frames could be fused");
    if (grownSinceLastFrame) {
        // The heaps grew after the last frame: no frame is left to re-mesh the incomplete cubes, so the mesh is
        // rebuilt from the TSDF (vertex ages restart at the last frame).
        volume.rebuildMesh();
        warn("mesh rebuilt after the last frame's heap growth (vertex ages restart)");
    }
    const double fuseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    // The mesh: the persistent shared-vertex mesh compacted on the GPU, or the baseline soup. The baseline's
    // vertex count is measured on the same TSDF either way (the paper's memory comparison).
    std::vector<std::pair<std::string, double>> meshMs;
    auto t0 = std::chrono::steady_clock::now();
    Mesh mesh;
    size_t baselineVertices = 0;
    uint32_t unreferenced = 0;
    double sliverTriangleShare = 0, irregularCubeShare = 0;
    if (config.meshMode == gpu::MeshMode::Incremental) {
        gpu::ExportedMesh exported = volume.exportMesh(&meshMs);
        unreferenced = exported.unreferencedVertices;
        mesh = toMesh(exported, volume.framesIntegrated());
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
    } else {
        gpu::TriangleSoup soup = volume.extractBaselineMesh(&meshMs);
        mesh.positions = soup.vertices;
        for (uint32_t t = 0; t < soup.triangleCount(); ++t) mesh.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
        baselineVertices = soup.vertices.size();
    }
    double meshWallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::filesystem::path out(args.output);
    if (out.extension() == ".obj")
        writeObj(out, mesh);
    else
        writePly(out, mesh);

    gpu::Counters k = volume.readCounters();
    json stats;
    stats["dataset"] = {{"path", std::filesystem::absolute(dataset->folder()).string()},
                        {"kind", toString(dataset->kind())},
                        {"frames_available", dataset->size()}};
    stats["device"] = context.info().name;
    stats["int64_atomics"] = context.int64Atomics();   // the block hash's path (docs/HASH.md)
    stats["mode"] = args.mode;
    stats["refine"] = args.refine;
    stats["refine_epsilon_voxels"] = args.refineEps;
    stats["lock_free"] = args.lockFree;
    stats["frames"] = {{"integrated", integrated}, {"skipped", skipped}};
    stats["voxel_size"] = args.voxel;
    stats["truncation_m"] = config.params.truncation();
    stats["allocation_stride"] = args.allocStride;
    stats["max_depth"] = args.data.maxDepth;
    stats["blocks"] = {{"in_use", k.blocksInUse}, {"capacity", volume.config().blockCapacity},
                       {"hash_capacity", volume.config().hashCapacity}, {"hash_entries", k.hashEntries},
                       {"hash_tombstones", k.hashTombstones}};
    stats["recycling"] = {{"keep_radius", args.keepRadius}, {"recycle", args.recycle},
                          {"recycle_after_frames", args.recycleAfter}, {"starve_weight", args.starveWeight}};
    stats["mesh"] = {{"vertices", mesh.positions.size()},
                     {"triangles", mesh.triangles.size()},
                     {"path", out.string()},
                     {"baseline_vertices", baselineVertices},
                     {"vertices_vs_baseline", baselineVertices ? double(mesh.positions.size()) / baselineVertices : 0.0},
                     {"unreferenced_vertices", unreferenced},
                     {"sliver_triangle_share", sliverTriangleShare},   // smallest angle < 10 degrees
                     {"irregular_cube_share", irregularCubeShare}};
    if (config.meshMode == gpu::MeshMode::Incremental) {
        const gpu::GpuVolumeConfig& c = volume.config();
        stats["heaps"] = {{"vertices", {{"capacity", c.vertexCapacity}, {"live", k.verticesInUse}, {"free", k.vertexFreeTop},
                                        {"high_water", k.vertexHighWater}}},
                          {"triangle_chunks", {{"capacity", c.chunkCapacity}, {"live", k.chunksInUse}, {"free", k.chunkFreeTop},
                                               {"high_water", k.chunkHighWater}}},
                          {"live_triangles", k.liveTriangles}};
    }
    // Persistent state per cube: TSDF (sdf + weight) + cube state + 3 edge-vertex slots.
    stats["bytes_per_cube"] = config.meshMode == gpu::MeshMode::Incremental ? 24 : 8;
    json gpuMs = json::object();
    for (const auto& [name, values] : stageMs) gpuMs[name] = statsOf(values);
    stats["gpu_ms_per_frame"] = gpuMs;
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
    stats["wall_s_fusion_total"] = fuseSeconds;
    json pools = json::object();
    size_t total = 0;
    for (const auto& p : volume.pools()) pools[p.name] = p.bytes, total += p.bytes;
    stats["gpu_pool_bytes"] = pools;
    stats["gpu_bytes_total"] = total;
    json capacityEvents = {{"hash_full", hashFull}, {"pool_exhausted", poolExhausted},
                           {"frames_touching_more_than_capacity", touchedOverflow}};
    for (const auto& [name, total] : events) capacityEvents[name] = total;
    stats["capacity_events"] = capacityEvents;
    stats["warnings"] = warnings;
    if (!args.statsPath.empty()) {
        std::ofstream file(args.statsPath);
        if (!file) throw Error("cannot write " + args.statsPath);
        file << stats.dump(2) << "\n";
    }
    auto median = [&](const char* name) { return stageMs.count(name) ? statsOf(stageMs[name])["median"].get<double>() : 0.0; };
    std::cout << "vkmesh fuse: " << integrated << " frames (" << skipped << " skipped) from " << args.data.dataset << " on "
              << context.info().name << "\n"
              << "  voxel " << args.voxel << " m, " << k.blocksInUse << " blocks, mesh (" << args.mode << "): "
              << mesh.positions.size() << " vertices (baseline " << baselineVertices << "), " << mesh.triangles.size()
              << " triangles -> " << out.string() << "\n"
              << "  GPU per frame (median): allocate " << median("allocate") << " ms, fuse " << median("fuse") << " ms, mesh "
              << median("mesh_total") << " ms; "
              << "wall " << statsOf(frameWallMs)["median"].get<double>() << " ms/frame\n";
    if (rendering) std::cout << "  " << picturesWritten << " pictures (" << args.renderView << " view) -> " << args.renderDir << "\n";
    if (deltaStream) std::cout << "  mesh deltas: " << deltaStream->bytesWritten() << " bytes -> " << args.deltasPath << "\n";
    if (!warnings.empty()) std::cout << "  " << warnings.size() << " warnings (see stderr)\n";
    return 0;
}

// `vkmesh deltas`: what a remote viewer does with the stream: apply every frame, write the mesh it holds.
int commandDeltas(const std::string& streamPath, const std::string& output, uint32_t untilFrame) {
    MeshReplica replica;
    size_t frames = 0, records = 0;
    readDeltaStream(streamPath, [&](const MeshDelta& d) {
        if (untilFrame && d.frame > untilFrame) return;
        replica.apply(d);
        ++frames;
        records += d.vertices.size() + d.triangles.size();
    });
    Mesh mesh = replica.toMesh();
    if (!output.empty()) writePly(output, mesh);
    std::cout << "vkmesh deltas: " << frames << " frames, " << records << " records from " << streamPath << " -> mesh at frame "
              << replica.lastFrame() << ": " << mesh.positions.size() << " vertices, " << mesh.triangles.size() << " triangles"
              << (output.empty() ? "" : " -> " + output) << "\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"vkmesh: real-time TSDF fusion and meshing on any Vulkan device"};
    app.require_subcommand(1);

    app.add_subcommand("devices", "list Vulkan devices and whether vkmesh can use them");

    auto* synth = app.add_subcommand("synth", "render a synthetic depth sequence with ground truth (TUM layout)");
    std::string synthOut, synthPath = "orbit";
    size_t synthFrames = 60;
    int synthWidth = 640, synthHeight = 480;
    bool synthNoise = false;
    uint32_t synthSeed = 1;
    synth->add_option("OUT_DIR", synthOut, "folder to write")->required();
    synth->add_option("--frames", synthFrames, "number of frames")->check(CLI::PositiveNumber);
    synth->add_option("--width", synthWidth, "image width")->check(CLI::Range(16, 4096));
    synth->add_option("--height", synthHeight, "image height")->check(CLI::Range(16, 4096));
    synth->add_flag("--noise", synthNoise, "Kinect-like noise and dropout");
    synth->add_option("--seed", synthSeed, "noise seed");
    synth->add_option("--path", synthPath, "camera path")->check(CLI::IsMember({"orbit", "revisit"}));

    auto* frames = app.add_subcommand("frames", "write the frames fuse would use (paths, poses, intrinsics) as JSON");
    CommonDatasetArgs framesArgs;
    std::string framesOut;
    framesArgs.add(frames);
    frames->add_option("-o,--output", framesOut, "JSON file to write")->required();

    auto* fuse = app.add_subcommand("fuse", "fuse a depth sequence into a TSDF on the GPU and write its mesh");
    FuseArgs fuseArgs;
    fuseArgs.data.add(fuse);
    fuse->add_option("-o,--output", fuseArgs.output, "mesh file (.ply binary, or .obj)")->required();
    fuse->add_option("--stats", fuseArgs.statsPath, "write counts, timings and memory as JSON");
    fuse->add_option("--mode", fuseArgs.mode,
                     "incremental: one shared-vertex mesh updated every frame (default); "
                     "baseline: marching cubes at the end, every triangle with its own 3 vertices")
        ->check(CLI::IsMember({"incremental", "baseline"}));
    fuse->add_flag("--refine,!--no-refine", fuseArgs.refine,
                   "Hamming-distance refinement of cube types (paper §V.F; off by default: it opens cracks between "
                   "refined and unrefined cubes, see docs/REFINEMENT.md)");
    fuse->add_option("--refine-eps", fuseArgs.refineEps, "refinement: corners within this many voxels of the surface may flip")
        ->check(CLI::Range(0.0f, 1.0f));
    fuse->add_flag("--lock-free", fuseArgs.lockFree, "claim edge vertices in 4 parity-class passes without atomics (paper's lock-free)");
    fuse->add_option("--vertices", fuseArgs.vertices, "vertex heap capacity")->check(CLI::PositiveNumber);
    fuse->add_option("--chunks", fuseArgs.chunks, "triangle chunk heap capacity (5 triangles each)")->check(CLI::PositiveNumber);
    fuse->add_option("--hash-slots", fuseArgs.hashSlots, "spatial hash capacity, a power of two (0 = 2x --blocks)");
    fuse->add_option("--keep-radius", fuseArgs.keepRadius,
                     "bounded map: keep only blocks within R metres of the camera; farther ones are not allocated and are "
                     "freed with their mesh (0 = off, the default)")
        ->check(CLI::NonNegativeNumber);
    fuse->add_flag("--recycle", fuseArgs.recycle,
                   "bounded map: blocks not seen for --recycle-after frames lose --starve-weight per frame and are freed "
                   "(with their mesh) once empty (off by default)");
    fuse->add_option("--recycle-after", fuseArgs.recycleAfter, "frames without a touch before a block starves")
        ->check(CLI::PositiveNumber);
    fuse->add_option("--starve-weight", fuseArgs.starveWeight, "weight a starving block's corners lose per frame")
        ->check(CLI::PositiveNumber);
    fuse->add_flag("--grow-heaps", fuseArgs.growHeaps,
                   "when the vertex or triangle-chunk heap runs out, double it before the next frame (up to one storage "
                   "buffer) and re-mesh the cubes left incomplete; without it a full heap leaves triangles out, with a warning");
    fuse->add_option("--voxel", fuseArgs.voxel, "voxel (cube) size in metres");
    fuse->add_option("--trunc", fuseArgs.truncVoxels, "truncation distance in voxels");
    fuse->add_option("--max-weight", fuseArgs.maxWeight, "cap of the TSDF weight");
    fuse->add_option("--min-weight", fuseArgs.minWeight, "a cube is meshed when its 8 corners have at least this weight")
        ->check(CLI::Range(1.0f, 255.0f));
    fuse->add_option("--alloc-stride", fuseArgs.allocStride,
                     "allocate blocks from every Nth pixel in x and y (1 = every pixel, as the paper; Open3D uses 4)")
        ->check(CLI::Range(1, 64));
    fuse->add_option("--blocks", fuseArgs.blocks, "block pool capacity (8x8x8 voxels each)")->check(CLI::PositiveNumber);
    fuse->add_option("--device", fuseArgs.device, "Vulkan device index (see `vkmesh devices`)");
    fuse->add_flag("--validation", fuseArgs.validation, "enable the Khronos validation layer (or VKMESH_VALIDATION=1)");
    fuse->add_flag("-q,--quiet", fuseArgs.quiet, "no progress line");
    fuse->add_option("--render-every", fuseArgs.renderEvery, "write a picture of the mesh every N frames (drawn from the GPU buffers)")
        ->check(CLI::PositiveNumber);
    fuse->add_option("--render-dir", fuseArgs.renderDir, "folder for the --render-every pictures (frame_NNNNNN.png)");
    fuse->add_option("--render-view", fuseArgs.renderView, "sensor: from the frame's camera; overview: framing the mesh so far")
        ->check(CLI::IsMember({"sensor", "overview"}));
    fuse->add_option("--render-color", fuseArgs.renderColor, "shade, normal or age (warm = new, cold = old)")
        ->check(CLI::IsMember({"shade", "normal", "age"}));
    fuse->add_option("--deltas", fuseArgs.deltasPath, "write every frame's mesh changes to this stream file (docs/DELTAS.md)");

    auto* deltas = app.add_subcommand("deltas", "replay a mesh-delta stream as a remote viewer would and write the mesh it ends with");
    std::string deltasIn, deltasOut;
    uint32_t deltasUntil = 0;
    deltas->add_option("STREAM", deltasIn, "stream written by fuse --deltas")->required();
    deltas->add_option("-o,--output", deltasOut, "PLY mesh to write");
    deltas->add_option("--until-frame", deltasUntil, "stop after this frame number (0 = all)");

    auto runEval = vkmesh::addEvalCommand(app);
    auto runRender = vkmesh::addRenderCommand(app);
    auto runSoak = vkmesh::addSoakCommand(app);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    try {
        if (app.got_subcommand("devices")) return commandDevices();
        if (app.got_subcommand("synth"))
            return commandSynth(synthOut, synthFrames, synthWidth, synthHeight, synthNoise, synthSeed, synthPath);
        if (app.got_subcommand("frames")) return commandFrames(framesArgs, framesOut);
        if (app.got_subcommand("fuse")) return commandFuse(fuseArgs);
        if (app.got_subcommand("eval")) return runEval();
        if (app.got_subcommand("render")) return runRender();
        if (app.got_subcommand("deltas")) return commandDeltas(deltasIn, deltasOut, deltasUntil);
        if (app.got_subcommand("soak")) return runSoak();
    } catch (const vkmesh::Error& e) {
        std::cerr << "vkmesh: error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "vkmesh: internal error: " << e.what() << "\n";
        return 3;
    }
    return 0;
}
