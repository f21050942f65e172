#include "core/camera.h"

#include <cstring>

namespace vkmesh {

RigidRows rigidRows(const Pose& m) {
    RigidRows rows{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j) rows.r[i][j] = static_cast<float>(m(i, j));
    return rows;
}

Pose inverseRigid(const Pose& m) {
    Pose inv = Pose::Identity();
    Eigen::Matrix3d rt = m.topLeftCorner<3, 3>().transpose();
    inv.topLeftCorner<3, 3>() = rt;
    inv.topRightCorner<3, 1>() = -rt * m.topRightCorner<3, 1>();
    return inv;
}

gpu::FramePush makeFramePush(const Intrinsics& intrinsics, const Pose& cameraToWorld, const VolumeParams& params,
                        uint32_t frameNumber) {
    gpu::FramePush push{};
    RigidRows w2c = rigidRows(inverseRigid(cameraToWorld)), c2w = rigidRows(cameraToWorld);
    std::memcpy(push.worldToCamera, w2c.r, sizeof(push.worldToCamera));
    std::memcpy(push.cameraToWorld, c2w.r, sizeof(push.cameraToWorld));
    push.intrinsics[0] = intrinsics.fx;
    push.intrinsics[1] = intrinsics.fy;
    push.intrinsics[2] = intrinsics.cx;
    push.intrinsics[3] = intrinsics.cy;
    push.imageSize = uint32_t(intrinsics.width) | (uint32_t(intrinsics.height) << 16);
    push.frameNumber = frameNumber;
    push.minDepth = params.minDepth;
    push.maxDepth = params.maxDepth;
    return push;
}

}  // namespace vkmesh
