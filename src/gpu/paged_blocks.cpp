#include "gpu/paged_blocks.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "core/types.h"

namespace vkmesh::gpu {

ViewReach::ViewReach(const Pose& cameraToWorld, const Intrinsics& intrinsics, float nearDepth, float farDepth, float blockSide,
                     float marginMetres)
    : blockSide_(blockSide), near_(nearDepth), far_(farDepth) {
    // The rigid inverse: world to camera.
    const Eigen::Matrix3d rotation = cameraToWorld.topLeftCorner<3, 3>().transpose();
    rotation_ = rotation.cast<float>();
    translation_ = (-rotation * cameraToWorld.topRightCorner<3, 1>()).cast<float>();
    radius_ = 0.5f * std::sqrt(3.0f) * blockSide + marginMetres;
    // Pixel columns [0, width] and rows [0, height]: x / z between (0 - cx) / fx and (width - cx) / fx, the same for y,
    // in either order (a negative focal length mirrors the image: ICL-NUIM's fy).
    const auto bounds = [](float size, float c, float f) {
        const float a = (0.0f - c) / f, b = (size - c) / f;
        return std::pair<float, float>(std::min(a, b), std::max(a, b));
    };
    const auto [left, right] = bounds(float(intrinsics.width), intrinsics.cx, intrinsics.fx);
    const auto [top, bottom] = bounds(float(intrinsics.height), intrinsics.cy, intrinsics.fy);
    planes_[0] = Eigen::Vector3f(1, 0, -left).normalized();
    planes_[1] = Eigen::Vector3f(-1, 0, right).normalized();
    planes_[2] = Eigen::Vector3f(0, 1, -top).normalized();
    planes_[3] = Eigen::Vector3f(0, -1, bottom).normalized();
}

bool ViewReach::reaches(const Eigen::Vector3i& block) const {
    const Eigen::Vector3f centre = (block.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * blockSide_;
    const Eigen::Vector3f p = rotation_ * centre + translation_;
    if (p.z() < near_ - radius_ || p.z() > far_ + radius_) return false;
    for (const Eigen::Vector3f& n : planes_)
        if (n.dot(p) < -radius_) return false;
    return true;
}

uint64_t PagedBlocks::key(const Eigen::Vector3i& c) {
    return uint64_t(uint32_t(c.x()) & 0x1FFFFF) | uint64_t(uint32_t(c.y()) & 0x1FFFFF) << 21 | uint64_t(uint32_t(c.z()) & 0x1FFFFF) << 42;
}

void PagedBlocks::put(PagedBlock block) {
    bytes_ += block.bytes();
    const uint64_t k = key(block.coord);
    auto [it, inserted] = blocks_.emplace(k, std::move(block));
    if (!inserted) throw Error("paging: block (" + std::to_string(it->second.coord.x()) + ", " + std::to_string(it->second.coord.y()) +
                               ", " + std::to_string(it->second.coord.z()) + ") is paged out twice");
}

namespace {
bool coordLess(const Eigen::Vector3i& a, const Eigen::Vector3i& b) {
    return std::tie(a.z(), a.y(), a.x()) < std::tie(b.z(), b.y(), b.x());
}
}  // namespace

std::vector<PagedBlock> PagedBlocks::takeReached(const ViewReach& view) {
    std::vector<uint64_t> keys;
    for (const auto& [k, b] : blocks_)
        if (view.reaches(b.coord)) keys.push_back(k);
    std::vector<PagedBlock> out;
    out.reserve(keys.size());
    for (uint64_t k : keys) {
        auto it = blocks_.find(k);
        bytes_ -= it->second.bytes();
        out.push_back(std::move(it->second));
        blocks_.erase(it);
    }
    std::sort(out.begin(), out.end(), [](const PagedBlock& a, const PagedBlock& b) { return coordLess(a.coord, b.coord); });
    return out;
}

std::vector<const PagedBlock*> PagedBlocks::all() const {
    std::vector<const PagedBlock*> out;
    for (const auto& [k, b] : blocks_) out.push_back(&b);
    std::sort(out.begin(), out.end(), [](const PagedBlock* a, const PagedBlock* b) { return coordLess(a->coord, b->coord); });
    return out;
}

}  // namespace vkmesh::gpu
