#include "cpu/reference_fusion.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

#include "core/marching_cubes.h"
#include "core/tsdf_corner.h"
#include "core/voxel_color.h"

namespace vkmesh::cpu {

using gpu::BLOCK_SIDE;
using gpu::VOXELS_PER_BLOCK;

bool cornerFlipped(float oldSdf, float oldWeight, float newSdf, float newWeight, const FusionRule& rule) {
    const bool wasObserved = oldWeight >= rule.minMeshWeight, isObserved = newWeight >= rule.minMeshWeight;
    return wasObserved != isObserved || (isObserved && (oldSdf < 0.0f) != (newSdf < 0.0f));
}

FusionCount fuseBlock(ReferenceBlock& block, const BlockCoord& c, const DepthImage& depth, const gpu::FramePush& push,
                      const FusionRule& rule, std::vector<std::array<int, 3>>* flipped, const ColorImage* color, bool deintegrate,
                      std::vector<std::array<int, 3>>* observedFlipped) {
    const bool withColor = rule.colorFusion != ColorFusion::Off && color && !color->empty();
    const float fx = push.intrinsics[0], fy = push.intrinsics[1], cx = push.intrinsics[2], cy = push.intrinsics[3];
    const float truncation = rule.truncation;
    const TsdfFixedPoint fixed = tsdfFixedPoint(truncation);
    const int side = int(BLOCK_SIDE);
    FusionCount count;
    for (uint32_t v = 0; v < VOXELS_PER_BLOCK; ++v) {
        const auto [lx, ly, lz] = localCoords(v);
        Eigen::Vector3f world(float(c[0] * side + lx) * rule.voxelSize, float(c[1] * side + ly) * rule.voxelSize,
                              float(c[2] * side + lz) * rule.voxelSize);
        Eigen::Vector3f cam = transformRows(push.worldToCamera, world);
        if (!(cam.z() > 0.0f)) continue;
        float u = (cam.x() * fx) / cam.z() + cx;
        float w = (cam.y() * fy) / cam.z() + cy;
        float pu = std::floor(u + 0.5f), pv = std::floor(w + 0.5f);
        if (!(pu >= 0.0f && pv >= 0.0f && pu < float(depth.width) && pv < float(depth.height))) continue;
        float d = depth.at(int(pu), int(pv));
        float sdf = d - cam.z();
        if (!(d >= push.minDepth && d <= push.maxDepth && sdf >= -truncation)) continue;
        const int32_t steps = tsdfSteps(std::min(sdf, truncation), fixed.stepsPerMetre);
        const int32_t oldSum = block.sdfSum[v];
        const float oldSdf = block.sdf[v], oldWeight = block.weight[v];
        const bool applies = deintegrate ? oldWeight >= 1.0f : oldWeight < float(gpu::SDF_MAX_COUNT);
        if (!applies) {
            ++count.dropped;
            continue;
        }
        const float newWeight = deintegrate ? oldWeight - 1.0f : oldWeight + 1.0f;
        const int32_t newSum = newWeight == 0.0f ? 0 : (deintegrate ? oldSum - steps : oldSum + steps);
        const float newSdf = tsdfMean(newSum, newWeight, fixed.metresPerStep);
        block.sdfSum[v] = newSum;
        block.sdf[v] = newSdf;
        block.weight[v] = newWeight;
        ++count.updated;
        const std::array<int, 3> corner{c[0] * side + lx, c[1] * side + ly, c[2] * side + lz};
        if (withColor) {
            const uint8_t* rgb = color->at(int(pu), int(pv));
            const auto mode = uint32_t(rule.colorFusion);
            block.color[v] = !deintegrate ? foldVoxelColor(block.color[v], oldWeight, newSdf, rgb, corner, mode, rule.colorRecency)
                             : newWeight == 0.0f ? 0u : unfoldVoxelColor(block.color[v], oldWeight, newSdf, rgb, corner, mode);
        } else if (deintegrate && newWeight == 0.0f) {
            block.color[v] = 0;
        }
        // Corners not updated keep their values and never flip.
        if (flipped && cornerFlipped(oldSdf, oldWeight, newSdf, newWeight, rule)) flipped->push_back(corner);
        if (observedFlipped && (oldWeight >= rule.minMeshWeight) != (newWeight >= rule.minMeshWeight)) observedFlipped->push_back(corner);
    }
    return count;
}

std::map<BlockCoord, CubeMask> cubesAroundCorners(const std::vector<std::array<int, 3>>& flipped,
                                                  const std::map<BlockCoord, ReferenceBlock>& blocks) {
    std::map<BlockCoord, CubeMask> cubes;
    const int side = int(BLOCK_SIDE);
    for (const auto& g : flipped) {
        for (int o = 0; o < 8; ++o) {
            const std::array<int, 3> off{o & 1, (o >> 1) & 1, (o >> 2) & 1};
            const int x = g[0] - off[0], y = g[1] - off[1], z = g[2] - off[2];
            const BlockCoord b{blockOf(x), blockOf(y), blockOf(z)};
            if (!blocks.count(b)) continue;
            cubes[b].set(localIndex(x - b[0] * side, y - b[1] * side, z - b[2] * side));
        }
    }
    return cubes;
}

}  // namespace vkmesh::cpu
