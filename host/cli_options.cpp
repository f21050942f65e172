#include "cli_options.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>

#include "io/mesh_file.h"

namespace vkmesh::cli {

void DatasetArgs::add(CLI::App* cmd) {
    cmd->add_option("DATASET", dataset,
                    "dataset folder (TUM, ICL-NUIM, Redwood, 7-Scenes, a folder with camera.json) or recording (ROS 1 .bag, "
                    "RealSense .bag, .mcap, rosbag2 .db3 or folder)")
        ->required();
    cmd->add_option("--frames", frames, "use at most N frames (0 = all)");
    cmd->add_option("--max-depth", maxDepth, "ignore depth beyond M metres")->check(CLI::PositiveNumber);
    cmd->add_option("--intrinsics", intrinsics, "override the camera: fx,fy,cx,cy");
    cmd->add_option("--depth-scale", depthScale, "raw depth units per metre (5000 TUM, 1000 mm)")->check(CLI::PositiveNumber);
    cmd->add_option("--depth-topic", depthTopic, "recordings: the depth image topic (default: the one sensor_msgs/Image topic of depth)");
    cmd->add_option("--color-topic", colorTopic, "recordings: the colour image topic (default: the one of colour, if any)");
    cmd->add_option("--info-topic", infoTopic,
                    "recordings: the depth camera's sensor_msgs/CameraInfo topic (default: the one beside the depth topic)");
}

std::unique_ptr<Dataset> DatasetArgs::open() const {
    DatasetOptions options;
    if (!intrinsics.empty()) options.intrinsics = parseIntrinsics(intrinsics);
    if (depthScale > 0) options.depthScale = depthScale;
    options.maxDepth = maxDepth;
    options.maxFrames = frames;
    options.requirePoses = !posesOptional;
    options.depthTopic = depthTopic;
    options.colorTopic = colorTopic;
    options.infoTopic = infoTopic;
    return Dataset::open(dataset, options);
}

void VolumeOptions::addCommon(CLI::App* cmd) {
    cmd->add_option("--voxel", voxel, "voxel (cube) size in metres");
    cmd->add_option("--blocks", blocks, "initial block pool capacity (8x8x8 voxels each); grows when nearly full")->check(CLI::PositiveNumber);
    cmd->add_flag("--no-grow", noGrow,
                  "keep every capacity (--blocks, --vertices, --chunks, --hash-slots) fixed: what does not fit is reported "
                  "and skipped instead of grown past");
    cmd->add_option("--keep-radius", keepRadius,
                    "bounded map: keep only blocks within R metres of the camera; farther ones are not allocated and are "
                    "freed with their mesh (0 = off, the default)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_flag("--recycle", recycle,
                  "bounded map: blocks not seen for --recycle-after frames lose --starve-weight per frame and are freed "
                  "(with their mesh) once empty (off by default)");
    cmd->add_option("--recycle-after", recycleAfter, "frames without a touch before a block starves")->check(CLI::PositiveNumber);
    cmd->add_option("--starve-weight", starveWeight, "weight a starving block's corners lose per frame")
        ->check(CLI::PositiveNumber);
}

void VolumeOptions::addTuning(CLI::App* cmd) {
    cmd->add_option("--mode", mode,
                    "incremental: one shared-vertex mesh updated every frame (default); "
                    "baseline: marching cubes at the end, every triangle with its own 3 vertices")
        ->check(CLI::IsMember({"incremental", "baseline"}));
    cmd->add_flag("--refine,!--no-refine", refine,
                  "Hamming-distance refinement of cube types, decided per corner so the mesh has no cracks (paper "
                  "§V.F, docs/REFINEMENT.md; on by default, --no-refine turns it off)");
    cmd->add_option("--refine-eps", refineEps, "refinement: corners within this many voxels of the surface may flip")
        ->check(CLI::Range(0.0f, 1.0f));
    cmd->add_flag("--lock-free", lockFree, "claim edge vertices in 4 parity-class passes without atomics (paper's lock-free)");
    cmd->add_option("--vertices", vertices, "initial vertex heap capacity (grows when nearly full)")->check(CLI::PositiveNumber);
    cmd->add_option("--chunks", chunks, "initial triangle chunk heap capacity (5 triangles each; grows when nearly full)")->check(CLI::PositiveNumber);
    cmd->add_option("--hash-slots", hashSlots, "initial spatial hash capacity, a power of two (0 = 2x --blocks; grows when half full)");
    cmd->add_option("--trunc", truncVoxels, "truncation distance in voxels");
    // Deprecated (map version 2): fusion keeps exact integer sums, which a cap would make impossible to undo.
    cmd->add_option("--max-weight", maxWeight, "deprecated, no effect: fusion keeps exact sums (docs/CORRECTION.md)")
        ->each([](const std::string&) {
            std::cerr << "vkmesh: --max-weight is deprecated and has no effect: the TSDF keeps exact sums of every "
                         "observation so that frames can be taken out again (docs/CORRECTION.md)\n";
        });
    cmd->add_option("--min-weight", minWeight, "a cube is meshed when its 8 corners have at least this weight")
        ->check(CLI::Range(1.0f, 255.0f));
    cmd->add_option("--alloc-stride", allocStride,
                    "allocate blocks from every Nth pixel in x and y (1 = every pixel, as the paper; Open3D uses 4)")
        ->check(CLI::Range(1, 64));
    cmd->add_flag("--alloc-tiles", allocTiles,
                  "allocation by tiles (the default): claim the blocks around the plane of a tile of 8 x 8 sampled pixels "
                  "where one fits, instead of walking each pixel's truncation band (a few percent more blocks, less "
                  "allocation work)");
    cmd->add_flag("--alloc-pixels", allocPixels,
                  "allocation pixel by pixel: every sampled pixel walks its truncation band (the default before "
                  "2026-12-05; maps fused that way keep it)")
        ->excludes("--alloc-tiles");
    cmd->add_flag("--no-color", noColor, "fuse depth only, even when the dataset has colour images (4 bytes per cube less)");
    cmd->add_option("--color-mode", colorMode,
                    "average: running average of the colour with the TSDF's weights (default); recent: exponential "
                    "average that follows lighting changes (--color-recency)")
        ->check(CLI::IsMember({"average", "recent"}));
    cmd->add_option("--color-recency", colorRecency, "--color-mode recent: share of the newest colour, in (0, 1]")
        ->check(CLI::Range(0.001f, 1.0f));
}

gpu::GpuVolumeConfig VolumeOptions::toConfig(float maxDepth, int width, int height, bool inputHasColor) const {
    gpu::GpuVolumeConfig config;
    config.params.voxelSize = voxel;
    config.params.truncVoxels = truncVoxels;
    config.params.maxWeight = maxWeight;
    config.params.maxDepth = maxDepth;
    config.params.allocationStride = allocStride;
    config.params.allocationTiles = allocTiles && !allocPixels;
    config.minMeshWeight = minWeight;
    config.meshMode = incremental() ? gpu::MeshMode::Incremental : gpu::MeshMode::Baseline;
    config.refine = refine;
    config.refineEpsilonVoxels = refineEps;
    config.lockFree = lockFree;
    config.blockCapacity = blocks;
    config.vertexCapacity = vertices;
    config.chunkCapacity = chunks;
    config.hashCapacity = hashSlots;
    config.keepRadius = keepRadius;
    config.recycle = recycle;
    config.recycleAfterFrames = recycleAfter;
    config.starveWeight = starveWeight;
    config.growCapacities = !noGrow;
    config.imageWidth = width;
    config.imageHeight = height;
    config.params.colorFusion = !inputHasColor || noColor ? ColorFusion::Off
                                : colorMode == "recent"   ? ColorFusion::Recent
                                                          : ColorFusion::Average;
    config.params.colorRecency = colorRecency;
    return config;
}

void DeviceArgs::add(CLI::App* cmd) {
    cmd->add_option("--device", device, "Vulkan device index (see `vkmesh devices`)");
    cmd->add_flag("--validation", validation, "enable the Khronos validation layer (or VKMESH_VALIDATION=1)");
}

void MeshOutputArgs::add(CLI::App* cmd) {
    cmd->add_option("-o,--output", path, "mesh file (.ply binary, .obj or .glb binary glTF)")->required();
    cmd->add_option("--simplify", simplify,
                    "write a simplified copy keeping about this fraction of the triangles, 0 < RATIO <= 1 (meshoptimizer; "
                    "its geometric error is reported; the fused mesh itself is not changed)");
}

void MeshOutputArgs::check() const {
    meshFormatOf(path);
    checkSimplifyRatio(simplify, "--simplify");
}

std::optional<SimplifyReport> MeshOutputArgs::write(const Mesh& mesh) const {
    if (!simplifying()) {
        writeMesh(path, mesh);
        return std::nullopt;
    }
    SimplifyReport report;
    writeMesh(path, simplifyMesh(mesh, simplify, &report));
    return report;
}

std::string describe(const SimplifyReport& r) {
    char line[200];
    std::snprintf(line, sizeof line, "simplified to %zu of %zu triangles (--simplify %g), geometric error %.2f mm", r.trianglesAfter,
                  r.trianglesBefore, r.ratio, 1000 * r.errorMetres);
    return line;
}

}  // namespace vkmesh::cli
