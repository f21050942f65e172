// The host half of point-to-plane ICP (docs/TRACKING.md): the per-pixel sums the GPU (or the CPU reference)
// formed, turned into the 6x6 normal equations and solved in double; the step applied to a pose; the
// conditioning that tracking-loss checks read. Shared by the GPU tracker and the CPU reference, so both take
// the same steps from the same sums.
#pragma once

#include <Eigen/Core>

#include <array>

#include "core/types.h"
#include "shared_layout.h"

namespace vkmesh {

using IcpSums = std::array<double, gpu::TRACK_SUM_COUNT>;   // laid out as TRACK_SUM_* says
using Twist = Eigen::Matrix<double, 6, 1>;                    // rotation (axis * angle, radians), then translation

struct IcpSystem {
    Eigen::Matrix<double, 6, 6> jtj = Eigen::Matrix<double, 6, 6>::Zero();   // sum w J^T J
    Twist jtr = Twist::Zero();                                              // sum w J^T r
    double weightedError = 0;   // sum w r^2
    double squaredError = 0;    // sum r^2 over the inliers
    double inliers = 0;
    double validPixels = 0;     // frame pixels with a point and a normal
    double modelHits = 0;       //  ... that projected onto the model
    double rmse() const;        // of the inliers' residuals (metres); 0 without inliers
};
IcpSystem icpSystem(const IcpSums& sums);

struct IcpStep {
    Twist twist = Twist::Zero();   // the step minimising the linearised error: jtj twist = -jtr
    bool solved = false;           // false: no inliers, or the system is singular
    // Smallest / largest eigenvalue of the system with its rotation rows scaled to the scene's size (so the
    // two kinds of unknown compare): near 0 when a direction of motion is not constrained (one plane, say).
    double conditioning = 0;
};
// `sceneScale`: metres per radian for the conditioning (the mean distance of the inliers from the world
// origin is a fair choice; 1 when unknown).
IcpStep solveIcpStep(const IcpSystem& system, double sceneScale = 1.0);

// The step applied to a camera pose: rotated by the axis-angle vector about its own centre, then moved by the
// translation, both in world axes (R' = exp(omega) R, t' = t + translation). Linearised about the camera
// rather than the world origin, a step stays accurate however far the camera is from the origin.
Pose applyTwist(const Twist& twist, const Pose& pose);

// The association gates and robust weight of one pyramid level (TrackerOptions; TrackPush).
struct IcpGates {
    float distance = 0.1f;      // metres between the frame's point and the model's
    float normalCos = 0.94f;    // cosine of the largest angle between their normals
    float huber = 0.02f;        // metres: weight 1 below, huber / |r| above
};

// The intrinsics of tracking's pyramid level `level` (0: the image itself): focal lengths halved per level,
// pixel centres kept at integer coordinates ((c + 0.5) / 2^level - 0.5), width and height >> level.
Intrinsics pyramidLevelIntrinsics(const Intrinsics& intrinsics, int level);

// Rotation angle (degrees) and translation length (metres) of a rigid transform.
double rotationDegrees(const Pose& motion);
double translationMetres(const Pose& motion);

}  // namespace vkmesh
