#include "cpu/reference_volume.h"

#include <algorithm>

#include "core/camera.h"
#include "core/tsdf_corner.h"
#include "cpu/reference_allocation.h"
#include "cpu/reference_baseline.h"
#include "cpu/reference_fusion.h"

namespace vkmesh::cpu {

ReferenceVolume::ReferenceVolume(const VolumeParams& params, float minMeshWeight) : params_(params), minMeshWeight_(minMeshWeight) {}

void ReferenceVolume::setRecycling(float keepRadius, uint32_t starveAfterFrames, float starveWeight) {
    recycling_ = RecyclingRule{keepRadius, starveAfterFrames, starveWeight};
}

size_t ReferenceVolume::retypeCubeCount() const {
    size_t n = 0;
    for (const auto& [coord, mask] : retypeCubes_) n += mask.count();
    return n;
}

std::vector<BlockCoord> ReferenceVolume::blocksTouchedBy(const DepthImage& depth, const Intrinsics& intrinsics,
                                                         const Pose& cameraToWorld, ReferenceFrameStats* stats) const {
    AllocationStats allocation;
    std::vector<BlockCoord> touched = touchedBlocks(depth, intrinsics, cameraToWorld, params_, recycling_.keepRadius, &allocation);
    if (stats) {
        *stats = ReferenceFrameStats{};
        stats->validPixels = allocation.validPixels;
        stats->blockRequests = allocation.blockRequests;
        stats->touchedCount = allocation.touchedCount;
        stats->rayTruncated = allocation.rayTruncated;
        stats->outOfRange = allocation.outOfRange;
        stats->outsideRadius = allocation.outsideRadius;
    }
    return touched;
}

ReferenceFrameStats ReferenceVolume::integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                               const ColorImage* color) {
    // 1. Allocation: the blocks the frame's truncation bands cross.
    ReferenceFrameStats stats;
    std::vector<BlockCoord> touched = blocksTouchedBy(depth, intrinsics, cameraToWorld, &stats);

    // 2. Fusion of every touched block; a new block starts at sdf 0, weight 0.
    const gpu::FramePush push = makeFramePush(intrinsics, cameraToWorld, params_, 1);
    lastFlipped_.clear();
    lastObservedFlipped_.clear();
    lastDeintegrated_ = false;
    for (const BlockCoord& c : touched) {
        auto [it, inserted] = blocks_.try_emplace(c);
        if (inserted) ++stats.blocksInserted;
        const FusionCount count = fuseBlock(it->second, c, depth, push, fusionRule(), &lastFlipped_, color, false, &lastObservedFlipped_);
        stats.updatedVoxels += count.updated;
        stats.observationsDropped += count.dropped;
    }
    lastTouched_ = std::move(touched);

    // 3. Recycling (recycle_retire.comp, then recycle_free.comp after the mesh passes).
    ++frame_;
    if (recycling_.enabled()) {
        for (const BlockCoord& c : lastTouched_) lastTouchedFrame_[c] = frame_;
        const RecyclingStats recycled = recycleBlocks(blocks_, lastTouchedFrame_, frame_, recycling_, params_.voxelSize,
                                                      tsdfFixedPoint(params_.truncation()).metresPerStep, push.cameraToWorld);
        stats.blocksStarved = recycled.blocksStarved;
        stats.blocksRetired = recycled.blocksRetired;
        stats.blocksFreed = recycled.blocksFreed;
    }

    // 4. The cubes around every flipped corner, in the blocks that exist now.
    retypeCubes_ = cubesAroundCorners(lastFlipped_, blocks_);
    observedRetypeCubes_ = cubesAroundCorners(lastObservedFlipped_, blocks_);
    return stats;
}

FusionRule ReferenceVolume::fusionRule() const {
    return FusionRule{params_.voxelSize, params_.truncation(), minMeshWeight_, params_.colorFusion, params_.colorRecency};
}

ReferenceFrameStats ReferenceVolume::deintegrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                                 const ColorImage* color) {
    ReferenceFrameStats stats;
    std::vector<BlockCoord> touched = blocksTouchedBy(depth, intrinsics, cameraToWorld, &stats);
    const gpu::FramePush push = makeFramePush(intrinsics, cameraToWorld, params_, 1);
    lastFlipped_.clear();
    lastObservedFlipped_.clear();
    lastDeintegrated_ = true;
    std::vector<BlockCoord> found;
    for (const BlockCoord& c : touched) {
        auto it = blocks_.find(c);
        if (it == blocks_.end()) {
            ++stats.blocksMissing;
            continue;
        }
        const FusionCount count = fuseBlock(it->second, c, depth, push, fusionRule(), &lastFlipped_, color, true, &lastObservedFlipped_);
        stats.updatedVoxels += count.updated;
        stats.observationsDropped += count.dropped;
        found.push_back(c);
    }
    ++frame_;
    // The cubes around every flipped corner are marked while the emptied blocks still exist (the GPU marks them
    // in fusion, and frees the blocks after the mesh passes).
    retypeCubes_ = cubesAroundCorners(lastFlipped_, blocks_);
    observedRetypeCubes_ = cubesAroundCorners(lastObservedFlipped_, blocks_);
    for (const BlockCoord& c : found) {
        const ReferenceBlock& b = blocks_.at(c);
        if (std::all_of(b.weight.begin(), b.weight.end(), [](float w) { return w == 0.0f; })) {
            blocks_.erase(c);
            lastTouchedFrame_.erase(c);
            ++stats.blocksFreed;
        }
    }
    lastTouched_ = std::move(found);
    return stats;
}

std::vector<Eigen::Vector3f> ReferenceVolume::extractBaselineMesh() const {
    return baselineMesh(blocks_, params_.voxelSize, minMeshWeight_);
}

}  // namespace vkmesh::cpu
