#include "api/settings.h"

#include <charconv>
#include <cmath>

#include "api/mapper.h"

namespace vkmesh {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string text(bool v) { return v ? "true" : "false"; }
std::string text(float v) { return shortestText(v); }
std::string text(int v) { return std::to_string(v); }
std::string text(uint32_t v) { return std::to_string(v); }
std::string text(size_t v) { return std::to_string(v); }

SettingDescription make(std::string cli, std::string python, SettingKind kind, std::string defaultValue, std::string help) {
    SettingDescription d;
    d.cli = std::move(cli);
    d.python = std::move(python);
    d.kind = kind;
    d.defaultValue = std::move(defaultValue);
    d.help = std::move(help);
    return d;
}

SettingDescription range(SettingDescription d, double min, double max, bool minExclusive = false) {
    d.min = min, d.max = max, d.minExclusive = minExclusive;
    return d;
}
SettingDescription positive(SettingDescription d) { return range(std::move(d), 0.0, kInf, true); }
SettingDescription choices(SettingDescription d, std::vector<std::string> values) {
    d.choices = std::move(values);
    return d;
}
SettingDescription fromMap(SettingDescription d, void (*copy)(const gpu::GpuVolumeConfig&, gpu::GpuVolumeConfig&), std::string givenWith = "") {
    d.fromMap = copy;
    d.givenWith = std::move(givenWith);
    return d;
}

std::vector<SettingDescription> describeAll() {
    using K = SettingKind;
    const VolumeParams p;
    const gpu::GpuVolumeConfig c;
    const gpu::TrackerOptions t;
    const MapperOptions m;
    std::vector<SettingDescription> s;
    // --- the input ---
    s.push_back(positive(make("--max-depth", "max_depth", K::Input, text(kDefaultMaxDepth), "ignore depth beyond M metres")));
    s.push_back(make("--frames", "", K::Input, "0", "use at most N frames (0 = all)"));
    s.push_back(make("--intrinsics", "", K::Input, "", "override the camera: fx,fy,cx,cy"));
    s.push_back(positive(make("--depth-scale", "", K::Input, "", "raw depth units per metre (5000 TUM, 1000 mm)")));
    s.push_back(make("--depth-topic", "", K::Input, "", "recordings: the depth image topic (default: the one sensor_msgs/Image topic of depth)"));
    s.push_back(make("--color-topic", "", K::Input, "", "recordings: the colour image topic (default: the one of colour, if any)"));
    s.push_back(make("--info-topic", "", K::Input, "",
                     "recordings: the depth camera's sensor_msgs/CameraInfo topic (default: the one beside the depth topic)"));
    s.push_back(make("--first-frame", "", K::Input, "0", "start at this frame of the dataset (0-based; frames before it are skipped)"));

    // --- what the map holds: saved with it, taken from it on --load ---
    s.push_back(fromMap(make("--voxel", "voxel_size", K::Map, text(p.voxelSize), "voxel (cube) size in metres"),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.params.voxelSize = map.params.voxelSize; }));
    s.push_back(fromMap(make("--trunc", "truncation_voxels", K::Map, text(p.truncVoxels), "truncation distance in voxels"),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.params.truncVoxels = map.params.truncVoxels; }));
    {
        SettingDescription d = make("--max-weight", "max_weight", K::Map, text(p.maxWeight),
                                    "deprecated, no effect: fusion keeps exact sums (docs/CORRECTION.md)");
        d.deprecated = "the TSDF keeps exact sums of every observation so that frames can be taken out again (docs/CORRECTION.md)";
        s.push_back(fromMap(d, [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.params.maxWeight = map.params.maxWeight; }));
    }
    s.push_back(fromMap(range(make("--min-weight", "min_weight", K::Map, text(c.minMeshWeight),
                                   "a cube is meshed when its 8 corners have at least this weight"),
                              1.0, 255.0),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.minMeshWeight = map.minMeshWeight; }));
    s.push_back(fromMap(range(make("--alloc-stride", "allocation_stride", K::Map, text(p.allocationStride),
                                   "allocate blocks from every Nth pixel in x and y (1 = every pixel, as the paper; Open3D uses 4)"),
                              1, 64),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.params.allocationStride = map.params.allocationStride; }));
    s.push_back(fromMap(make("--alloc-tiles", "allocation_tiles", K::Map, text(p.allocationTiles),
                             "allocation by tiles (the default): claim the blocks around the plane of a tile of 8 x 8 sampled pixels "
                             "where one fits, instead of walking each pixel's truncation band (a few percent more blocks, less "
                             "allocation work)"),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.params.allocationTiles = map.params.allocationTiles; },
                        "--alloc-pixels"));
    s.push_back(make("--alloc-pixels", "", K::Map, "false",
                     "allocation pixel by pixel: every sampled pixel walks its truncation band (the default before "
                     "2026-12-05; maps fused that way keep it)"));
    s.push_back(fromMap(choices(make("--mode", "", K::Map, "incremental",
                                     "incremental: one shared-vertex mesh updated every frame (default); "
                                     "baseline: marching cubes at the end, every triangle with its own 3 vertices"),
                                {"incremental", "baseline"}),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.meshMode = map.meshMode; }));
    s.push_back(fromMap(make("--refine", "refine", K::Map, text(c.refine),
                             "Hamming-distance refinement of cube types, decided per corner so the mesh has no cracks (paper "
                             "§V.F, docs/REFINEMENT.md; on by default, --no-refine turns it off)"),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.refine = map.refine; }));
    s.push_back(fromMap(range(make("--refine-eps", "refine_epsilon_voxels", K::Map, text(c.refineEpsilonVoxels),
                                   "refinement: corners within this many voxels of the surface may flip"),
                              0.0, 1.0),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.refineEpsilonVoxels = map.refineEpsilonVoxels; }));
    s.push_back(fromMap(range(make("--keep-radius", "keep_radius", K::Map, text(c.keepRadius),
                                   "bounded map: keep only blocks within R metres of the camera; farther ones are not allocated and are "
                                   "freed with their mesh (0 = off, the default)"),
                              0.0, kInf),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.keepRadius = map.keepRadius; }));
    s.push_back(fromMap(make("--recycle", "recycle", K::Map, text(c.recycle),
                             "bounded map: blocks not seen for --recycle-after frames lose --starve-weight per frame and are freed "
                             "(with their mesh) once empty (off by default)"),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.recycle = map.recycle; }));
    s.push_back(fromMap(positive(make("--recycle-after", "recycle_after_frames", K::Map, text(c.recycleAfterFrames),
                                      "frames without a touch before a block starves")),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.recycleAfterFrames = map.recycleAfterFrames; }));
    s.push_back(fromMap(positive(make("--starve-weight", "starve_weight", K::Map, text(c.starveWeight),
                                      "weight a starving block's corners lose per frame")),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.starveWeight = map.starveWeight; }));
    // A map keeps its colour (frames without colour images then fuse depth only); --no-color or --color-mode on the
    // command line must agree with it.
    s.push_back(fromMap(choices(make("--color-mode", "color_mode", K::Map, "average",
                                     "average: running average of the colour with the TSDF's weights (default); recent: exponential "
                                     "average that follows lighting changes (--color-recency); Python also takes off"),
                                {"average", "recent"}),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.params.colorFusion = map.params.colorFusion; },
                        "--no-color"));
    s.push_back(make("--no-color", "", K::Map, "false", "fuse depth only, even when the dataset has colour images (4 bytes per cube less)"));
    s.push_back(fromMap(range(make("--color-recency", "color_recency", K::Map, text(p.colorRecency),
                                   "--color-mode recent: share of the newest colour, in (0, 1]"),
                              0.001, 1.0),
                        [](const gpu::GpuVolumeConfig& map, gpu::GpuVolumeConfig& to) { to.params.colorRecency = map.params.colorRecency; }));

    // --- capacities: initial sizes, grown when full ---
    s.push_back(positive(make("--blocks", "block_capacity", K::Capacity, text(c.blockCapacity),
                              "initial block pool capacity (8x8x8 voxels each); grows when nearly full")));
    s.push_back(make("--resident-blocks", "resident_blocks", K::Processing, text(c.residentBlocks),
                     "paging: keep at most N blocks in GPU memory, the others on the host until a camera may reach them "
                     "again; the map is the same, bit for bit (docs/PAGING.md; 0 = every block, the default)"));
    s.push_back(make("--hash-slots", "hash_capacity", K::Capacity, text(c.hashCapacity),
                     "initial spatial hash capacity, a power of two (0 = 2x --blocks; grows when half full)"));
    s.push_back(positive(make("--vertices", "vertex_capacity", K::Capacity, text(c.vertexCapacity),
                              "initial vertex heap capacity (grows when nearly full)")));
    s.push_back(positive(make("--chunks", "chunk_capacity", K::Capacity, text(c.chunkCapacity),
                              "initial triangle chunk heap capacity (5 triangles each; grows when nearly full)")));
    s.push_back(make("", "touched_capacity", K::Capacity, text(c.touchedCapacity), "blocks one frame may touch (0: the block capacity)"));
    s.push_back(make("", "retype_capacity", K::Capacity, text(c.retypeCapacity), "cubes one mesh pass can retype (more wait for the next pass)"));
    s.push_back(make("", "delta_record_capacity", K::Capacity, text(c.deltaRecordCapacity),
                     "initial size of each mesh-delta record list (grown on demand)"));
    {
        SettingDescription d = make("--no-grow", "grow_capacities", K::Capacity, text(c.growCapacities),
                                    "keep every capacity (--blocks, --vertices, --chunks, --hash-slots) fixed: what does not fit is "
                                    "reported and skipped instead of grown past");
        d.cliNegates = true;
        s.push_back(d);
    }
    {
        SettingDescription d = make("--grow-heaps", "", K::Capacity, "false",
                                    "deprecated, no effect: every capacity grows by default (--no-grow keeps them fixed)");
        d.deprecated = "capacities grow by default (--no-grow keeps them fixed)";
        s.push_back(d);
    }

    // --- how the work is done ---
    s.push_back(make("--lock-free", "lock_free", K::Processing, text(c.lockFree),
                     "claim edge vertices in 4 parity-class passes without atomics (paper's lock-free)"));

    // --- tracking ---
    s.push_back(make("--track", "", K::Tracking, "false",
                     "estimate the camera poses: every frame after the first is tracked against the mesh fused so far "
                     "(the first frame's pose is the dataset's, or identity when it has none; its other poses are not used). "
                     "Datasets without poses need it"));
    s.push_back(make("--track-iterations", "", K::Tracking, "",
                     "ICP iterations per pyramid level, finest first (default by the finest tracked level's width: 3,4,4 from 320 "
                     "pixels wide, 10,5,4 below)"));
    s.push_back(range(make("--track-color-weight", "track_color_weight", K::Tracking, text(t.colorWeight),
                           "weight of tracking's photometric term (the frame's intensity against the mesh's fused colours; needs "
                           "colour images and colour fusion); 0: geometry only"),
                      0.0, 100.0));
    s.push_back(choices(make("--track-solve", "track_solve", K::Tracking, t.solveOnGpu ? "gpu" : "host",
                             "where tracking solves its 6x6 systems: host (in double, one GPU submission per ICP iteration) or gpu (in "
                             "float; the frame's tracking, fusion and meshing in one submission; docs/TRACKING.md)"),
                        {"host", "gpu"}));
    s.push_back(choices(make("--track-downsample", "track_downsample", K::Tracking, text(t.downsample),
                             "track on the frames downsampled by 1, 2 or 4 (fusion keeps the full frames); 0 (default): 2 for frames at "
                             "least 640 pixels wide, else 1 (on 640x480 a quarter of the finest level's work at the same accuracy; "
                             "docs/TRACKING.md)"),
                        {"0", "1", "2", "4"}));
    s.push_back(range(make("--track-model-reuse", "track_model_reuse", K::Tracking, text(t.modelReuseFrames),
                           "let up to this many frames in a row (default 2) reuse the model maps (the mesh drawn at an earlier pose) "
                           "while the predicted pose is within 4 cm and 4 degrees of where they were drawn; 0 draws the mesh for "
                           "every frame"),
                      0, 1000));

    // --- kept frames, corrections, loop closure ---
    s.push_back(make("--keep-frames", "keep_frames", K::Correction, "false",
                     "keep every frame as fused (compressed) in a frame store saved beside the --save map (MAP.vkframes), so "
                     "that vkmesh correct can re-fuse frames whose poses change (the default with --save)"));
    s.push_back(make("--no-keep-frames", "", K::Correction, "false", "with --save: do not keep the frames (the map cannot be corrected later)"));
    s.push_back(positive(make("--frames-budget", "frames_budget_mb", K::Correction, text(FrameStoreOptions{}.memoryBudgetBytes >> 20),
                              "the frame store's memory budget in MiB (compressed frames)")));
    s.push_back(make("--frames-spill", "frames_spill", K::Correction, "",
                     "folder for the frames beyond --frames-budget (else the run stops there; the system's temporary folder when only "
                     "--track's default loop closure keeps them, without --save)"));
    s.push_back(make("--loop-closure", "loop_closure", K::Correction, "false",
                     "recognise places seen before (keyframes, random ferns), verify them by ICP, optimise a pose graph (Ceres) "
                     "and re-fuse the frames a loop moves; relocalise lost frames from the keyframes (docs/LOOP_CLOSURE.md). The "
                     "command line's --track does this by default; Python's loop_closure and the library's MapperOptions ask for it"));
    s.push_back(make("--no-loop-closure", "", K::Correction, "false",
                     "with --track: close no loops and relocalise no lost frame (tracking alone; no frames kept unless --save)"));
    s.push_back(make("--corrections-per-frame", "corrections_per_frame", K::Correction, text(m.correctionsPerFrame),
                     "with --loop-closure: frames a loop moved that are re-fused before each new frame (default 2; the rest "
                     "after the last frame)"));
    s.push_back(range(make("--loop-place-candidates", "loop_place_candidates", K::Correction, text(kDefaultLoopPlaceCandidates),
                           "with --loop-closure: old keyframes that the pose graph puts near a new keyframe (within the drift the "
                           "path allows, looking the same way) verified as loop candidates besides the ferns' (default 2; 0: the "
                           "ferns alone, a third of the loop closer's time where the camera stays in one place; docs/LOOP_CLOSURE.md)"),
                      0, 100));

    // --- instrumentation ---
    s.push_back(make("--no-stage-times", "", K::Instrumentation, "false",
                     "record no GPU timestamps between stages (~0.3-0.5 ms per frame on lavapipe); the summary and --stats then "
                     "have no GPU stage times, only wall times (-q without --stats records none either)"));
    s.push_back(make("--pass-times", "", K::Instrumentation, "false",
                     "also a GPU timestamp after every pass (compute dispatch) of a frame: --stats gains gpu_ms_per_pass, each "
                     "pass's time per frame by shader name (each timestamp costs ~50 us on lavapipe: for profiling)"));
    s.push_back(make("--analyse-mesh", "", K::Instrumentation, "false",
                     "also analyse the final mesh for --stats: the baseline's vertex count on the same TSDF (mesh.baseline_vertices, "
                     "vertices_vs_baseline), sliver triangles, irregular cubes, boundary and non-manifold edges, coincident "
                     "vertices (the paper's evaluation; without it these keys are null: ~0.3-0.8 s less per run)"));
    s.push_back(make("--quiet", "", K::Instrumentation, "false", "no progress line"));

    // --- outputs ---
    s.push_back(make("--output", "", K::Output, "", "mesh file (.ply binary, .obj or .glb binary glTF)"));
    // (0, 1], checked by the command with its own message (checkSimplifyRatio), not by the option parser.
    s.push_back(make("--simplify", "", K::Output, "1",
                     "write a simplified copy keeping about this fraction of the triangles, 0 < RATIO <= 1 (meshoptimizer; "
                     "its geometric error is reported; the fused mesh itself is not changed)"));
    s.push_back(make("--stats", "", K::Output, "", "write counts, timings and memory as JSON"));
    s.push_back(make("", "track_deltas", K::Output, text(false), "report each frame's mesh changes (deltas(), docs/DELTAS.md)"));
    s.push_back(make("--deltas", "", K::Output, "", "write every frame's mesh changes to this stream file (docs/DELTAS.md)"));
    s.push_back(positive(make("--render-every", "", K::Output, "", "write a picture of the mesh every N frames (drawn from the GPU buffers)")));
    s.push_back(make("--render-dir", "", K::Output, "", "folder for the --render-every pictures (frame_NNNNNN.png)"));
    s.push_back(choices(make("--render-view", "", K::Output, "sensor", "sensor: from the frame's camera; overview: framing the mesh so far"),
                        {"sensor", "overview"}));
    s.push_back(choices(make("--render-color", "", K::Output, "auto",
                             "shade, normal, age (warm = new, cold = old) or rgb (the fused colours); default: rgb when colour is "
                             "fused, else shade"),
                        {"shade", "normal", "age", "rgb", "auto"}));
    s.push_back(make("--save", "", K::Output, "", "write the whole state after the last frame to this map file (.vkmap, docs/MAPFILE.md)"));
    s.push_back(make("--load", "", K::Input, "",
                     "continue the map in this file (its settings unless given; with --first-frame, the frames it does not hold yet)"));
    s.push_back(make("--trajectory", "", K::Output, "",
                     "write the pose used for every frame (tracked or given) in TUM format: timestamp tx ty tz qx qy qz qw; with "
                     "--loop-closure the final poses, every loop's correction applied"));
    s.push_back(make("--trajectory-online", "", K::Output, "",
                     "with --track: write the poses as they were when each frame was fused (TUM format), before any loop's correction"));
    s.push_back(range(make("--serve", "", K::Output, "",
                           "serve the live browser viewer on this port while fusing (docs/VIEWER.md; open the URL it prints)"),
                      0, 65535));
    s.push_back(make("--host", "", K::Output, "127.0.0.1",
                     "address --serve listens on (default 127.0.0.1: this machine only; 0.0.0.0: every interface)"));
    s.push_back(make("--serve-linger", "", K::Output, "",
                     "with --serve: keep serving this many seconds after the last frame (default: until Ctrl-C; 0: stop at once)"));

    // --- the device ---
    s.push_back(make("--device", "device", K::Device, "", "Vulkan device index (see `vkmesh devices`); default: the first suitable one"));
    s.push_back(make("--validation", "validation", K::Device, "false", "enable the Khronos validation layer (or VKMESH_VALIDATION=1)"));
    return s;
}

}  // namespace

const char* toString(SettingKind kind) {
    switch (kind) {
        case SettingKind::Map: return "map";
        case SettingKind::Capacity: return "capacity";
        case SettingKind::Processing: return "processing";
        case SettingKind::Tracking: return "tracking";
        case SettingKind::Correction: return "correction";
        case SettingKind::Instrumentation: return "instrumentation";
        case SettingKind::Input: return "input";
        case SettingKind::Output: return "output";
        case SettingKind::Device: return "device";
    }
    return "?";
}

const std::vector<SettingDescription>& settingDescriptions() {
    static const std::vector<SettingDescription> all = describeAll();
    return all;
}

const SettingDescription& setting(std::string_view name) {
    for (const SettingDescription& d : settingDescriptions())
        if ((!d.cli.empty() && d.cli == name) || (!d.python.empty() && d.python == name)) return d;
    throw Error("no setting named '" + std::string(name) + "' (api/settings.cpp describes every one)");
}

std::string shortestText(float value) {
    char buffer[32];
    const auto r = std::to_chars(buffer, buffer + sizeof buffer, value);
    return std::string(buffer, r.ptr);
}

}  // namespace vkmesh
