// Rigid transforms in the exact float form the shaders use, so the CPU reference computes the same
// numbers as the GPU (same values, same order of operations, no fused multiply-add).
#pragma once

#include "core/types.h"
#include "shared_layout.h"

namespace vkmesh {

// The 3 rows of [R | t] in float.
struct RigidRows {
    float r[3][4];
    // x' = r.x*x + r.y*y + r.z*z + r.w, left to right (as transformPoint in shaders_comp/structure/rigid.glsl).
    Eigen::Vector3f apply(const Eigen::Vector3f& p) const {
        Eigen::Vector3f q;
        for (int i = 0; i < 3; ++i) q[i] = r[i][0] * p.x() + r[i][1] * p.y() + r[i][2] * p.z() + r[i][3];
        return q;
    }
};

RigidRows rigidRows(const Pose& m);
// Inverse of a rigid transform (R^T, -R^T t), computed in double.
Pose inverseRigid(const Pose& m);

// The push constants of a frame (camera both ways, intrinsics, depth range) exactly as the shaders
// get them; the CPU reference reads its floats from the same struct.
gpu::FramePush makeFramePush(const Intrinsics& intrinsics, const Pose& cameraToWorld, const VolumeParams& params,
                             uint32_t frameNumber);

}  // namespace vkmesh
