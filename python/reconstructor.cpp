// vkmesh.Reconstructor: its settings checked into ReconstructorOptions (makeReconstructor, loadReconstructor) and the
// py::class_ over PyReconstructor (bindReconstructor); the overhead benchmark's _CppFrame (bindBenchmark).
#include "bindings.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "api/reconstructor.h"
#include "api/settings.h"
#include "arrays.h"
#include "core/types.h"
#include "gpu/gpu_volume.h"
#include "py_reconstructor.h"
#include "slam/loop_closer.h"
#include "vk/context.h"

using namespace pybind11::literals;

namespace vkmesh::python {

vk::ContextOptions deviceOptions(const py::object& device, bool validation) {
    vk::ContextOptions o;
    if (!device.is_none()) {
        if (!py::isinstance<py::int_>(device) || py::isinstance<py::bool_>(device))
            throw py::value_error("device must be None (the first suitable one) or an index from vkmesh.devices(), got " +
                                  py::repr(device).cast<std::string>());
        const long long index = device.cast<long long>();
        if (index < 0) throw py::value_error("device " + std::to_string(index) + " must be >= 0");
        o.deviceIndex = int(std::min<long long>(index, std::numeric_limits<int>::max()));   // too large: vk::Context says so
    }
    o.validation = validation;   // VKMESH_VALIDATION=1 turns it on as well (vk::Context, as for the CLI)
    return o;
}

namespace {

ColorFusion parseColorMode(const std::string& mode) {
    if (mode == "average") return ColorFusion::Average;
    if (mode == "recent") return ColorFusion::Recent;
    if (mode == "off") return ColorFusion::Off;
    throw py::value_error("color_mode '" + mode + "' is not one of 'average', 'recent', 'off'");
}

uint32_t capacity(const char* name, long long value) {
    if (value < 0 || value > 0xFFFFFFFFll)
        throw py::value_error(std::string(name) + " = " + std::to_string(value) + " must be in [0, 2^32)");
    return uint32_t(value);
}

// The capacities of gpu::GpuVolumeConfig, shared by the constructor and load() (initial sizes: they grow).
struct Capacities {
    long long blocks, hashSlots, touched, vertices, chunks, retype, deltaRecords;
    void applyTo(gpu::GpuVolumeConfig& c) const {
        c.blockCapacity = capacity("block_capacity", blocks);
        c.hashCapacity = capacity("hash_capacity", hashSlots);
        c.touchedCapacity = capacity("touched_capacity", touched);
        c.vertexCapacity = capacity("vertex_capacity", vertices);
        c.chunkCapacity = capacity("chunk_capacity", chunks);
        c.retypeCapacity = capacity("retype_capacity", retype);
        c.deltaRecordCapacity = capacity("delta_record_capacity", deltaRecords);
    }
};


// Checks a configuration's settings before any device exists: a bad value is a ValueError naming it. The
// image size is not known before the first frame; a placeholder stands in for it.
void checkConfig(gpu::GpuVolumeConfig config) {
    config.imageWidth = config.imageHeight = 1;
    try {
        gpu::resolveConfig(config);
    } catch (const Error& e) {
        throw py::value_error(e.what());
    }
}

// keep_frames, corrections_per_frame, frames_budget_mb, frames_spill (ReconstructorOptions, docs/CORRECTION.md), and
// loop_closure (docs/LOOP_CLOSURE.md: its loop closer is made once the tracker's options are known, withLoopClosure).
struct CorrectionSettings {
    bool keepFrames = false;
    bool loopClosure = false;
    long long correctionsPerFrame = ReconstructorOptions{}.correctionsPerFrame;
    long long loopPlaceCandidates = kDefaultLoopPlaceCandidates;
    double framesBudgetMb = 1024;
    std::string framesSpill;
    void applyTo(ReconstructorOptions& o) const {
        if (correctionsPerFrame < 0 || correctionsPerFrame > 1000000)
            throw py::value_error("corrections_per_frame " + std::to_string(correctionsPerFrame) + " must be in [0, 1000000]");
        if (loopPlaceCandidates < 0 || loopPlaceCandidates > 100)
            throw py::value_error("loop_place_candidates " + std::to_string(loopPlaceCandidates) + " must be in [0, 100]");
        if (!(framesBudgetMb > 0)) throw py::value_error("frames_budget_mb " + std::to_string(framesBudgetMb) + " must be positive");
        o.keepFrames = keepFrames;
        o.correctionsPerFrame = uint32_t(correctionsPerFrame);
        o.frameStore.memoryBudgetBytes = size_t(framesBudgetMb * 1024 * 1024);
        o.frameStore.spillFolder = framesSpill;
    }
    void withLoopClosure(ReconstructorOptions& o) const {
        if (!loopClosure) return;
        if (!keepFrames) throw py::value_error("loop_closure=True re-fuses the frames a loop moves: it needs keep_frames=True");
        slam::LoopClosureOptions lo;
        lo.tracker = o.tracker;
        lo.proximityCandidates = int(loopPlaceCandidates);
        o.loopClosure = std::make_shared<slam::LoopCloser>(lo);
    }
};

std::unique_ptr<PyReconstructor> makeReconstructor(float voxelSize, float truncationVoxels, float maxDepth, const py::object& device,
                                                   const std::string& colorMode, float colorRecency, bool trackDeltas, float maxWeight,
                                                   float minWeight, int allocationStride, bool refine, float refineEpsilonVoxels,
                                                   bool lockFree, const Capacities& capacities, bool growCapacities, float keepRadius,
                                                   bool recycle, long long recycleAfterFrames, float starveWeight, bool validation,
                                                   float trackColorWeight, const std::string& trackSolve, int trackDownsample,
                                                   int trackModelReuse, const CorrectionSettings& correction, bool allocationTiles,
                                                   long long residentBlocks) {
    ReconstructorOptions o;
    correction.applyTo(o);
    gpu::GpuVolumeConfig& c = o.volume;
    c.params.voxelSize = voxelSize;
    c.params.truncVoxels = truncationVoxels;
    c.params.maxDepth = maxDepth;
    c.params.maxWeight = maxWeight;
    if (maxWeight != VolumeParams{}.maxWeight)
        PyErr_WarnEx(PyExc_DeprecationWarning, "max_weight is deprecated and has no effect: the TSDF keeps exact sums so that frames can be taken out again", 1);
    c.params.allocationStride = allocationStride;
    c.params.allocationTiles = allocationTiles;
    c.params.colorFusion = parseColorMode(colorMode);
    c.params.colorRecency = colorRecency;
    c.minMeshWeight = minWeight;
    c.refine = refine;
    c.refineEpsilonVoxels = refineEpsilonVoxels;
    c.lockFree = lockFree;
    capacities.applyTo(c);
    c.growCapacities = growCapacities;
    c.keepRadius = keepRadius;
    c.recycle = recycle;
    c.recycleAfterFrames = capacity("recycle_after_frames", recycleAfterFrames);
    c.starveWeight = starveWeight;
    if (residentBlocks < 0 || residentBlocks > UINT32_MAX)
        throw py::value_error("resident_blocks " + std::to_string(residentBlocks) + " must be in [0, 2^32) (0: every block stays on the GPU)");
    c.residentBlocks = uint32_t(residentBlocks);
    // The checks `vkmesh fuse` makes on its options (CLI11 ranges) that the volume itself does not.
    if (!(minWeight >= 1.0f && minWeight <= 255.0f)) throw py::value_error("min_weight " + std::to_string(minWeight) + " must be in [1, 255]");
    if (c.blockCapacity == 0) throw py::value_error("block_capacity must be at least 1");
    checkConfig(c);
    if (!(trackColorWeight >= 0.0f && trackColorWeight <= 100.0f))
        throw py::value_error("track_color_weight " + std::to_string(trackColorWeight) + " must be in [0, 100]");
    if (trackSolve != "host" && trackSolve != "gpu") throw py::value_error("track_solve '" + trackSolve + "' must be 'host' or 'gpu'");
    o.tracker.colorWeight = trackColorWeight;
    o.tracker.solveOnGpu = trackSolve == "gpu";
    if (trackDownsample != 0 && trackDownsample != 1 && trackDownsample != 2 && trackDownsample != 4)
        throw py::value_error("track_downsample " + std::to_string(trackDownsample) + " must be 0 (by the frame's width), 1, 2 or 4");
    o.tracker.downsample = trackDownsample;
    if (trackModelReuse < 0 || trackModelReuse > 1000)
        throw py::value_error("track_model_reuse " + std::to_string(trackModelReuse) + " must be in 0..1000");
    o.tracker.modelReuseFrames = trackModelReuse;
    correction.withLoopClosure(o);
    o.trackDeltas = trackDeltas;
    o.device = deviceOptions(device, validation);
    std::unique_ptr<Reconstructor> rec;
    std::vector<std::string> messages;
    {
        py::gil_scoped_release release;   // creating the instance and the device takes a while
        rec = std::make_unique<Reconstructor>(o);
        messages = rec->context().takeValidationMessages();
    }
    publishMessages(std::move(messages));
    return std::make_unique<PyReconstructor>(o, std::move(rec));
}

std::unique_ptr<PyReconstructor> loadReconstructor(const fs::path& path, const py::object& device, bool trackDeltas,
                                                   const Capacities& capacities, bool validation, const CorrectionSettings& correction) {
    ReconstructorOptions o;
    correction.applyTo(o);
    capacities.applyTo(o.volume);
    o.trackDeltas = trackDeltas;
    o.device = deviceOptions(device, validation);
    std::unique_ptr<Reconstructor> rec;
    std::vector<std::string> messages;
    {
        py::gil_scoped_release release;
        rec = Reconstructor::load(path, o);
        messages = rec->context().takeValidationMessages();
    }
    publishMessages(std::move(messages));
    o.volume = rec->volume()->config();   // the map's settings (voxel size, max depth, colour, ...)
    return std::make_unique<PyReconstructor>(o, std::move(rec));
}

// A frame converted to the C++ API's types ahead of time, for the overhead benchmark (bench/python_overhead.py).
struct CppFrame {
    DepthImage depth;
    std::optional<ColorImage> color;
    Intrinsics intrinsics;
    Pose pose;
};

}  // namespace

void bindReconstructor(py::module_& m) {
    const gpu::GpuVolumeConfig dc;   // the library's defaults, which are `vkmesh fuse`'s
    const VolumeParams dp;
    py::class_<PyReconstructor>(m, "Reconstructor", R"doc(
Fuses depth frames into a TSDF on the GPU and keeps one incremental triangle mesh up to date.

    r = vkmesh.Reconstructor(voxel_size=0.02)
    for f in vkmesh.open_dataset("room"):
        r.integrate(f.depth, f.intrinsics, f.pose, color=f.color)
    m = r.mesh()                  # m.vertices (N, 3) float32, m.triangles (M, 3) uint32, ...
    m.save("room.ply")

The defaults are those of `vkmesh fuse`, so the same frames give the CLI's mesh. Every capacity is an initial
size that grows between frames when nearly full (grow_capacities=True). Runs on the first suitable Vulkan
device unless `device` gives an index from vkmesh.devices(); VKMESH_VALIDATION=1 in the environment (or
validation=True) turns the Khronos validation layer on. One thread at a time uses a Reconstructor (calls from
several threads wait for each other); the GIL is released while the GPU works.

Keyword arguments (all optional):
  voxel_size            metres between TSDF samples (--voxel; 0.03)
  truncation_voxels     truncation distance in voxels (--trunc; 4)
  max_depth             depth beyond this many metres is ignored (--max-depth; 4)
  device                None (a discrete GPU if any, else the first suitable device) or an index (--device)
  color_mode            'average' (running average with the TSDF weights), 'recent' (exponential, follows
                        lighting changes, see color_recency) or 'off' (depth only, 4 bytes per cube less)
  color_recency         'recent': share of the newest colour, in (0, 1] (--color-recency; 0.2)
  track_deltas          keep each frame's mesh changes for deltas() (--deltas)
  max_weight            deprecated, no effect (a DeprecationWarning): the TSDF keeps exact sums (--max-weight)
  min_weight            a cube is meshed when its 8 corners have this weight (--min-weight; 1)
  allocation_stride     allocate blocks from every Nth pixel (--alloc-stride; 2)
  allocation_tiles      claim the blocks around the plane of a tile of 8 x 8 sampled pixels where one fits instead of
                        walking every sampled pixel's band (--alloc-tiles / --alloc-pixels; True)
  refine, refine_epsilon_voxels   Hamming-distance refinement of cube types (--refine, --refine-eps)
  lock_free             the paper's lock-free vertex claims (--lock-free; same mesh)
  block_capacity, hash_capacity, touched_capacity, vertex_capacity, chunk_capacity, retype_capacity,
  delta_record_capacity initial capacities (gpu::GpuVolumeConfig; --blocks, --hash-slots, --vertices, --chunks)
  grow_capacities       grow them when nearly full (True); False: fixed, what does not fit is skipped and
                        reported as a vkmesh.CapacityWarning (--no-grow)
  keep_radius, recycle, recycle_after_frames, starve_weight   bounded maps (--keep-radius, --recycle, ...)
  resident_blocks       paging: at most this many blocks stay in GPU memory, the others wait on the host until a
                        camera may reach them; the same map, bit for bit (docs/PAGING.md; --resident-blocks; 0: all)
  validation            the Khronos validation layer (also on with VKMESH_VALIDATION=1)
  track_color_weight    tracking (integrate without a pose): the photometric term's weight (--track-color-weight; 0.1)
  track_solve           tracking: 'host' (systems solved in double, a GPU submission per ICP iteration) or 'gpu'
                        (in float; the frame's tracking, fusion and meshing in one submission) (--track-solve; 'host')
  track_downsample      tracking on the frames downsampled by 1, 2 or 4; 0: 2 for frames at least 640 pixels wide,
                        else 1 (--track-downsample; 0)
  track_model_reuse     tracking: frames in a row that may reuse the model maps (the mesh drawn for an earlier frame)
                        while the camera is predicted within 4 cm and 4 degrees of where they were drawn; 0: the
                        mesh is drawn for every frame (--track-model-reuse; 2)
  keep_frames           keep every fused frame (compressed) so that correct() can re-fuse frames whose poses
                        change; save() writes them beside the map (docs/CORRECTION.md; False)
  corrections_per_frame corrected frames re-fused by each later integrate() (2)
  frames_budget_mb, frames_spill   the kept frames' memory budget in MiB (1024) and a folder for those beyond it
                        ('' : none, and a frame beyond the budget raises vkmesh.Error) (--frames-budget, --frames-spill)
  loop_closure          tracking: recognise places seen before, verify them, optimise a pose graph and re-fuse the
                        frames a loop moves; relocalise lost frames from keyframes (docs/LOOP_CLOSURE.md; needs
                        keep_frames=True; --loop-closure; False)
  loop_place_candidates loop closure: old keyframes that the pose graph puts near a new keyframe verified as loop
                        candidates besides the ferns'; 0: the ferns alone (--loop-place-candidates; 2)

Bad settings raise ValueError; no usable device or a capacity that does not fit it raises vkmesh.Error.
)doc")
        // Float settings are taken as Python floats (doubles) whose defaults read back as the library's floats.
        .def(py::init([](double voxelSize, double truncationVoxels, double maxDepth, const py::object& device, const std::string& colorMode,
                         double colorRecency, bool trackDeltas, double maxWeight, double minWeight, int allocationStride, bool refine,
                         double refineEpsilonVoxels, bool lockFree, long long blockCapacity, long long hashCapacity,
                         long long touchedCapacity, long long vertexCapacity, long long chunkCapacity, long long retypeCapacity,
                         long long deltaRecordCapacity, bool growCapacities, double keepRadius, bool recycle,
                         long long recycleAfterFrames, double starveWeight, bool validation, double trackColorWeight,
                         const std::string& trackSolve, int trackDownsample, int trackModelReuse, bool keepFrames,
                         long long correctionsPerFrame, double framesBudgetMb, const std::string& framesSpill, bool loopClosure,
                         long long loopPlaceCandidates, bool allocationTiles, long long residentBlocks) {
                 return makeReconstructor(voxelSize, truncationVoxels, maxDepth, device, colorMode, colorRecency, trackDeltas,
                                          maxWeight, minWeight, allocationStride, refine, refineEpsilonVoxels, lockFree,
                                          {blockCapacity, hashCapacity, touchedCapacity, vertexCapacity, chunkCapacity,
                                           retypeCapacity, deltaRecordCapacity},
                                          growCapacities, keepRadius, recycle, recycleAfterFrames, starveWeight, validation,
                                          float(trackColorWeight), trackSolve, trackDownsample, trackModelReuse,
                                          {.keepFrames = keepFrames, .loopClosure = loopClosure, .correctionsPerFrame = correctionsPerFrame,
                                           .loopPlaceCandidates = loopPlaceCandidates, .framesBudgetMb = framesBudgetMb,
                                           .framesSpill = framesSpill}, allocationTiles, residentBlocks);
             }),
             py::kw_only(), "voxel_size"_a = shortest(dp.voxelSize), "truncation_voxels"_a = shortest(dp.truncVoxels),
             // `vkmesh fuse --max-depth` defaults to 4 m (host/cli_options.h, DatasetArgs), not VolumeParams' 5 m.
             "max_depth"_a = kDefaultMaxDepth, "device"_a = py::none(), "color_mode"_a = "average", "color_recency"_a = shortest(dp.colorRecency),
             "track_deltas"_a = false, "max_weight"_a = shortest(dp.maxWeight), "min_weight"_a = shortest(dc.minMeshWeight),
             "allocation_stride"_a = dp.allocationStride, "refine"_a = dc.refine,
             "refine_epsilon_voxels"_a = shortest(dc.refineEpsilonVoxels),
             "lock_free"_a = dc.lockFree, "block_capacity"_a = dc.blockCapacity, "hash_capacity"_a = dc.hashCapacity,
             "touched_capacity"_a = dc.touchedCapacity, "vertex_capacity"_a = dc.vertexCapacity, "chunk_capacity"_a = dc.chunkCapacity,
             "retype_capacity"_a = dc.retypeCapacity, "delta_record_capacity"_a = dc.deltaRecordCapacity,
             "grow_capacities"_a = dc.growCapacities, "keep_radius"_a = shortest(dc.keepRadius), "recycle"_a = dc.recycle,
             "recycle_after_frames"_a = dc.recycleAfterFrames, "starve_weight"_a = shortest(dc.starveWeight), "validation"_a = false,
             "track_color_weight"_a = shortest(gpu::TrackerOptions{}.colorWeight), "track_solve"_a = "host",
             "track_downsample"_a = gpu::TrackerOptions{}.downsample,
             "track_model_reuse"_a = gpu::TrackerOptions{}.modelReuseFrames, "keep_frames"_a = false,
             "corrections_per_frame"_a = ReconstructorOptions{}.correctionsPerFrame, "frames_budget_mb"_a = 1024.0, "frames_spill"_a = "",
             "loop_closure"_a = false, "loop_place_candidates"_a = kDefaultLoopPlaceCandidates, "allocation_tiles"_a = dp.allocationTiles,
             "resident_blocks"_a = dc.residentBlocks)
        .def("integrate", &PyReconstructor::integrate, "depth"_a, "intrinsics"_a, "pose"_a = py::none(), "depth_scale"_a = 5000.0,
             "color"_a = py::none(), R"doc(
Fuses one frame and updates the mesh; returns when the GPU has finished it.

depth        H x W numpy array: uint16 raw sensor units (divided by depth_scale, as vkmesh reads a dataset's
             PNGs) or float32 metres (0 or NaN: no measurement). Depth beyond max_depth is ignored. Every
             frame must have the first frame's size. Arrays that are not C-contiguous are copied once.
intrinsics   (fx, fy, cx, cy) in pixels, or a 3x3 camera matrix.
pose         4x4 camera-to-world matrix (the camera's pose in the world), rigid: a rotation and a translation.
             None: the camera is tracked against the mesh fused so far (docs/TRACKING.md); the very first frame
             is fused at the identity (or at the last pose given). Returns then a dict: "pose" (the 4x4 pose
             used), "tracked" (False: the frame was lost and not fused; "pose" is the prediction),
             "lost_reason", "iterations", "inliers", "valid_pixels", "rmse" (metres), "ms". With a pose: None.
depth_scale  raw units per metre for uint16 depth (5000: TUM; 1000: millimetres); ignored for float32.
color        None or an H x W x 3 uint8 array (red, green, blue) registered to the depth image.

Raises ValueError (wrong dtype, shape or value; a pose that is not rigid) before anything reaches the GPU,
vkmesh.Error for Vulkan problems. Capacity problems are vkmesh.CapacityWarning warnings.
)doc")
        .def("correct", &PyReconstructor::correct, "frames"_a, "poses"_a, R"doc(
New camera-to-world poses for frames already fused (docs/CORRECTION.md; needs keep_frames=True): frames is a
1-D array of frame indices (frame i: the i-th frame integrated, trajectory()[i]), poses an N x 4 x 4 array.
Every index and pose is checked first (ValueError for a bad array or pose, vkmesh.Error for a frame that was
not kept, e.g. lost by tracking), and then nothing is queued. Each frame is de-integrated at the pose it was
fused at and integrated at the new one, exactly: the map then equals one fused at the new poses from the start.
The largest pose changes go first, corrections_per_frame of them in each later integrate(); finish_corrections()
does the rest at once. The mesh follows; deltas() reports every change.
)doc")
        .def("pending_corrections", &PyReconstructor::pendingCorrections, "How many corrected frames wait to be re-fused.")
        .def("finish_corrections", &PyReconstructor::finishCorrections, R"doc(
Re-fuses every queued frame now and publishes the mesh. Returns a dict: frames_refused, frames (their indices in
the order re-fused), blocks_freed (blocks left with no observation), observations_dropped (0 for a consistent
map), ms, warnings.
)doc")
        .def("last_corrections", &PyReconstructor::lastCorrections,
             "What the last integrate() or finish_corrections() re-fused (the dict finish_corrections() returns).")
        .def("trajectory", &PyReconstructor::trajectory, R"doc(
Every frame's camera-to-world pose so far (given, tracked, or predicted for a lost frame), as an N x 4 x 4 array.
)doc")
        .def("mesh", &PyReconstructor::mesh, R"doc(
The mesh after the last frame, copied from the GPU: a vkmesh.Mesh with vertices (N, 3) float32, triangles
(M, 3) uint32 (counter-clockwise seen from outside), normals (N, 3) float32, colors (N, 3) uint8 (None when no
colour was fused; grey for vertices no colour reached) and ages (N,) uint32 (frames since each vertex was
created). Empty before the first frame. To save a map that resumes exactly, call save() before mesh().
)doc")
        .def("deltas", &PyReconstructor::deltas, R"doc(
The last frame's mesh changes (docs/DELTAS.md) as a vkmesh.MeshDelta: vertices and triangles added, changed
(vertices only) or removed, by id. Needs track_deltas=True (else vkmesh.Error). Applying every frame's deltas
in order to an empty mesh gives mesh().
)doc")
        .def("stats", &PyReconstructor::stats, R"doc(
Counts, capacities and memory as a dict, with the keys `vkmesh fuse --stats` uses for the same things:
device, int64_atomics, frames, voxel_size, truncation_m, allocation_stride, allocation_tiles, max_depth, color, capacities,
recycling, and after the first frame blocks, heaps, gpu_pool_bytes, gpu_bytes_total and last_frame (its
GPU milliseconds per stage, counts, capacity warnings and growth); with keep_frames, frame_store (frames,
compressed bytes in memory and on disk, bytes_per_frame, pending_corrections).
)doc")
        .def("save", &PyReconstructor::save, "path"_a, R"doc(
Writes everything the reconstruction holds after the last frame to a map file (.vkmap, docs/MAPFILE.md), and with
keep_frames the kept frames beside it (the path with the extension .vkframes, docs/CORRECTION.md).
Reconstructor.load(path), `vkmesh fuse --load path` and `vkmesh export path` continue from it exactly.
Raises vkmesh.Error before the first frame or when the file cannot be written.
)doc")
        .def_static("load", [](const fs::path& path, const py::object& device, bool trackDeltas, long long blockCapacity,
                               long long hashCapacity, long long touchedCapacity, long long vertexCapacity, long long chunkCapacity,
                               long long retypeCapacity, long long deltaRecordCapacity, bool validation, bool keepFrames,
                               long long correctionsPerFrame, double framesBudgetMb, const std::string& framesSpill) {
                        return loadReconstructor(path, device, trackDeltas,
                                                 {blockCapacity, hashCapacity, touchedCapacity, vertexCapacity, chunkCapacity,
                                                  retypeCapacity, deltaRecordCapacity},
                                                 validation,
                                                 {.keepFrames = keepFrames, .correctionsPerFrame = correctionsPerFrame,
                                                  .framesBudgetMb = framesBudgetMb, .framesSpill = framesSpill});
                    },
                    "path"_a, py::kw_only(), "device"_a = py::none(), "track_deltas"_a = false, "block_capacity"_a = dc.blockCapacity,
                    "hash_capacity"_a = dc.hashCapacity, "touched_capacity"_a = dc.touchedCapacity,
                    "vertex_capacity"_a = dc.vertexCapacity, "chunk_capacity"_a = dc.chunkCapacity, "retype_capacity"_a = dc.retypeCapacity,
                    "delta_record_capacity"_a = dc.deltaRecordCapacity, "validation"_a = false, "keep_frames"_a = false,
                    "corrections_per_frame"_a = ReconstructorOptions{}.correctionsPerFrame, "frames_budget_mb"_a = 1024.0,
                    "frames_spill"_a = "", R"doc(
A Reconstructor continuing the map in `path` (written by save() or `vkmesh fuse --save`): the next integrate()
gives exactly what an uninterrupted run would have. keep_frames=True also loads the frame store saved beside it
(path with the extension .vkframes), so that correct() works on the map's frames (vkmesh.Error when there is
none, or when it was saved with another map). The map's settings are used (voxel size, truncation, max
depth, colour, ...); the capacities given here where larger than the map's. Raises vkmesh.Error naming the
file and the problem for a missing, corrupt or truncated map.
)doc")
        .def("serve",
             [](PyReconstructor& self, int port, const std::string& host) {
                 const std::string url = self.serve(port, host);
                 py::print("vkmesh: serving the viewer at " + url);
                 return url;
             },
             "port"_a = 8080, "host"_a = "127.0.0.1", R"doc(
Serves the live browser viewer (docs/VIEWER.md) and returns its URL (also printed): every later integrate()
sends the frame's mesh changes to the pages open at that URL, and a page that joins late gets the whole mesh
first. Needs track_deltas=True and must be called before the first integrate(). The server runs on a thread of
its own: integrate() only hands it a copy of the frame's changes and never waits for a page. host 127.0.0.1
(default) serves this machine only; "0.0.0.0" every interface. port 0: any free port. Raises vkmesh.Error when
the port is taken (naming it). stop_serving() or close() stops it.
)doc")
        .def("stop_serving", &PyReconstructor::stopServing,
             "Stops the viewer's server (closing its pages) and returns what it did: pages, messages_sent, bytes_sent, "
             "frames_published, frames_coalesced (an empty dict when not serving).")
        .def("close", &PyReconstructor::close,
             "Releases the GPU memory and the Vulkan device now (rather than when the object is collected). Any later "
             "call raises vkmesh.Error.")
        .def("__enter__", [](py::object self) { return self; })
        .def("__exit__", [](PyReconstructor& self, const py::args&) { self.close(); })
        .def_property_readonly("closed", &PyReconstructor::closed, "Whether close() was called.")
        .def_property_readonly("frames_integrated", &PyReconstructor::framesIntegrated, "How many frames have been fused.")
        .def("__repr__", &PyReconstructor::repr)
        .def_property_readonly("_last_cpp_seconds", &PyReconstructor::lastCppSeconds,
                               "Benchmarks: seconds the last integrate() spent in the C++ Reconstructor::integrate.");
}

void bindBenchmark(py::module_& m) {
    // The overhead benchmark's C++ side (bench/python_overhead.py): a frame converted once, then the C++ API's
    // integrate on it, timed in C++.
    py::class_<CppFrame>(m, "_CppFrame")
        .def(py::init([](const py::object& depth, const py::object& intrinsics, const py::object& pose, double depthScale,
                         const py::object& color, float maxDepth) {
                 auto f = std::make_unique<CppFrame>();
                 const DepthInput d = checkDepth(depth);
                 convertDepth(d, depthScale, maxDepth, f->depth);
                 f->intrinsics = toIntrinsics(intrinsics, d.width, d.height);
                 f->pose = toPose(pose, "_CppFrame");
                 if (auto c = checkColor(color, d)) convertColor(*c, f->color.emplace());
                 return f;
             }),
             "depth"_a, "intrinsics"_a, "pose"_a, "depth_scale"_a = 5000.0, "color"_a = py::none(), "max_depth"_a = 4.0f);
    m.def("_timed_cpp_integrate", [](PyReconstructor& r, const CppFrame& f) {
        return r.timedCppIntegrate(f.depth, f.color ? &*f.color : nullptr, f.intrinsics, f.pose);
    });
}

}  // namespace vkmesh::python
