// The CPU reference of block allocation (shaders_comp/allocate/, paper §V.A): with VolumeParams::allocationTiles,
// every tile of 8 x 8 sampled pixels whose depths a plane fits claims the blocks of the slab around it
// (allocate_tiles.comp); every other valid pixel (of every allocationStride-th row and column) walks the blocks its
// truncation band crosses, a 3D DDA in block units from depth d - trunc to d + trunc along the pixel's ray
// (allocate_blocks.comp). The shaders' float operations.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <vector>

#include "core/camera.h"
#include "core/types.h"
#include "cpu/reference_block.h"
#include "cpu/reference_hash.h"

namespace vkmesh::cpu {

// The Amanatides & Woo walk of allocate_blocks.comp from a to b (block units), calling visit for every
// block it enters, a's first. Returns false when the walk was cut at RAY_MAX_BLOCKS blocks.
bool walkBand(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const std::function<void(const BlockCoord&)>& visit);

// allocate_tiles.comp for the tile whose first and last samples are (firstX, firstY) and (lastX, lastY) (pixels):
// where a plane fits the tile's valid depths, calls visit for every block the slab around it may cross (a
// superset of the blocks its samples' band walks visit), adds the valid samples to *validSamples and returns
// true; else visits nothing and returns false (the samples walk their bands). The shader's float operations.
bool walkTileSlab(const DepthImage& depth, const gpu::FramePush& push, const VolumeParams& params, int firstX, int firstY,
                  int lastX, int lastY, const std::function<void(const BlockCoord&)>& visit, uint32_t* validSamples);

// What the allocation stage counted; the fields mean the same as the GPU's Counters of the same names.
struct AllocationStats {
    uint32_t validPixels = 0;
    uint32_t blockRequests = 0;  // block visits of all band walks
    uint32_t outOfRange = 0;     //  ... beyond the block key range
    uint32_t outsideRadius = 0;  //  ... beyond the keep radius (not allocated)
    uint32_t rayTruncated = 0;
    uint32_t touchedCount = 0;   // distinct blocks touched
    // With a hash table only (touchedBlocks' `hash`): the insertions' outcomes.
    uint32_t blocksFound = 0, blocksInserted = 0, hashFull = 0;
};

// The distinct blocks the frame's tiles and bands cross, in first-visit order (covered tiles, then the other pixels,
// each in raster order), leaving out
// blocks beyond the key range and beyond keepRadius (> 0) from the camera. With `hash`, every visit inserts
// its key there (allocate_blocks.comp's insertKey) and stamps the slot with frameNumber, and a block whose
// key finds no slot (hash full) is not touched.
std::vector<BlockCoord> touchedBlocks(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                      const VolumeParams& params, float keepRadius, AllocationStats* stats = nullptr,
                                      ReferenceHash* hash = nullptr, uint32_t frameNumber = 1);

}  // namespace vkmesh::cpu
