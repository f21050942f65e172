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

namespace {

Eigen::Vector2f rayOf(int x, int y, float fx, float fy, float cx, float cy) { return {(float(x) - cx) / fx, (float(y) - cy) / fy}; }

// allocate_tiles.comp's boxOutside, planeToBlocks and sideNormal, with its float operations in its order.
bool boxOutside(const Eigen::Vector3f& c, const Eigen::Vector4f& plane) {
    const float high = plane.x() * c.x() + plane.y() * c.y() + plane.z() * c.z() + std::max(plane.x(), 0.0f) +
                       std::max(plane.y(), 0.0f) + std::max(plane.z(), 0.0f);
    const float bound = plane.w() - gpu::ALLOC_SLAB_MARGIN * (std::abs(plane.x()) + std::abs(plane.y()) + std::abs(plane.z()));
    return high < bound;
}

Eigen::Vector4f planeToBlocks(const float cameraToWorld[3][4], const Eigen::Vector3f& n, float o, const Eigen::Vector3f& origin,
                              float blockSize) {
    const Eigen::Vector3f nw = transformRows(cameraToWorld, n) - origin;
    const float ow = (o + (nw.x() * origin.x() + nw.y() * origin.y() + nw.z() * origin.z())) / blockSize;
    return {nw.x(), nw.y(), nw.z(), ow};
}

Eigen::Vector3f sideNormal(const Eigen::Vector2f& e, const Eigen::Vector2f& f) {
    return {e.y() - f.y(), f.x() - e.x(), e.x() * f.y() - f.x() * e.y()};
}

}  // namespace

bool walkTileSlab(const DepthImage& depth, const gpu::FramePush& push, const VolumeParams& params, int firstX, int firstY,
                  int lastX, int lastY, const std::function<void(const BlockCoord&)>& visit, uint32_t* validSamples) {
    const float fx = push.intrinsics[0], fy = push.intrinsics[1], cx = push.intrinsics[2], cy = push.intrinsics[3];
    const int stride = params.allocationStride;
    const uint32_t side = gpu::ALLOC_TILE;
    auto sample = [&](uint32_t j, int& x, int& y) {
        x = firstX + int(j % side) * stride;
        y = firstY + int(j / side) * stride;
        return x <= lastX && y <= lastY;
    };
    auto validDepth = [&](float d) { return d >= push.minDepth && d <= push.maxDepth; };
    const Eigen::Vector2f ray0 = rayOf(firstX, firstY, fx, fy, cx, cy);
    const float d0 = depth.at(firstX, firstY);
    const Eigen::Vector3f origin0(ray0.x() * d0, ray0.y() * d0, 1.0f * d0);
    uint32_t n = 0;
    Eigen::Vector3f s1(0.0f, 0.0f, 0.0f);
    float sxx = 0.0f, sxy = 0.0f, syy = 0.0f, sxz = 0.0f, syz = 0.0f;
    for (uint32_t j = 0; j < side * side; ++j) {
        int x, y;
        if (!sample(j, x, y)) continue;
        const float d = depth.at(x, y);
        if (!validDepth(d)) continue;
        ++n;
        const Eigen::Vector2f ray = rayOf(x, y, fx, fy, cx, cy);
        const Eigen::Vector3f p(ray.x() * d - origin0.x(), ray.y() * d - origin0.y(), d - origin0.z());
        s1 = Eigen::Vector3f(s1.x() + p.x(), s1.y() + p.y(), s1.z() + p.z());
        sxx += p.x() * p.x(), sxy += p.x() * p.y(), syy += p.y() * p.y(), sxz += p.x() * p.z(), syz += p.y() * p.z();
    }
    const bool firstRules = params.allocationTileRules == int(gpu::ALLOC_TILE_RULES_FIRST);
    if (n == 0 && !firstRules) return true;   // nothing for the pixels to walk either
    if (n < gpu::ALLOC_TILE_MIN_VALID) return false;
    Eigen::Vector3f mean(s1.x() / float(n), s1.y() / float(n), s1.z() / float(n));
    sxx -= s1.x() * mean.x(), sxy -= s1.x() * mean.y(), syy -= s1.y() * mean.y(), sxz -= s1.x() * mean.z(), syz -= s1.y() * mean.z();
    const float det = sxx * syy - sxy * sxy;
    const float detBound = 1e-6f * sxx * syy;
    if (!(det > detBound) || !(sxx > 0.0f) || !(syy > 0.0f)) return false;
    const float a = (sxz * syy - syz * sxy) / det;
    const float b = (syz * sxx - sxz * sxy) / det;
    mean = Eigen::Vector3f(mean.x() + origin0.x(), mean.y() + origin0.y(), mean.z() + origin0.z());
    const float g = mean.z() - a * mean.x() - b * mean.y();
    const bool positive = g > 0.0f || firstRules;   // D takes g's sign on every ray of a tile the plane fits
    float r = 0.0f;
    for (uint32_t j = 0; j < side * side; ++j) {
        int x, y;
        if (!sample(j, x, y)) continue;
        const float d = depth.at(x, y);
        if (!validDepth(d)) continue;
        const Eigen::Vector2f ray = rayOf(x, y, fx, fy, cx, cy);
        const float D = 1.0f - a * ray.x() - b * ray.y();
        const float residual = std::abs(d - g / D);
        r = std::max(r, (positive ? D : -D) > 0.0f ? residual : 1e30f);
    }
    const float truncation = params.truncation();
    if (!(r <= gpu::ALLOC_TILE_MAX_RESIDUAL * truncation)) return false;
    const Eigen::Vector2f rayFirst = rayOf(firstX, firstY, fx, fy, cx, cy), rayLast = rayOf(lastX, lastY, fx, fy, cx, cy);
    const Eigen::Vector2f r00(std::min(rayFirst.x(), rayLast.x()), std::min(rayFirst.y(), rayLast.y()));
    const Eigen::Vector2f r11(std::max(rayFirst.x(), rayLast.x()), std::max(rayFirst.y(), rayLast.y()));
    const Eigen::Vector2f r10(r11.x(), r00.y()), r01(r00.x(), r11.y());
    const Eigen::Vector2f corner[4] = {r00, r10, r11, r01};
    float D[4], sD[4];
    for (int k = 0; k < 4; ++k) {
        D[k] = 1.0f - a * corner[k].x() - b * corner[k].y();
        sD[k] = positive ? D[k] : -D[k];
        if (!(sD[k] > 0.0f)) return false;
    }
    const float maxD = std::max(std::max(sD[0], sD[1]), std::max(sD[2], sD[3]));
    const float m = (truncation + r) * maxD * 1.0001f + 1e-5f;
    const float lowOffset = g - m, highOffset = g + m;
    if (!((positive ? lowOffset : -highOffset) > 0.0f)) return false;
    const float blockSize = params.voxelSize * float(gpu::BLOCK_SIDE);
    const Eigen::Vector3f origin = transformRows(push.cameraToWorld, Eigen::Vector3f(0.0f, 0.0f, 0.0f));
    Eigen::Vector3f lo(1e30f, 1e30f, 1e30f), hi(-1e30f, -1e30f, -1e30f);
    for (int k = 0; k < 4; ++k) {
        const float lowZ = lowOffset / D[k], highZ = highOffset / D[k];
        const Eigen::Vector3f lowW = transformRows(push.cameraToWorld, Eigen::Vector3f(corner[k].x() * lowZ, corner[k].y() * lowZ, 1.0f * lowZ));
        const Eigen::Vector3f highW = transformRows(push.cameraToWorld, Eigen::Vector3f(corner[k].x() * highZ, corner[k].y() * highZ, 1.0f * highZ));
        for (int i = 0; i < 3; ++i) {
            const float lowP = lowW[i] / blockSize, highP = highW[i] / blockSize;
            lo[i] = std::min(lo[i], std::min(lowP, highP));
            hi[i] = std::max(hi[i], std::max(lowP, highP));
        }
    }
    int c0[3], c1[3], extent[3];
    for (int i = 0; i < 3; ++i) {
        c0[i] = int(std::floor(lo[i] - gpu::ALLOC_SLAB_MARGIN));
        c1[i] = int(std::floor(hi[i] + gpu::ALLOC_SLAB_MARGIN));
        extent[i] = c1[i] - c0[i] + 1;
    }
    const uint32_t cells = uint32_t(extent[0] * extent[1] * extent[2]);
    if (cells > gpu::ALLOC_TILE_MAX_BLOCKS) return false;
    const Eigen::Vector3f slabN(-a, -b, 1.0f);
    const Eigen::Vector4f planes[6] = {
        planeToBlocks(push.cameraToWorld, slabN, lowOffset, origin, blockSize),
        planeToBlocks(push.cameraToWorld, -slabN, -highOffset, origin, blockSize),
        planeToBlocks(push.cameraToWorld, sideNormal(r00, r10), 0.0f, origin, blockSize),
        planeToBlocks(push.cameraToWorld, sideNormal(r10, r11), 0.0f, origin, blockSize),
        planeToBlocks(push.cameraToWorld, sideNormal(r11, r01), 0.0f, origin, blockSize),
        planeToBlocks(push.cameraToWorld, sideNormal(r01, r00), 0.0f, origin, blockSize),
    };
    if (validSamples) *validSamples += n;
    for (uint32_t i = 0; i < cells; ++i) {
        const BlockCoord cell{c0[0] + int(i % uint32_t(extent[0])), c0[1] + int((i / uint32_t(extent[0])) % uint32_t(extent[1])),
                              c0[2] + int(i / uint32_t(extent[0] * extent[1]))};
        const Eigen::Vector3f c(static_cast<float>(cell[0]), static_cast<float>(cell[1]), static_cast<float>(cell[2]));
        bool outside = false;
        for (const Eigen::Vector4f& plane : planes) outside = outside || boxOutside(c, plane);
        if (!outside) visit(cell);
    }
    return true;
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
    auto visitBlock = [&](const BlockCoord& c) {
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
    };
    // Allocation by tiles (allocate_tiles.comp): the tiles whose slab was claimed; their pixels walk nothing.
    const int samplesX = (depth.width + stride - 1) / stride, samplesY = (depth.height + stride - 1) / stride;
    const int side = int(gpu::ALLOC_TILE), tilesX = (samplesX + side - 1) / side, tilesY = (samplesY + side - 1) / side;
    std::vector<uint8_t> covered(size_t(tilesX) * tilesY, 0);
    if (params.allocationTiles) {
        for (int ty = 0; ty < tilesY; ++ty)
            for (int tx = 0; tx < tilesX; ++tx) {
                const int firstX = tx * side * stride, firstY = ty * side * stride;
                const int lastX = std::min(firstX + (side - 1) * stride, (samplesX - 1) * stride);
                const int lastY = std::min(firstY + (side - 1) * stride, (samplesY - 1) * stride);
                covered[size_t(ty) * tilesX + tx] = walkTileSlab(depth, push, params, firstX, firstY, lastX, lastY, visitBlock, &local.validPixels);
            }
    }
    for (int y = 0; y < depth.height; y += stride) {
        for (int x = 0; x < depth.width; x += stride) {
            if (covered[size_t(y / stride / side) * tilesX + size_t(x / stride / side)]) continue;
            float d = depth.at(x, y);
            if (!(d >= push.minDepth && d <= push.maxDepth)) continue;
            ++local.validPixels;
            Eigen::Vector3f ray((float(x) - cx) / fx, (float(y) - cy) / fy, 1.0f);
            float nearZ = std::max(d - truncation, push.minDepth * 0.5f);
            float farZ = d + truncation;
            Eigen::Vector3f a = transformRows(push.cameraToWorld, Eigen::Vector3f(ray * nearZ)) / blockSize;
            Eigen::Vector3f b = transformRows(push.cameraToWorld, Eigen::Vector3f(ray * farZ)) / blockSize;
            bool complete = walkBand(a, b, visitBlock);
            if (!complete) ++local.rayTruncated;
        }
    }
    local.touchedCount = static_cast<uint32_t>(order.size());
    if (stats) *stats = local;
    return order;
}

}  // namespace vkmesh::cpu
