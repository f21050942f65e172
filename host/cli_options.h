// Options more than one subcommand takes, each registered and mapped in one place:
//   DatasetArgs    DATASET --frames --max-depth --intrinsics --depth-scale --depth-topic --color-topic --info-topic
//                  (frames, fuse) -> Dataset::open
//   VolumeOptions  --voxel --blocks, bounded maps; fuse adds the tuning ones  (fuse, soak)  -> GpuVolumeConfig
//   DeviceArgs     --device --validation                                     (fuse, render, soak) -> vk::Context
//   MeshOutputArgs -o --simplify                                             (fuse, export) -> writeMesh
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "api/settings.h"
#include "gpu/gpu_volume.h"
#include "io/dataset.h"
#include "io/mesh_simplify.h"
#include "vk/context.h"

namespace CLI {
class App;
class Option;
}

namespace vkmesh::cli {

struct DatasetArgs {
    std::string dataset;
    size_t frames = 0;
    float maxDepth = kDefaultMaxDepth;
    std::string intrinsics;
    double depthScale = 0;
    std::string depthTopic, colorTopic, infoTopic;  // recordings: which topics, when the types do not tell
    // Frames without a camera pose are kept (the camera is tracked): a dataset without pose files opens.
    bool posesOptional = false;

    void add(CLI::App* cmd);
    std::unique_ptr<Dataset> open() const;
};

// The GPU volume's options. The defaults are GpuVolumeConfig's, so a command that offers only some of them
// (soak) gets the library's values for the rest; a command may change a default before add*().
struct VolumeOptions {
    std::string mode = "incremental";   // "incremental" or "baseline"
    float voxel = VolumeParams{}.voxelSize;
    float truncVoxels = VolumeParams{}.truncVoxels;
    float maxWeight = VolumeParams{}.maxWeight;
    float minWeight = gpu::GpuVolumeConfig{}.minMeshWeight;
    int allocStride = VolumeParams{}.allocationStride;
    bool allocTiles = VolumeParams{}.allocationTiles;
    bool allocPixels = false;   // --alloc-pixels: allocTiles off
    bool refine = gpu::GpuVolumeConfig{}.refine;
    float refineEps = gpu::GpuVolumeConfig{}.refineEpsilonVoxels;
    bool lockFree = gpu::GpuVolumeConfig{}.lockFree;
    uint32_t blocks = gpu::GpuVolumeConfig{}.blockCapacity;
    uint32_t residentBlocks = 0;   // --resident-blocks: paging (docs/PAGING.md)
    uint32_t vertices = gpu::GpuVolumeConfig{}.vertexCapacity;
    uint32_t chunks = gpu::GpuVolumeConfig{}.chunkCapacity;
    uint32_t hashSlots = gpu::GpuVolumeConfig{}.hashCapacity;   // 0: twice the block capacity, a power of two
    float keepRadius = gpu::GpuVolumeConfig{}.keepRadius;
    bool recycle = gpu::GpuVolumeConfig{}.recycle;
    uint32_t recycleAfter = gpu::GpuVolumeConfig{}.recycleAfterFrames;
    float starveWeight = gpu::GpuVolumeConfig{}.starveWeight;
    bool noGrow = !gpu::GpuVolumeConfig{}.growCapacities;
    bool noColor = false;                  // --no-color: depth only even when the dataset has colour
    std::string colorMode = "average";     // --color-mode average|recent
    float colorRecency = VolumeParams{}.colorRecency;

    // --voxel, --blocks, --no-grow and the bounded-map options (--keep-radius, --recycle, --recycle-after,
    // --starve-weight).
    void addCommon(CLI::App* cmd);
    // The rest (fuse): --mode, --refine, --refine-eps, --lock-free, --vertices, --chunks, --hash-slots,
    // --trunc, --max-weight, --min-weight, --alloc-stride, --alloc-tiles, --alloc-pixels, --no-color, --color-mode, --color-recency.
    void addTuning(CLI::App* cmd);

    bool incremental() const { return mode != "baseline"; }
    // The volume configuration for images of width x height, depth used up to maxDepth metres; colour is
    // fused (colorMode) when the input has colour and --no-color was not given.
    gpu::GpuVolumeConfig toConfig(float maxDepth, int width, int height, bool inputHasColor = false) const;
};

struct DeviceArgs {
    int device = -1;
    bool validation = false;

    void add(CLI::App* cmd);
    vk::ContextOptions contextOptions() const { return {device, validation}; }
};

// The mesh a command writes: -o (.ply, .obj or .glb, io/mesh_file.h) and --simplify RATIO (a simplified copy is
// written; the mesh on the GPU is never changed).
struct MeshOutputArgs {
    std::string path;
    double simplify = 1;   // the fraction of triangles to keep; 1: the mesh as it is

    void add(CLI::App* cmd);
    // Throws Error for an unknown extension or a ratio outside (0, 1]: called before any work, so that a typo does not
    // surface after a long fusion.
    void check() const;
    bool simplifying() const { return simplify != 1; }
    // Writes the mesh, simplified when --simplify was given (then returns what simplification did).
    std::optional<SimplifyReport> write(const Mesh& mesh) const;
};

// Registers a setting described in api/settings.h under the CLI11 `names` ("--refine,!--no-refine", "-q,--quiet"):
// the description of the first long name gives the help, the range or choices, and for a deprecated setting the
// message printed when it is given. Throws Error for a name no description has (a test registers every command).
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, float& value);
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, double& value);
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, int& value);
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, uint32_t& value);
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, size_t& value);
CLI::Option* addSetting(CLI::App* cmd, const std::string& names, std::string& value);
CLI::Option* addSettingFlag(CLI::App* cmd, const std::string& names, bool& value);

// One line for the command's summary: "simplified to T of T0 triangles (--simplify R), geometric error E mm".
std::string describe(const SimplifyReport& report);

}  // namespace vkmesh::cli
