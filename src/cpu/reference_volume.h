// The CPU reference of vkmesh's GPU stages: block allocation along truncation bands, TSDF fusion and
// the baseline marching-cubes mesh, written serially and plainly, with the same float operations in
// the same order as the shaders (shaders_comp/*.comp), so tests can compare GPU and CPU results
// value for value. It is also the readable statement of what each stage computes.
#pragma once

#include <Eigen/Core>

#include <array>
#include <map>
#include <vector>

#include "core/types.h"
#include "shared_layout.h"

namespace vkmesh::cpu {

using BlockCoord = std::array<int, 3>;

struct ReferenceBlock {
    std::array<float, gpu::VOXELS_PER_BLOCK> sdf{};
    std::array<float, gpu::VOXELS_PER_BLOCK> weight{};
};

// What one frame did; the fields mean the same as the GPU's Counters of the same names.
struct ReferenceFrameStats {
    uint32_t validPixels = 0;
    uint32_t blockRequests = 0;
    uint32_t blocksInserted = 0;
    uint32_t touchedCount = 0;
    uint32_t updatedVoxels = 0;
    uint32_t rayTruncated = 0;
};

class ReferenceVolume {
public:
    explicit ReferenceVolume(const VolumeParams& params, float minMeshWeight = 1.0f);

    ReferenceFrameStats integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld);

    // Blocks in coordinate order.
    const std::map<BlockCoord, ReferenceBlock>& blocks() const { return blocks_; }

    // Blocks whose truncation band a pixel of the image crosses (the allocation stage alone).
    std::vector<BlockCoord> blocksTouchedBy(const DepthImage& depth, const Intrinsics& intrinsics,
                                            const Pose& cameraToWorld, ReferenceFrameStats* stats = nullptr) const;

    // Baseline mesh: every cube's triangles with 3 vertices of their own (a triangle soup).
    std::vector<Eigen::Vector3f> extractBaselineMesh() const;

    // The blocks touched by the last integrate() call (allocation order), what the incremental mesh marks dirty.
    const std::vector<BlockCoord>& lastTouched() const { return lastTouched_; }

private:
    VolumeParams params_;
    float minMeshWeight_;
    std::map<BlockCoord, ReferenceBlock> blocks_;
    std::vector<BlockCoord> lastTouched_;
};

}  // namespace vkmesh::cpu
