#include "cpu/reference_allocation.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/camera.h"
#include "cpu/reference_recycling.h"

namespace vkmesh::cpu {

bool walkBand(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const std::function<void(const BlockCoord&)>& visit) {
    Eigen::Vector3f dir = b - a;
    BlockCoord cell{int(std::floor(a.x())), int(std::floor(a.y())), int(std::floor(a.z()))};
    BlockCoord last{int(std::floor(b.x())), int(std::floor(b.y())), int(std::floor(b.z()))};
    int step[3];
    float tMax[3], tDelta[3];
    for (int k = 0; k < 3; ++k) {
        step[k] = dir[k] > 0.0f ? 1 : (dir[k] < 0.0f ? -1 : 0);
        if (dir[k] > 0.0f) {
            tMax[k] = (std::floor(a[k]) + 1.0f - a[k]) / dir[k];
            tDelta[k] = 1.0f / dir[k];
        } else if (dir[k] < 0.0f) {
            tMax[k] = (a[k] - std::floor(a[k])) / -dir[k];
            tDelta[k] = 1.0f / -dir[k];
        } else {
            tMax[k] = 1e30f;
            tDelta[k] = 1e30f;
        }
    }
    for (uint32_t s = 0; s < gpu::RAY_MAX_BLOCKS; ++s) {
        visit(cell);
        if (cell == last) return true;
        int axis = (tMax[0] <= tMax[1] && tMax[0] <= tMax[2]) ? 0 : (tMax[1] <= tMax[2] ? 1 : 2);
        if (tMax[axis] > 1.0f) return true;
        cell[axis] += step[axis];
        tMax[axis] += tDelta[axis];
    }
    return false;
}

std::vector<BlockCoord> touchedBlocks(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                      const VolumeParams& params, float keepRadius, AllocationStats* stats,
                                      ReferenceHash* hash, uint32_t frameNumber) {
    const gpu::FramePush push = makeFramePush(intrinsics, cameraToWorld, params, 1);
    const float fx = push.intrinsics[0], fy = push.intrinsics[1], cx = push.intrinsics[2], cy = push.intrinsics[3];
    const float truncation = params.truncation();
    const float blockSize = params.voxelSize * float(gpu::BLOCK_SIDE);
    std::set<BlockCoord> seen;
    std::vector<BlockCoord> order;
    AllocationStats local;
    const int stride = params.allocationStride;
    for (int y = 0; y < depth.height; y += stride) {
        for (int x = 0; x < depth.width; x += stride) {
            float d = depth.at(x, y);
            if (!(d >= push.minDepth && d <= push.maxDepth)) continue;
            ++local.validPixels;
            Eigen::Vector3f ray((float(x) - cx) / fx, (float(y) - cy) / fy, 1.0f);
            float nearZ = std::max(d - truncation, push.minDepth * 0.5f);
            float farZ = d + truncation;
            Eigen::Vector3f a = transformRows(push.cameraToWorld, Eigen::Vector3f(ray * nearZ)) / blockSize;
            Eigen::Vector3f b = transformRows(push.cameraToWorld, Eigen::Vector3f(ray * farZ)) / blockSize;
            bool complete = walkBand(a, b, [&](const BlockCoord& c) {
                ++local.blockRequests;
                if (!blockCoordInRange(c)) {
                    ++local.outOfRange;
                    return;
                }
                if (blockOutsideKeepRadius(c, params.voxelSize, keepRadius, push.cameraToWorld)) {
                    ++local.outsideRadius;
                    return;
                }
                if (hash) {
                    const HashInsertResult r = hash->insert(c);
                    if (r.outcome == HashInsert::Full) {
                        ++local.hashFull;
                        return;
                    }
                    ++(r.outcome == HashInsert::Found ? local.blocksFound : local.blocksInserted);
                    hash->setStamp(r.slot, frameNumber);
                }
                if (seen.insert(c).second) order.push_back(c);
            });
            if (!complete) ++local.rayTruncated;
        }
    }
    local.touchedCount = static_cast<uint32_t>(order.size());
    if (stats) *stats = local;
    return order;
}

}  // namespace vkmesh::cpu
