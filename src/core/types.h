// Plain value types shared by every part of vkmesh (I/O, CPU reference, GPU pipeline, CLI).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace vkmesh {

// Every error vkmesh reports to a user: the message names the file, value or Vulkan call at fault.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Pinhole camera. fy may be negative (ICL-NUIM's TUM-compatible release uses fy = -480 with its poses).
struct Intrinsics {
    float fx = 0, fy = 0, cx = 0, cy = 0;
    int width = 0, height = 0;
};

// Camera-to-world rigid transform (the convention of TUM, ICL-NUIM, Redwood and 7-Scenes files).
using Pose = Eigen::Matrix4d;

// A depth image in metres, row-major, 0 where the sensor gave no measurement.
struct DepthImage {
    int width = 0, height = 0;
    std::vector<float> meters;
    float at(int x, int y) const { return meters[static_cast<size_t>(y) * width + x]; }
};

// An 8-bit RGB image registered to the depth image it came with (same size, same pixel grid), row-major,
// 3 bytes a pixel (red, green, blue). Empty when a frame has no usable colour.
struct ColorImage {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;
    bool empty() const { return rgb.empty(); }
    const uint8_t* at(int x, int y) const { return &rgb[(static_cast<size_t>(y) * width + x) * 3]; }
};

// How fusion folds colour into the corners (docs/COLOR.md); the values are gpu::COLOR_MODE_*.
enum class ColorFusion : uint32_t {
    Off = 0,      // depth only: no colour buffer, grey meshes
    Average = 1,  // running average with the TSDF's weight (as Open3D, InfiniTAM and the paper's code)
    Recent = 2,   // exponential average, c' = c + colorRecency (new - c): follows lighting changes (as nvblox)
};

// Parameters of the TSDF volume, identical for the GPU pipeline and the CPU reference.
struct VolumeParams {
    float voxelSize = 0.03f;       // metres between two TSDF samples (cube side)
    float truncVoxels = 4.0f;      // truncation distance in voxels: trunc = truncVoxels * voxelSize
    // Deprecated, no effect: the cap of the running-average weight before fusion kept exact sums (map version 2;
    // shared_layout.h "A TSDF corner"). Kept so that code and map files that set it still build and load.
    float maxWeight = 255.0f;
    float minDepth = 0.1f;         // depth samples outside [minDepth, maxDepth] are ignored
    float maxDepth = 5.0f;
    // Block allocation walks the truncation bands of every Nth pixel in x and y; fusion always uses
    // every pixel. 1 follows the paper (every valid pixel); Open3D's VoxelBlockGrid uses 4. 2 costs a
    // quarter of 1 and changes under 0.1 % of the baseline triangles on the real datasets (docs/RESULTS.md).
    int allocationStride = 2;
    // Allocation by tiles (shaders_comp/allocate/allocate_tiles.comp; the default since 2026-12-05, `fuse
    // --alloc-pixels` turns it off): where a plane fits a tile of 8 x 8 sampled pixels, the blocks of the slab around
    // it are claimed at once, a superset of what the tile's band walks claim; the other tiles' pixels walk their
    // bands. On lavapipe a frame is 1-11 % faster than walking every sampled pixel on the synthetic room and TUM, and
    // even on ICL-NUIM (the extra blocks, +4-8 %, cost fusion about what the walks they save cost); the mesh's
    // accuracy and completeness against ground truth are the same (docs/RESULTS.md). false: every sampled pixel walks its band (maps written before tiles keep that).
    bool allocationTiles = true;
    // Which rules decide the tiles a plane covers (shared_layout.h, ALLOC_TILE_RULES): the current ones (2) for a new
    // volume; a loaded map's own (1 for maps written with the first rules), so that its frames de-integrate from the
    // blocks they were fused into. Not a user setting.
    int allocationTileRules = 2;
    // Colour: frames that come with a colour image fold it into the corners they update (same weights);
    // frames without one fuse depth only. Off allocates no colour (4 bytes per corner less).
    ColorFusion colorFusion = ColorFusion::Average;
    float colorRecency = 0.2f;     // ColorFusion::Recent: the share of the newest colour, in (0, 1]
    float truncation() const { return truncVoxels * voxelSize; }
};

}  // namespace vkmesh
