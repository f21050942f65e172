#include "cpu/reference_volume.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/camera.h"
#include "core/marching_cubes.h"
#include "core/refinement.h"

namespace vkmesh::cpu {
namespace {

using gpu::BLOCK_SIDE;
using gpu::VOXELS_PER_BLOCK;

Eigen::Vector3f transformRows(const float rows[3][4], const Eigen::Vector3f& p) {
    Eigen::Vector3f q;
    for (int i = 0; i < 3; ++i) q[i] = rows[i][0] * p.x() + rows[i][1] * p.y() + rows[i][2] * p.z() + rows[i][3];
    return q;
}

bool inKeyRange(const BlockCoord& c) {
    const int bias = int(gpu::KEY_BIAS);
    return c[0] >= -bias && c[1] >= -bias && c[2] >= -bias && c[0] < bias && c[1] < bias && c[2] < bias;
}

// The 3D DDA of allocate_blocks.comp for one pixel, visiting the blocks from a to b (block units).
// Returns false when the walk was cut at RAY_MAX_BLOCKS.
template <typename Visit>
bool walkBand(const Eigen::Vector3f& a, const Eigen::Vector3f& b, Visit&& visit) {
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

}  // namespace

ReferenceVolume::ReferenceVolume(const VolumeParams& params, float minMeshWeight, bool refine, float refineEpsilon)
    : params_(params), minMeshWeight_(minMeshWeight) {
    setRefinement(refine, refineEpsilon);
}

void ReferenceVolume::setRefinement(bool refine, float refineEpsilon) {
    refine_ = refine;
    refineEpsilon_ = refineEpsilon < 0.0f ? defaultRefineEpsilon(params_.voxelSize) : refineEpsilon;
}

void ReferenceVolume::setRecycling(float keepRadius, uint32_t starveAfterFrames, float starveWeight) {
    keepRadius_ = keepRadius;
    starveAfterFrames_ = starveAfterFrames;
    starveWeight_ = starveWeight;
}

// blockOutsideKeepRadius of shaders_comp/structure/frame.glsl, the same float operations in the same order.
bool ReferenceVolume::outsideKeepRadius(const BlockCoord& c, const float cameraToWorld[3][4]) const {
    if (!(keepRadius_ > 0.0f)) return false;
    const float blockSize = params_.voxelSize * float(BLOCK_SIDE);
    float distance2 = 0.0f;
    for (int k = 0; k < 3; ++k) {
        const float centre = (float(c[k]) + 0.5f) * blockSize;
        const float d = centre - cameraToWorld[k][3];
        distance2 = k == 0 ? d * d : distance2 + d * d;
    }
    return distance2 > keepRadius_ * keepRadius_;
}

size_t ReferenceVolume::retypeCubeCount() const {
    size_t n = 0;
    for (const auto& [coord, mask] : retypeCubes_) n += mask.count();
    return n;
}

std::vector<BlockCoord> ReferenceVolume::blocksTouchedBy(const DepthImage& depth, const Intrinsics& intrinsics,
                                                         const Pose& cameraToWorld, ReferenceFrameStats* stats) const {
    const gpu::FramePush push = makeFramePush(intrinsics, cameraToWorld, params_, 1);
    const float fx = push.intrinsics[0], fy = push.intrinsics[1], cx = push.intrinsics[2], cy = push.intrinsics[3];
    const float truncation = params_.truncation();
    const float blockSize = params_.voxelSize * float(BLOCK_SIDE);
    std::set<BlockCoord> seen;
    std::vector<BlockCoord> order;
    ReferenceFrameStats local;
    const int stride = params_.allocationStride;
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
                if (!inKeyRange(c)) return;
                if (outsideKeepRadius(c, push.cameraToWorld)) { ++local.outsideRadius; return; }
                if (seen.insert(c).second) order.push_back(c);
            });
            if (!complete) ++local.rayTruncated;
        }
    }
    local.touchedCount = static_cast<uint32_t>(order.size());
    if (stats) *stats = local;
    return order;
}

ReferenceFrameStats ReferenceVolume::integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld) {
    ReferenceFrameStats stats;
    std::vector<BlockCoord> touched = blocksTouchedBy(depth, intrinsics, cameraToWorld, &stats);
    const gpu::FramePush push = makeFramePush(intrinsics, cameraToWorld, params_, 1);
    const float fx = push.intrinsics[0], fy = push.intrinsics[1], cx = push.intrinsics[2], cy = push.intrinsics[3];
    const float truncation = params_.truncation();
    const float eps = refineEpsilon_;
    lastFlipped_.clear();
    for (const BlockCoord& c : touched) {
        auto [it, inserted] = blocks_.try_emplace(c);   // a new block starts at weight 0
        if (inserted) ++stats.blocksInserted;
        ReferenceBlock& block = it->second;
        for (uint32_t v = 0; v < VOXELS_PER_BLOCK; ++v) {
            int lx = int(v % BLOCK_SIDE), ly = int((v / BLOCK_SIDE) % BLOCK_SIDE), lz = int(v / (BLOCK_SIDE * BLOCK_SIDE));
            Eigen::Vector3f world(float(c[0] * int(BLOCK_SIDE) + lx) * params_.voxelSize,
                                  float(c[1] * int(BLOCK_SIDE) + ly) * params_.voxelSize,
                                  float(c[2] * int(BLOCK_SIDE) + lz) * params_.voxelSize);
            Eigen::Vector3f cam = transformRows(push.worldToCamera, world);
            if (!(cam.z() > 0.0f)) continue;
            float u = (cam.x() * fx) / cam.z() + cx;
            float w = (cam.y() * fy) / cam.z() + cy;
            float pu = std::floor(u + 0.5f), pv = std::floor(w + 0.5f);
            if (!(pu >= 0.0f && pv >= 0.0f && pu < float(depth.width) && pv < float(depth.height))) continue;
            float d = depth.at(int(pu), int(pv));
            float sdf = d - cam.z();
            if (!(d >= push.minDepth && d <= push.maxDepth && sdf >= -truncation)) continue;
            float tsdf = std::min(sdf, truncation);
            float oldSdf = block.sdf[v], oldWeight = block.weight[v];
            const float newSdf = (oldSdf * oldWeight + tsdf) / (oldWeight + 1.0f);
            const float newWeight = std::min(oldWeight + 1.0f, params_.maxWeight);
            block.sdf[v] = newSdf;
            block.weight[v] = newWeight;
            ++stats.updatedVoxels;
            // Did the corner flip (fuse_depth.comp)? Corners not updated keep their values and never flip.
            const bool wasObserved = oldWeight >= minMeshWeight_, isObserved = newWeight >= minMeshWeight_;
            bool flipped = wasObserved != isObserved || (isObserved && (oldSdf < 0.0f) != (newSdf < 0.0f));
            if (refine_ && isObserved && (std::fabs(oldSdf) < eps) != (std::fabs(newSdf) < eps)) flipped = true;
            if (flipped)
                lastFlipped_.push_back({c[0] * int(BLOCK_SIDE) + lx, c[1] * int(BLOCK_SIDE) + ly, c[2] * int(BLOCK_SIDE) + lz});
        }
    }
    lastTouched_ = std::move(touched);

    // Recycling (recycle_retire.comp, then recycle_free.comp after the mesh passes).
    ++frame_;
    if (keepRadius_ > 0.0f || starveAfterFrames_ > 0) {
        for (const BlockCoord& c : lastTouched_) lastTouchedFrame_[c] = frame_;
        for (auto it = blocks_.begin(); it != blocks_.end();) {
            const bool retire = outsideKeepRadius(it->first, push.cameraToWorld);
            const bool starve = !retire && starveAfterFrames_ > 0 && frame_ - lastTouchedFrame_[it->first] >= starveAfterFrames_;
            if (!retire && !starve) { ++it; continue; }
            ++(retire ? stats.blocksRetired : stats.blocksStarved);
            bool empty = true;
            for (float& w : it->second.weight) {
                w = retire ? 0.0f : std::max(w - starveWeight_, 0.0f);
                empty = empty && w == 0.0f;
            }
            if (!empty) { ++it; continue; }
            ++stats.blocksFreed;
            lastTouchedFrame_.erase(it->first);
            it = blocks_.erase(it);
        }
    }

    // The 8 cubes around every flipped corner, in the blocks that exist now.
    retypeCubes_.clear();
    const int side = int(BLOCK_SIDE);
    auto floorDiv = [side](int a) { return a >= 0 ? a / side : -((-a + side - 1) / side); };
    for (const auto& g : lastFlipped_) {
        for (int o = 0; o < 8; ++o) {
            const auto off = cornerOffset(o);
            const int x = g[0] - off[0], y = g[1] - off[1], z = g[2] - off[2];
            const BlockCoord b{floorDiv(x), floorDiv(y), floorDiv(z)};
            if (!blocks_.count(b)) continue;
            const uint32_t cube = uint32_t((x - b[0] * side) + side * ((y - b[1] * side) + side * (z - b[2] * side)));
            retypeCubes_[b].set(cube);
        }
    }
    return stats;
}

std::vector<Eigen::Vector3f> ReferenceVolume::extractBaselineMesh() const {
    const MarchingCubesTables& tables = marchingCubesTables();
    std::vector<Eigen::Vector3f> soup;
    for (const auto& [coord, block] : blocks_) {
        // The block itself and its 7 neighbours in +x, +y, +z, indexed like cube corners.
        const ReferenceBlock* neighbour[8];
        for (int i = 0; i < 8; ++i) {
            BlockCoord n{coord[0] + (i & 1), coord[1] + ((i >> 1) & 1), coord[2] + ((i >> 2) & 1)};
            auto it = blocks_.find(n);
            neighbour[i] = it == blocks_.end() ? nullptr : &it->second;
        }
        for (uint32_t local = 0; local < VOXELS_PER_BLOCK; ++local) {
            int cube[3] = {int(local % BLOCK_SIDE), int((local / BLOCK_SIDE) % BLOCK_SIDE), int(local / (BLOCK_SIDE * BLOCK_SIDE))};
            float d[8];
            bool observed = true;
            int type = 0;
            for (int c = 0; c < 8; ++c) {
                int g[3] = {cube[0] + (c & 1), cube[1] + ((c >> 1) & 1), cube[2] + ((c >> 2) & 1)};
                int wrap = (g[0] / 8) | ((g[1] / 8) << 1) | ((g[2] / 8) << 2);
                const ReferenceBlock* nb = neighbour[wrap];
                d[c] = 0.0f;
                if (!nb) { observed = false; continue; }
                uint32_t v = ((g[2] % 8) * BLOCK_SIDE + (g[1] % 8)) * BLOCK_SIDE + (g[0] % 8);
                if (nb->weight[v] < minMeshWeight_) observed = false;
                d[c] = nb->sdf[v];
                if (d[c] < 0.0f) type |= 1 << c;
            }
            if (!observed) continue;
            for (int t = 0; t < 3 * tables.triangleCount[type]; ++t) {
                int e = tables.triangleEdges[type][t];
                auto [lo, hi] = edgeCorners(e);
                int axis = edgeAxis(e);
                float s = d[lo] / (d[lo] - d[hi]);
                float p[3] = {float(coord[0] * 8 + cube[0] + (lo & 1)), float(coord[1] * 8 + cube[1] + ((lo >> 1) & 1)),
                              float(coord[2] * 8 + cube[2] + ((lo >> 2) & 1))};
                p[axis] += s;
                soup.emplace_back(p[0] * params_.voxelSize, p[1] * params_.voxelSize, p[2] * params_.voxelSize);
            }
        }
    }
    return soup;
}

}  // namespace vkmesh::cpu
