// vkmesh_gpubench: per-stage GPU times of the ordinary frame pipeline on the synthetic room, with nothing to
// install but a Vulkan driver. It renders the sequence `vkmesh synth` writes by default (the furnished room,
// the 60-pose orbit, 640x480, colour, no noise) in memory, quantised as the TUM writer and the dataset reader
// would (1/5000 m, depth beyond 4 m dropped), and fuses it as `vkmesh fuse` does with its defaults (incremental
// shared-vertex mesh kept current every frame, colour fused by running average) at each voxel size asked for:
// it drives the library's frame loop, vkmesh::Mapper (api/mapper.h), and reports what the Mapper reports per frame.
// It links the vkmesh libraries statically and libstdc++/libgcc statically too, so the binary needs only glibc,
// libvulkan.so.1 and libzstd.so.1 (the Mapper's frame store): scripts/pack_gpubench.sh packs it with the loader
// and libzstd for a bare machine (bench/README.md).
//
//   vkmesh_gpubench [--voxel 0.03,0.01] [--frames 60] [--repeat 1] [--warmup 10] [--device I] [--json FILE]
//                   [--publish] [--track [--track-solve host|gpu]] [--correct] [--resident-blocks N] [--quick] [--devices]
//
// Prints a table per voxel size (median and p90 GPU ms per stage, the frame's GPU and wall time, the meshing
// total) and writes the same as JSON. Exit codes: 0 done; 1 validation messages (VKMESH_VALIDATION=1);
// 2 an error named in the message (no Vulkan driver or device, a voxel size out of range); 3 an internal error;
// a malformed command line: CLI11's own non-zero code.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <dlfcn.h>
#include <gnu/libc-version.h>
#include <vulkan/vulkan.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Geometry>

#include "api/mapper.h"
#include "core/types.h"
#include "gpu/gpu_volume.h"
#include "gpu/tracking/pose_tracker.h"
#include "synth/synthetic_scene.h"
#include "vk/context.h"

namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;
using vkmesh::ColorImage;
using vkmesh::DepthImage;
using vkmesh::Error;
using vkmesh::Intrinsics;
using vkmesh::Pose;

// `vkmesh synth`'s defaults (host/synth_command.cpp) and what `vkmesh fuse` reads of them: TUM depth units
// (src/synth/tum_sequence.cpp), the default --max-depth (host/cli_options.h).
constexpr int kWidth = 640, kHeight = 480;
constexpr size_t kSynthFrames = 60;
constexpr double kDepthUnitsPerMetre = 5000.0;
constexpr float kMaxDepth = 4.0f;
// The goals of issue 14 on an H100/H200-class GPU, at 3 cm.
constexpr double kGoalFrameMs = 1.0, kGoalMeshMs = 0.3;

struct Options {
    std::vector<double> voxels{0.03, 0.01};   // double: the JSON then says 0.03, not 0.029999999
    size_t frames = kSynthFrames;
    size_t loopFrames = kSynthFrames;
    size_t repeat = 1;
    size_t warmup = 10;
    int device = -1;
    bool validation = false;
    bool publish = false;
    bool track = false;        // every frame after a run's first tracked against the mesh (docs/TRACKING.md)
    // where tracking solves its 6x6 systems: host (a wait per iteration), gpu, or both (each voxel size run in
    // both modes, side by side: on a GPU this says which should be the default there)
    std::string trackSolve = "both";
    bool correct = false;      // after each run, every frame re-fused at a moved pose (docs/CORRECTION.md)
    bool quick = false;
    bool passTimes = false;    // a timestamp after every pass as well
    bool allocTiles = vkmesh::VolumeParams{}.allocationTiles;   // allocation by tiles (VolumeParams::allocationTiles)
    bool allocPixels = false;                                    // --alloc-pixels: allocTiles off
    uint32_t residentBlocks = 0;   // paging (docs/PAGING.md): at most this many blocks in GPU memory; 0: all
    std::string jsonPath;
};

struct Frame {
    DepthImage depth;
    ColorImage color;
    Pose pose;
};

// What the dataset reader hands `vkmesh fuse` for a depth image the TUM writer stored: rounded to the 16-bit
// sensor unit (0 beyond what 16 bits hold), depth beyond kMaxDepth dropped: bit for bit the depth fuse reads
// (its poses differ from these only by groundtruth.txt's 9 decimals).
void quantiseAsStored(DepthImage& depth) {
    for (float& d : depth.meters) {
        const double units = std::round(double(d) * kDepthUnitsPerMetre);
        float m = units > 0 && units <= 65535.0 ? float(units / kDepthUnitsPerMetre) : 0.0f;
        if (m > kMaxDepth) m = 0.0f;
        d = m;
    }
}

// Renders the first `count` poses of the `loopFrames`-pose orbit. Each renderDepth call uses two threads, so
// several frames are rendered at once on a machine with more cores (a datacenter host: seconds, not minutes).
std::vector<Frame> renderFrames(size_t count, size_t loopFrames) {
    const vkmesh::synth::SyntheticScene scene = vkmesh::synth::SyntheticScene::defaultRoom();
    const Intrinsics intrinsics = vkmesh::synth::kinectIntrinsics(kWidth, kHeight);
    const std::vector<Pose> poses = vkmesh::synth::cameraPath(loopFrames, vkmesh::synth::PathKind::Orbit);
    std::vector<Frame> frames(count);
    std::atomic<size_t> next{0};
    std::exception_ptr failure;
    std::mutex failureMutex;
    auto work = [&] {
        try {
            for (size_t i = next++; i < count; i = next++) {
                vkmesh::synth::RenderOptions options;   // as writeTumSequence: range 8 m, no noise, gain 1
                options.seed = vkmesh::synth::frameSeed(1, i);
                frames[i].pose = poses[i];
                frames[i].depth = scene.renderDepth(intrinsics, poses[i], options, &frames[i].color);
                quantiseAsStored(frames[i].depth);
            }
        } catch (...) {
            std::lock_guard<std::mutex> lock(failureMutex);
            if (!failure) failure = std::current_exception();
            next = count;
        }
    };
    const size_t workers = std::clamp<size_t>(std::thread::hardware_concurrency() / 2, 1, count);
    std::vector<std::thread> threads;
    for (size_t w = 1; w < workers; ++w) threads.emplace_back(work);
    work();
    for (std::thread& t : threads) t.join();
    if (failure) std::rethrow_exception(failure);
    return frames;
}

std::string cm(double voxel) {
    char text[32];
    std::snprintf(text, sizeof text, "%g cm", voxel * 100.0);
    return text;
}

struct Summary {
    double median = 0, p90 = 0, mean = 0, max = 0;
    size_t count = 0;
};

Summary summarize(std::vector<double> values) {
    Summary s;
    s.count = values.size();
    if (values.empty()) return s;
    std::sort(values.begin(), values.end());
    const size_t n = values.size();
    s.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
    // Nearest rank: the smallest value that at least 90 % of the frames do not exceed.
    s.p90 = values[size_t(std::ceil(0.9 * double(n))) - 1];
    s.mean = std::accumulate(values.begin(), values.end(), 0.0) / double(n);
    s.max = values.back();
    return s;
}

json toJson(const Summary& s) {
    if (s.count == 0) return json{{"median", nullptr}, {"p90", nullptr}, {"mean", nullptr}, {"max", nullptr}, {"frames", 0}};
    return json{{"median", s.median}, {"p90", s.p90}, {"mean", s.mean}, {"max", s.max}, {"frames", s.count}};
}

// One voxel size: every repeat fuses the sequence into a fresh volume; the frames of all repeats are pooled.
struct VoxelRun {
    double voxel = 0;
    size_t frames = 0;                             // fused, all repeats together
    std::vector<std::string> stageOrder;           // the pipeline's order, as the timestamps came
    std::map<std::string, std::vector<double>> stageMs;
    std::vector<double> gpuFrameMs, meshMs, wallMs;
    std::vector<double> dispatches;                // compute dispatches (passes) each frame recorded
    // --pass-times: each pass's GPU ms per frame (a pass recorded twice in a frame: the sum), by shader name
    std::vector<std::string> passOrder;
    std::map<std::string, std::vector<double>> passMs;
    vkmesh::gpu::Counters last{};                  // counters after the last frame of the last repeat
    size_t growths = 0, deferredAttempts = 0, warnings = 0;
    size_t gpuBytes = 0;
    double seconds = 0;
    // --track: per tracked frame, the tracker's GPU and wall time, host round trips and the position error
    // against the rendered pose; frames lost.
    std::vector<double> trackGpuMs, trackWallMs, trackSubmissions, trackErrorMm;
    std::vector<std::string> trackStageOrder;                 // the tracker's stages (pyramid, model maps, ICP)
    std::map<std::string, std::vector<double>> trackStageMs;  //  ... their GPU ms per tracked frame
    size_t modelDraws = 0;                                    // tracked frames that drew the mesh (not reused maps)
    std::string trackSolve;       // "host" or "gpu" (--track)
    bool oneSubmission = false;   // --track-solve gpu: tracked frames fused in tracking's submission
    size_t lostFrames = 0;
    // --correct: per re-fused frame, the de-integration's and the re-integration's GPU and wall time (each an
    // intermediate frame: no export, no deltas) and the observations that could not be taken out (must be 0).
    std::vector<double> deintegrateGpuMs, deintegrateWallMs, reintegrateGpuMs, reintegrateWallMs, refuseWallMs;
    size_t observationsDropped = 0;
    // --resident-blocks: per fused frame, the paging's host ms (copies and submissions included) and blocks moved.
    std::vector<double> pagingMs, blocksPagedIn, blocksPagedOut;
};

vkmesh::gpu::GpuVolumeConfig volumeConfig(double voxel, bool publish, bool passTimes, bool allocTiles, uint32_t residentBlocks) {
    // The library's defaults are `vkmesh fuse`'s (host/cli_options.h takes them from GpuVolumeConfig); colour
    // fusion defaults to the running average, which fuse keeps for input with colour.
    vkmesh::gpu::GpuVolumeConfig config;
    config.params.voxelSize = float(voxel);
    config.params.maxDepth = kMaxDepth;
    config.imageWidth = kWidth;
    config.imageHeight = kHeight;
    config.publishMesh = publish;
    config.timePasses = passTimes;
    config.params.allocationTiles = allocTiles;
    config.residentBlocks = residentBlocks;
    return config;
}

// Fuses frames 0..count-1 of the loop (frame i is rendered[i % rendered.size()]) into a fresh volume: gpubench drives
// the library's frame loop, vkmesh::Mapper (api/mapper.h), as `vkmesh fuse` does, and records what each frame's
// MapperResult reports. `run` is null for the untimed warm-up.
// Without `track` every frame is given its true pose. With `track`, the first frame is fused at its true pose (the
// run's start pose) and every later one is tracked against the mesh and fused at the tracked pose (lost frames are
// not fused), as `vkmesh fuse --track` does; the true pose is each frame's reference.
// With `correct`, after the sequence every fused frame is re-fused as Reconstructor::correct does it: taken out at
// the pose it was fused at and fused again at that pose moved by 1 cm and 0.5 degrees.
void fuseSequence(const vkmesh::vk::Context& context, const std::vector<Frame>& rendered, size_t count, double voxel,
                  bool publish, bool track, bool trackSolveOnGpu, bool correct, bool passTimes, bool allocTiles, uint32_t residentBlocks,
                  VoxelRun* run) {
    vkmesh::MapperOptions options;
    options.volume = volumeConfig(voxel, publish, passTimes, allocTiles, residentBlocks);   // tracking draws the volume's own mesh
    options.tracker.maxDepth = kMaxDepth;
    options.tracker.solveOnGpu = trackSolveOnGpu;
    vkmesh::Mapper mapper(context, std::move(options));
    const Intrinsics intrinsics = vkmesh::synth::kinectIntrinsics(kWidth, kHeight);
    std::vector<std::pair<size_t, Pose>> fusedAt;   // --correct: each frame fused and its pose
    for (size_t i = 0; i < count; ++i) {
        const Frame& frame = rendered[i % rendered.size()];
        vkmesh::MapperFrame input;
        input.index = uint32_t(i);
        input.depth = &frame.depth;
        input.color = &frame.color;
        input.intrinsics = intrinsics;
        input.source = "synthetic frame " + std::to_string(i);
        if (!track) {
            input.pose = frame.pose;
        } else {
            if (i == 0) input.startPose = frame.pose;   // later frames: no pose, tracked
            input.reference = frame.pose;
        }
        // Tracked frames: tracked, then fused at the tracked pose (--track-solve gpu: both in one submission, and
        // the wall times below are each the whole frame's).
        const vkmesh::MapperResult result = mapper.process(input);
        // A tracked run's first frame reports the tracker's start (TrackingReport::first): nothing was tracked.
        if (result.tracking && !result.tracking->first && run) {
            const vkmesh::gpu::TrackingReport& tr = *result.tracking;
            run->trackGpuMs.push_back(tr.gpuMilliseconds);
            run->trackWallMs.push_back(tr.milliseconds);
            run->trackSubmissions.push_back(tr.submissions);
            run->trackErrorMm.push_back(1e3 * (tr.cameraToWorld.block<3, 1>(0, 3) - frame.pose.block<3, 1>(0, 3)).norm());
            for (const auto& [name, ms] : tr.gpuStageMilliseconds) {
                if (!run->trackStageMs.count(name)) run->trackStageOrder.push_back(name);
                run->trackStageMs[name].push_back(ms);
            }
            run->modelDraws += tr.modelDrawn;
            run->lostFrames += result.status == vkmesh::FrameStatus::Lost;
            run->oneSubmission = result.oneSubmission;
        }
        if (result.status == vkmesh::FrameStatus::Skipped)
            for (const std::string& w : result.warnings) std::cerr << "warning: " << cm(voxel) << ", " << w << "\n";
        if (!result.isFused()) continue;   // lost by tracking (or skipped): not fused
        // The stage times are those of the frame's last submission: a frame run again after growing a capacity is
        // timed on its second attempt, and mesh completion passes after a heap growth are not timed; the wall
        // time holds all of it, and the depth/colour upload before the first stage too.
        const vkmesh::gpu::FrameReport& report = *result.fused;
        const double wallMs = result.fuseWallMs;
        for (const std::string& w : report.warnings) std::cerr << "warning: " << cm(voxel) << ", frame " << i << ": " << w << "\n";
        for (const std::string& g : report.growth) std::cerr << "note: " << cm(voxel) << ", frame " << i << ": grew " << g << "\n";
        if (!run) continue;
        double total = 0, mesh = 0;
        for (const auto& [name, ms] : report.stageMs) {
            if (!run->stageMs.count(name)) run->stageOrder.push_back(name);
            run->stageMs[name].push_back(ms);
            total += ms;
            if (name.rfind("mesh_", 0) == 0) mesh += ms;   // as fuse's --stats "mesh_total"
        }
        if (!report.stageMs.empty()) {
            run->gpuFrameMs.push_back(total);
            run->meshMs.push_back(mesh);
        }
        run->wallMs.push_back(wallMs);
        run->dispatches.push_back(report.dispatches);
        if (residentBlocks > 0) {
            run->pagingMs.push_back(report.paging.milliseconds);
            run->blocksPagedIn.push_back(report.paging.blocksIn);
            run->blocksPagedOut.push_back(report.paging.blocksOut);
        }
        std::map<std::string, double> framePassMs;
        for (const auto& [name, ms] : report.passMs) {
            if (!run->passMs.count(name) && !framePassMs.count(name)) run->passOrder.push_back(name);
            framePassMs[name] += ms;
        }
        for (const auto& [name, ms] : framePassMs) run->passMs[name].push_back(ms);
        if (correct) fusedAt.emplace_back(i, result.cameraToWorld);
        run->last = report.counters;
        run->growths += report.growth.size();
        run->deferredAttempts += report.deferredAttempts;
        run->warnings += report.warnings.size();
        ++run->frames;
    }
    if (!mapper.hasVolume()) return;
    vkmesh::gpu::GpuVolume& volume = mapper.volume();
    // --correct goes to the Mapper's volume itself, not through Mapper::correct / finishCorrections: their report
    // (CorrectionReport) has one wall time for the whole batch re-fused, where this times each frame's take-out and
    // re-fuse apart, on the GPU and in wall time; and they need the fused frames kept (keepFrames: a frame store
    // that compresses every frame as it is fused, host work the runs without --correct would not do). It submits
    // what MapCorrector::apply does: the frame de-integrated at its pose, then integrated at the new one, each an
    // intermediate frame.
    if (run && correct) {
        Pose moved = Pose::Identity();
        moved.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.5 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
        moved.topRightCorner<3, 1>() = Eigen::Vector3d(0.01, 0.0, 0.0);
        auto gpuMs = [](const vkmesh::gpu::FrameReport& r) {
            double total = 0;
            for (const auto& [name, ms] : r.stageMs) total += ms;
            return total;
        };
        for (const auto& [i, pose] : fusedAt) {
            const Frame& frame = rendered[i % rendered.size()];
            vkmesh::gpu::FrameInput input = vkmesh::gpu::FrameInput::fromHost(frame.depth, &frame.color, intrinsics, pose);
            input.intermediate = true;
            double wall[2] = {0, 0};
            for (bool out : {true, false}) {
                input.deintegrate = out;
                input.cameraToWorld = out ? pose : Pose(moved * pose);
                const auto t0 = Clock::now();
                volume.submitFrame(input);
                const vkmesh::gpu::FrameReport r = volume.finishFrame();
                wall[out ? 0 : 1] = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
                (out ? run->deintegrateGpuMs : run->reintegrateGpuMs).push_back(gpuMs(r));
                run->observationsDropped += r.counters.observationsDropped;
            }
            run->deintegrateWallMs.push_back(wall[0]);
            run->reintegrateWallMs.push_back(wall[1]);
            run->refuseWallMs.push_back(wall[0] + wall[1]);
        }
    }
    if (run) {
        run->gpuBytes = 0;
        for (const auto& pool : volume.pools()) run->gpuBytes += pool.bytes;
    }
}

// What the driver says about itself: the name and version the NVIDIA numbers in docs/RESULTS.md are filed under.
struct DriverDescription {
    std::string deviceName, deviceType, apiVersion, driverName, driverInfo, driverVersion, loaderVersion, loaderPath;
    uint32_t vendorId = 0, deviceId = 0;
};

std::string versionString(uint32_t v) {
    return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
           std::to_string(VK_API_VERSION_PATCH(v));
}

// VkPhysicalDeviceProperties::driverVersion is vendor-encoded: NVIDIA packs 10.8.8.6 bits (580.159.03);
// Mesa and most others use the Vulkan version layout.
std::string driverVersionString(uint32_t vendorId, uint32_t v) {
    char text[64];
    if (vendorId == 0x10DE) {
        std::snprintf(text, sizeof text, "%u.%u.%02u", (v >> 22) & 0x3FF, (v >> 14) & 0xFF, (v >> 6) & 0xFF);
        if (v & 0x3F) std::snprintf(text + std::strlen(text), sizeof text - std::strlen(text), ".%u", v & 0x3F);
        return text;
    }
    return versionString(v);
}

DriverDescription describeDriver(const vkmesh::vk::Context& context) {
    VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
    VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    props.pNext = &driver;   // Vulkan 1.2, which vk::Context requires of every device it opens
    vkGetPhysicalDeviceProperties2(context.physicalDevice(), &props);
    const VkPhysicalDeviceProperties& p = props.properties;
    DriverDescription d;
    d.deviceName = p.deviceName;
    d.deviceType = context.info().type;
    d.apiVersion = versionString(p.apiVersion);
    d.driverName = driver.driverName;
    d.driverInfo = driver.driverInfo;
    d.driverVersion = driverVersionString(p.vendorID, p.driverVersion);
    d.vendorId = p.vendorID;
    d.deviceId = p.deviceID;
    uint32_t loader = VK_API_VERSION_1_0;
    if (vkEnumerateInstanceVersion(&loader) == VK_SUCCESS) d.loaderVersion = versionString(loader);
    // The file the loader was loaded from: a pack's run.sh must have put its own libvulkan.so.1 first.
    Dl_info where{};
    if (void* symbol = dlsym(RTLD_DEFAULT, "vkGetInstanceProcAddr"); symbol && dladdr(symbol, &where) && where.dli_fname)
        d.loaderPath = where.dli_fname;
    return d;
}

void printRun(const VoxelRun& r, size_t repeat) {
    std::printf("\nvoxel %s%s: %zu frames in %zu run(s), %.1f s; at the end %u blocks, %u vertices, %u triangles, %.0f MiB on "
                "the GPU\n",
                cm(r.voxel).c_str(), r.trackSolve.empty() ? "" : (", tracked, systems solved on the " + r.trackSolve).c_str(),
                r.frames, repeat, r.seconds, r.last.blocksInUse, r.last.verticesInUse,
                r.last.liveTriangles, double(r.gpuBytes) / (1 << 20));
    if (r.growths || r.deferredAttempts || r.warnings)
        std::printf("  capacity growths %zu, frames run again after growing %zu, warnings %zu\n", r.growths,
                    r.deferredAttempts, r.warnings);
    std::printf("  %-24s %10s %10s %10s %7s\n", "stage (GPU ms)", "median", "p90", "max", "frames");
    auto row = [](const std::string& name, const Summary& s) {
        std::printf("  %-24s %10.3f %10.3f %10.3f %7zu\n", name.c_str(), s.median, s.p90, s.max, s.count);
    };
    for (const std::string& name : r.stageOrder) row(name, summarize(r.stageMs.at(name)));
    if (r.gpuFrameMs.empty()) {
        std::printf("  (the device writes no timestamps: wall times only)\n");
    } else {
        row("meshing total (mesh_*)", summarize(r.meshMs));
        row("whole frame, GPU", summarize(r.gpuFrameMs));
    }
    row("whole frame, wall", summarize(r.wallMs));
    // What a pass costs whatever its work: compare the GPU's whole frame with this count.
    const Summary passes = summarize(r.dispatches);
    std::printf("  %-24s %10.0f %10.0f %10.0f %7zu\n", "passes (dispatches)", passes.median, passes.p90, passes.max, passes.count);
    if (!r.passOrder.empty()) {
        // --pass-times: where each stage's time goes, pass by pass (each from the timestamp before it).
        std::printf("  %-24s %10s %10s %10s %7s\n", "pass (GPU ms)", "median", "p90", "max", "frames");
        for (const std::string& name : r.passOrder) row(name, summarize(r.passMs.at(name)));
    }
    if (!r.trackWallMs.empty()) {
        for (const std::string& name : r.trackStageOrder) row("tracking: " + name, summarize(r.trackStageMs.at(name)));
        row("tracking, GPU", summarize(r.trackGpuMs));
        row("tracking, wall", summarize(r.trackWallMs));
        row("tracking, round trips", summarize(r.trackSubmissions));
        row("tracking, error (mm)", summarize(r.trackErrorMm));
        std::printf("  frames lost by tracking: %zu; frames that drew the mesh: %zu of %zu (the others reused the model maps)\n",
                    r.lostFrames, r.modelDraws, r.trackWallMs.size());
        if (r.oneSubmission)
            std::printf("  (--track-solve gpu: tracking, fusion and meshing are one submission; both wall rows are the whole frame's)\n");
    }
    if (!r.refuseWallMs.empty()) {
        row("correct: take out, GPU", summarize(r.deintegrateGpuMs));
        row("correct: refuse, GPU", summarize(r.reintegrateGpuMs));
        row("correct: take out, wall", summarize(r.deintegrateWallMs));
        row("correct: refuse, wall", summarize(r.reintegrateWallMs));
        row("correct: both, wall", summarize(r.refuseWallMs));
        const double frame = summarize(r.wallMs).median;
        std::printf("  re-fusing a frame costs %.2fx fusing one (wall medians); observations not taken out: %zu (must be 0)\n",
                    frame > 0 ? summarize(r.refuseWallMs).median / frame : 0.0, r.observationsDropped);
    }
    if (!r.pagingMs.empty()) {
        row("paging (host, wall)", summarize(r.pagingMs));
        row("blocks paged in", summarize(r.blocksPagedIn));
        row("blocks paged out", summarize(r.blocksPagedOut));
    }
}

json runJson(const VoxelRun& r) {
    json stages = json::object();
    for (const std::string& name : r.stageOrder) stages[name] = toJson(summarize(r.stageMs.at(name)));
    json trackStages = json::object();
    for (const std::string& name : r.trackStageOrder) trackStages[name] = toJson(summarize(r.trackStageMs.at(name)));
    if (!r.meshMs.empty()) stages["mesh_total"] = toJson(summarize(r.meshMs));   // fuse's --stats name
    json passes = json::object();
    for (const std::string& name : r.passOrder) passes[name] = toJson(summarize(r.passMs.at(name)));
    return json{{"voxel_size", r.voxel},
                {"frames", r.frames},
                {"stage_order", r.stageOrder},
                {"gpu_ms_per_frame", stages},
                {"gpu_ms_frame_total", toJson(summarize(r.gpuFrameMs))},
                {"wall_ms_per_frame", toJson(summarize(r.wallMs))},
                {"dispatches_per_frame", toJson(summarize(r.dispatches))},
                {"pass_order", r.passOrder},
                {"gpu_ms_per_pass", passes},   // empty without --pass-times
                {"blocks_in_use", r.last.blocksInUse},
                {"vertices_in_use", r.last.verticesInUse},
                {"live_triangles", r.last.liveTriangles},
                {"gpu_bytes_total", r.gpuBytes},
                {"capacity_growths", r.growths},
                {"deferred_attempts", r.deferredAttempts},
                {"warnings", r.warnings},
                {"wall_s", r.seconds},
                {"tracking", r.trackWallMs.empty() ? json(nullptr)
                                                   : json{{"gpu_ms_per_frame", toJson(summarize(r.trackGpuMs))},
                                                          {"wall_ms_per_frame", toJson(summarize(r.trackWallMs))},
                                                          {"submissions_per_frame", toJson(summarize(r.trackSubmissions))},
                                                          {"position_error_mm", toJson(summarize(r.trackErrorMm))},
                                                          {"lost_frames", r.lostFrames},
                                                          {"solve", r.trackSolve},
                                                          {"gpu_ms_stages", trackStages},
                                                          {"model_draws", r.modelDraws},
                                                          // tracking, fusion and meshing in one submission:
                                                          // both wall times are the whole frame's
                                                          {"fused_in_tracking_submission", r.oneSubmission}}},
                {"paging", r.pagingMs.empty() ? json(nullptr)
                                              : json{{"ms", toJson(summarize(r.pagingMs))},
                                                     {"blocks_in", toJson(summarize(r.blocksPagedIn))},
                                                     {"blocks_out", toJson(summarize(r.blocksPagedOut))}}},
                {"correction", r.refuseWallMs.empty() ? json(nullptr)
                                                      : json{{"deintegrate_gpu_ms", toJson(summarize(r.deintegrateGpuMs))},
                                                             {"reintegrate_gpu_ms", toJson(summarize(r.reintegrateGpuMs))},
                                                             {"deintegrate_wall_ms", toJson(summarize(r.deintegrateWallMs))},
                                                             {"reintegrate_wall_ms", toJson(summarize(r.reintegrateWallMs))},
                                                             {"refuse_wall_ms", toJson(summarize(r.refuseWallMs))},
                                                             {"observations_dropped", r.observationsDropped}}}};
}

std::string utcNow() {
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return text;
}

int run(Options o, const CLI::App& cli) {
    auto given = [&](const char* option) { return cli.get_option(option)->count() > 0; };
    if (o.quick) {   // lavapipe: a smoke run that still goes through every stage at both sizes
        if (!given("--frames")) o.frames = 3;
        if (!given("--warmup")) o.warmup = 0;
    }
    // Tracking follows a camera that moves a few centimetres per frame, as a sensor at 30 Hz does; the 60-pose
    // orbit steps 14 cm and 6 degrees.
    if (o.track && !given("--loop-frames")) o.loopFrames = 240;
    for (double v : o.voxels)
        if (!(v >= 0.004 && v <= 0.5)) throw Error("--voxel " + std::to_string(v) + " m: give sizes between 0.004 and 0.5");
    const size_t renderCount = std::min(std::max(o.frames, o.warmup), o.loopFrames);
    o.warmup = std::min(o.warmup, renderCount);

    const auto start = Clock::now();
    // The device first: without one there is nothing to render for.
    vkmesh::vk::Context context(vkmesh::vk::ContextOptions{o.device, o.validation});
    const DriverDescription d = describeDriver(context);
    std::printf("vkmesh_gpubench: %s (%s), Vulkan %s, driver %s %s (version %s), loader %s%s\n", d.deviceName.c_str(),
                d.deviceType.c_str(), d.apiVersion.c_str(), d.driverName.c_str(), d.driverInfo.c_str(),
                d.driverVersion.c_str(), d.loaderVersion.c_str(), context.validationEnabled() ? ", validation on" : "");
    std::printf("  Vulkan loader: %s; glibc %s\n", d.loaderPath.empty() ? "(not found by dladdr)" : d.loaderPath.c_str(),
                gnu_get_libc_version());
    for (const char* var : {"VK_DRIVER_FILES", "VK_ICD_FILENAMES"})
        if (const char* value = std::getenv(var)) std::printf("  %s=%s\n", var, value);
    if (!context.timestampsSupported()) std::printf("  the compute queue writes no timestamps: no per-stage GPU times\n");

    const auto renderStart = Clock::now();
    std::fprintf(stderr, "rendering %zu frames of the synthetic room (%dx%d)...\n", renderCount, kWidth, kHeight);
    const std::vector<Frame> rendered = renderFrames(renderCount, o.loopFrames);
    const double renderSeconds = std::chrono::duration<double>(Clock::now() - renderStart).count();
    std::printf("scene: synthetic room, orbit of %zu poses (vkmesh synth's default), %dx%d with colour, max depth %g m; "
                "%zu frames per run, %zu run(s) per voxel size; rendered in %.1f s\n",
                o.loopFrames, kWidth, kHeight, double(kMaxDepth), o.frames, o.repeat, renderSeconds);
    std::printf("pipeline: incremental mesh every frame, colour fusion on%s\n",
                o.publish ? ", mesh compacted into draw buffers every frame (--publish)" : "");

    if (o.warmup > 0) {   // raises the GPU's clocks and fills the driver's caches before anything is timed
        std::fprintf(stderr, "warm-up: %zu untimed frames at %s\n", o.warmup, cm(o.voxels.front()).c_str());
        fuseSequence(context, rendered, o.warmup, o.voxels.front(), o.publish, o.track, o.trackSolve == "gpu", false, o.passTimes, o.allocTiles, o.residentBlocks, nullptr);
        if (o.track && o.trackSolve == "both")   // the other mode's pipelines and caches too
            fuseSequence(context, rendered, std::min<size_t>(o.warmup, 10), o.voxels.front(), o.publish, true, true, false, o.passTimes, o.allocTiles, o.residentBlocks, nullptr);
    }
    std::vector<VoxelRun> runs;
    // Written after every voxel size, so that a run stopped part way (run.sh's --timeout) leaves what it measured.
    auto writeJson = [&](bool complete) {
        json runsJson = json::array();
        for (const VoxelRun& r : runs) runsJson.push_back(runJson(r));
        json device = {{"name", d.deviceName},        {"type", d.deviceType},         {"vendor_id", d.vendorId},
                       {"device_id", d.deviceId},      {"api_version", d.apiVersion},  {"driver_name", d.driverName},
                       {"driver_info", d.driverInfo},  {"driver_version", d.driverVersion},
                       {"loader_version", d.loaderVersion}, {"loader_path", d.loaderPath},
                       {"glibc", gnu_get_libc_version()}, {"int64_atomics", context.int64Atomics()},
                       {"timestamps", context.timestampsSupported()}};
        json icd = json::object();
        for (const char* var : {"VK_DRIVER_FILES", "VK_ICD_FILENAMES"})
            if (const char* value = std::getenv(var)) icd[var] = value;
        json out = {{"tool", "vkmesh_gpubench"},
                    {"date", utcNow()},
                    {"complete", complete},
                    {"device", device},
                    {"icd_env", icd},
                    {"host_cpus", std::thread::hardware_concurrency()},
                    {"scene", {{"name", "synthetic room (vkmesh synth defaults)"}, {"path", "orbit"},
                               {"loop_frames", o.loopFrames}, {"width", kWidth}, {"height", kHeight},
                               {"max_depth", kMaxDepth}, {"color", true}, {"render_s", renderSeconds}}},
                    {"pipeline", {{"mode", "incremental"}, {"color_fusion", "average"}, {"publish_mesh", o.publish}, {"track", o.track}, {"track_solve", o.trackSolve}, {"correct", o.correct}, {"pass_times", o.passTimes}, {"alloc_tiles", o.allocTiles}, {"resident_blocks", o.residentBlocks}}},
                    {"frames_per_run", o.frames},
                    {"repeat", o.repeat},
                    {"warmup_frames", o.warmup},
                    {"quick", o.quick},
                    {"goals_ms", {{"voxel_size", 0.03}, {"frame", kGoalFrameMs}, {"mesh", kGoalMeshMs}}},
                    {"runs", runsJson},
                    {"validation", context.validationEnabled()},
                    {"validation_messages", context.validationEnabled() ? context.validationMessageCount() : 0},
                    {"wall_s_total", std::chrono::duration<double>(Clock::now() - start).count()}};
        std::ofstream file(o.jsonPath, std::ios::trunc);
        file << out.dump(2) << "\n";
        file.close();
        if (!file) throw Error("cannot write " + o.jsonPath);
    };
    // With --track, one run per solve mode asked for (both by default), each voxel size in each mode.
    std::vector<std::string> solveModes = {""};
    if (o.track) solveModes = o.trackSolve == "both" ? std::vector<std::string>{"host", "gpu"} : std::vector<std::string>{o.trackSolve};
    for (double voxel : o.voxels) {
        for (const std::string& solve : solveModes) {
            VoxelRun r;
            r.voxel = voxel;
            r.trackSolve = solve;
            const auto t0 = Clock::now();
            for (size_t rep = 0; rep < o.repeat; ++rep) {
                std::fprintf(stderr, "fusing %zu frames at %s%s (%zu/%zu)...\n", o.frames, cm(voxel).c_str(),
                             solve.empty() ? "" : (", tracking solved on the " + solve).c_str(), rep + 1, o.repeat);
                fuseSequence(context, rendered, o.frames, voxel, o.publish, o.track, solve == "gpu", o.correct, o.passTimes, o.allocTiles, o.residentBlocks, &r);
            }
            r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
            printRun(r, o.repeat);
            runs.push_back(std::move(r));
            if (!o.jsonPath.empty()) writeJson(false);
        }
    }

    // The goals of issue 14 are for an H100/H200-class GPU; on any other device this is only a comparison.
    for (const VoxelRun& r : runs) {
        if (std::abs(r.voxel - 0.03) > 1e-9 || r.gpuFrameMs.empty()) continue;
        const double frame = summarize(r.gpuFrameMs).median, mesh = summarize(r.meshMs).median;
        std::printf("\ngoal at 3 cm (H100/H200 class): whole frame %.3f ms (<= %.1f: %s), meshing %.3f ms (<= %.1f: %s)\n",
                    frame, kGoalFrameMs, frame <= kGoalFrameMs ? "met" : "not met", mesh, kGoalMeshMs,
                    mesh <= kGoalMeshMs ? "met" : "not met");
    }
    const size_t validationMessages = context.validationEnabled() ? context.validationMessageCount() : 0;
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    std::printf("total %.1f s\n", seconds);

    if (!o.jsonPath.empty()) {
        writeJson(true);
        std::printf("wrote %s\n", o.jsonPath.c_str());
    }
    if (validationMessages > 0) {
        std::fprintf(stderr, "vkmesh_gpubench: %zu validation messages (above)\n", validationMessages);
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App cli{"vkmesh_gpubench: per-stage GPU times of vkmesh's frame pipeline on the synthetic room "
                 "(rendered in memory; needs only a Vulkan driver)"};
    Options o;
    cli.add_option("--voxel", o.voxels, "voxel sizes in metres, comma-separated")->delimiter(',')->expected(1, 16)->type_name("M[,M...]");
    cli.add_option("--frames", o.frames, "frames fused per run (past the loop's length the camera drives it again)")
        ->check(CLI::Range(size_t(1), size_t(100000)));
    cli.add_option("--loop-frames", o.loopFrames, "poses of the camera's orbit (vkmesh synth --frames)")
        ->check(CLI::Range(size_t(1), size_t(2000)));
    cli.add_option("--repeat", o.repeat, "runs per voxel size, each into a fresh volume; their frames are pooled")
        ->check(CLI::Range(size_t(1), size_t(100)));
    cli.add_option("--warmup", o.warmup, "untimed frames fused first, at the first voxel size (GPU clocks, caches)");
    cli.add_option("--device", o.device, "Vulkan device index (--devices lists them; default: a discrete GPU if any)");
    bool listDevices = false;
    cli.add_flag("--devices", listDevices, "list the Vulkan devices and whether vkmesh can use them, then exit");
    cli.add_flag("--validation", o.validation, "Khronos validation layer on (or VKMESH_VALIDATION=1); any message: exit 1");
    cli.add_flag("--publish", o.publish, "also compact the mesh into draw-ready buffers every frame (an embedding renderer's cost)");
    cli.add_flag("--track", o.track,
                 "track the camera: every frame after a run's first is aligned to the mesh (ICP against the mesh drawn at "
                 "the predicted pose) and fused at the tracked pose; reports the tracker's GPU time and its error "
                 "(with it, the orbit has 240 poses unless --loop-frames says)");
    cli.add_option("--track-solve", o.trackSolve,
                   "with --track: where the ICP systems are solved: host (double, one submission per iteration), gpu (float, "
                   "the frame's tracking in one submission), or both (default: every voxel size run in each mode)")
        ->check(CLI::IsMember({"host", "gpu", "both"}));
    cli.add_flag("--correct", o.correct,
                 "after each run, re-fuse every frame as a pose correction does (de-integrated at its pose, fused again 1 cm "
                 "and 0.5 degrees away; docs/CORRECTION.md) and report the cost against fusing a frame");
    cli.add_option("--resident-blocks", o.residentBlocks,
                   "paging (vkmesh fuse --resident-blocks, docs/PAGING.md): at most N blocks in GPU memory, the others on the "
                   "host; reports the paging's cost per frame (0: every block stays, the default)");
    cli.add_option("--json", o.jsonPath, "write the results as JSON to this file");
    cli.add_flag("--alloc-tiles", o.allocTiles,
                 "allocation by tiles (the default, vkmesh fuse --alloc-tiles): a plane's slab per tile of 8 x 8 sampled pixels "
                 "where one fits, the other pixels' band walks");
    cli.add_flag("--alloc-pixels", o.allocPixels,
                 "allocation pixel by pixel (vkmesh fuse --alloc-pixels): every sampled pixel walks its band (on lavapipe "
                 "up to ~10 % slower a frame than tiles: what does a GPU say?)")
        ->excludes("--alloc-tiles");
    cli.add_flag("--pass-times", o.passTimes,
                 "also a GPU timestamp after every pass (compute dispatch): the GPU ms of each pass by shader name, printed "
                 "after the stages and in the JSON (gpu_ms_per_pass)");
    cli.add_flag("--quick", o.quick, "smoke run for a CPU device (lavapipe): 3 frames per voxel size, no warm-up, "
                                     "unless --frames / --warmup say otherwise");
    CLI11_PARSE(cli, argc, argv);
    if (o.allocPixels) o.allocTiles = false;
    // Line by line, so that the table and the progress on stderr stay in order in run.sh's gpubench.txt.
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    try {
        if (listDevices) {
            const auto devices = vkmesh::vk::Context::listDevices();
            if (devices.empty()) throw Error("No Vulkan device found (the loader found no driver, or the driver no device)");
            for (const auto& d : devices)
                std::printf("%u: %s (%s, Vulkan %s, %s)%s\n", d.index, d.name.c_str(), d.type.c_str(), d.apiVersion.c_str(),
                            d.driver.c_str(), d.suitable ? "" : ("  NOT USABLE: " + d.whyNot).c_str());
            return 0;
        }
        return run(o, cli);
    } catch (const Error& e) {
        std::cerr << "vkmesh_gpubench: error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "vkmesh_gpubench: internal error: " << e.what() << "\n";
        return 3;
    }
}
