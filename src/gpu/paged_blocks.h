// Paging's host side (docs/PAGING.md): the blocks a volume has moved out of GPU memory, each as its record (every
// per-block array as it was on the GPU and its hash stamp, PAGE_RECORD_* in shared_layout.h), by block coordinate;
// and which blocks a camera may reach. No Vulkan here: the GpuVolume moves the records (src/gpu/paging.cpp).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "core/types.h"
#include "gpu/layout.h"

namespace vkmesh::gpu {

struct PagedBlock {
    Eigen::Vector3i coord;
    std::vector<uint32_t> record;   // PAGE_RECORD_WORDS
    uint64_t bytes() const { return 4 * record.size(); }
};

// The blocks a camera can reach, conservatively: every block whose bounding sphere, grown by `marginMetres`,
// meets the view frustum of a `intrinsics` camera at `cameraToWorld` between nearDepth and farDepth. Fusion touches
// only blocks within the truncation band of a depth in [near, far] along a pixel's ray, so with far = max depth +
// truncation and a margin of one block (the neighbours the mesh passes read) a frame's work stays inside.
class ViewReach {
public:
    ViewReach(const Pose& cameraToWorld, const Intrinsics& intrinsics, float nearDepth, float farDepth, float blockSide,
              float marginMetres);
    bool reaches(const Eigen::Vector3i& block) const;

private:
    Eigen::Matrix3f rotation_;   // world to camera
    Eigen::Vector3f translation_;
    float blockSide_, radius_, near_, far_;
    // Side planes through the camera centre: n . p >= -radius for a sphere at p (camera frame) that meets the frustum.
    Eigen::Vector3f planes_[4];
};

class PagedBlocks {
public:
    bool empty() const { return blocks_.empty(); }
    size_t size() const { return blocks_.size(); }
    uint64_t bytes() const { return bytes_; }
    void put(PagedBlock block);
    bool contains(const Eigen::Vector3i& coord) const { return blocks_.count(key(coord)) != 0; }
    // Takes out the blocks the view reaches, in coordinate order (the same order on every run).
    std::vector<PagedBlock> takeReached(const ViewReach& view);
    // Every block, for snapshots (downloadBlocks), in coordinate order.
    std::vector<const PagedBlock*> all() const;

private:
    static uint64_t key(const Eigen::Vector3i& c);
    std::unordered_map<uint64_t, PagedBlock> blocks_;
    uint64_t bytes_ = 0;
};

}  // namespace vkmesh::gpu
