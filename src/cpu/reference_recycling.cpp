#include "cpu/reference_recycling.h"

#include <algorithm>

#include "core/tsdf_corner.h"

namespace vkmesh::cpu {

bool blockOutsideKeepRadius(const BlockCoord& c, float voxelSize, float keepRadius, const float cameraToWorld[3][4]) {
    if (!(keepRadius > 0.0f)) return false;
    const float blockSize = voxelSize * float(gpu::BLOCK_SIDE);
    float distance2 = 0.0f;
    for (int k = 0; k < 3; ++k) {
        const float centre = (float(c[k]) + 0.5f) * blockSize;
        const float d = centre - cameraToWorld[k][3];
        distance2 = k == 0 ? d * d : distance2 + d * d;
    }
    return distance2 > keepRadius * keepRadius;
}

RecyclingStats recycleBlocks(std::map<BlockCoord, ReferenceBlock>& blocks, std::map<BlockCoord, uint32_t>& lastTouchedFrame,
                             uint32_t frame, const RecyclingRule& rule, float voxelSize, float metresPerStep,
                             const float cameraToWorld[3][4]) {
    RecyclingStats stats;
    if (!rule.enabled()) return stats;
    for (auto it = blocks.begin(); it != blocks.end();) {
        const bool retire = blockOutsideKeepRadius(it->first, voxelSize, rule.keepRadius, cameraToWorld);
        const bool starve = !retire && rule.starveAfterFrames > 0 && frame - lastTouchedFrame[it->first] >= rule.starveAfterFrames;
        if (!retire && !starve) {
            ++it;
            continue;
        }
        ++(retire ? stats.blocksRetired : stats.blocksStarved);
        bool empty = true;
        ReferenceBlock& b = it->second;
        for (uint32_t v = 0; v < gpu::VOXELS_PER_BLOCK; ++v) {
            const float oldWeight = b.weight[v];
            const float newWeight = retire ? 0.0f : std::max(oldWeight - rule.starveWeight, 0.0f);
            if (newWeight != oldWeight) {
                b.sdfSum[v] = starvedSum(b.sdfSum[v], oldWeight, newWeight);
                b.weight[v] = newWeight;
                b.sdf[v] = tsdfMean(b.sdfSum[v], newWeight, metresPerStep);
            }
            empty = empty && newWeight == 0.0f;
        }
        if (!empty) {
            ++it;
            continue;
        }
        ++stats.blocksFreed;
        lastTouchedFrame.erase(it->first);
        it = blocks.erase(it);
    }
    return stats;
}

}  // namespace vkmesh::cpu
