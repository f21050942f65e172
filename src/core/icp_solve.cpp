#include "core/icp_solve.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vkmesh {

double IcpSystem::rmse() const { return inliers > 0 ? std::sqrt(squaredError / inliers) : 0.0; }

IcpSystem icpSystem(const IcpSums& sums) {
    using namespace gpu;
    IcpSystem s;
    uint32_t slot = TRACK_SUM_JTJ;
    for (int a = 0; a < 6; ++a) {
        for (int b = a; b < 6; ++b) {
            s.jtj(a, b) = s.jtj(b, a) = sums[slot];
            ++slot;
        }
        s.jtr(a) = sums[TRACK_SUM_JTR + a];
    }
    s.weightedError = sums[TRACK_SUM_WEIGHTED_ERROR];
    s.squaredError = sums[TRACK_SUM_SQUARED_ERROR];
    s.inliers = sums[TRACK_SUM_INLIERS];
    s.validPixels = sums[TRACK_SUM_VALID];
    s.modelHits = sums[TRACK_SUM_MODEL_HITS];
    return s;
}

IcpStep solveIcpStep(const IcpSystem& system, double sceneScale) {
    IcpStep step;
    if (system.inliers < 6 || !system.jtj.allFinite() || !system.jtr.allFinite()) return step;
    // Rotation unknowns in radians against translations in metres: scale the rotation rows by the scene's
    // size so that "unconstrained" means the same for both before comparing eigenvalues.
    Eigen::Matrix<double, 6, 1> scale;
    scale << 1.0 / sceneScale, 1.0 / sceneScale, 1.0 / sceneScale, 1.0, 1.0, 1.0;
    Eigen::Matrix<double, 6, 6> scaled = scale.asDiagonal() * system.jtj * scale.asDiagonal();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(scaled, Eigen::EigenvaluesOnly);
    const double largest = eigen.eigenvalues().maxCoeff(), smallest = eigen.eigenvalues().minCoeff();
    step.conditioning = largest > 0 ? std::max(0.0, smallest) / largest : 0.0;
    if (!(largest > 0) || !(smallest > 0)) return step;
    Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(system.jtj);
    if (ldlt.info() != Eigen::Success) return step;
    step.twist = ldlt.solve(-system.jtr);
    step.solved = step.twist.allFinite();
    if (!step.solved) step.twist.setZero();
    return step;
}

Pose applyTwist(const Twist& twist, const Pose& pose) {
    const Eigen::Vector3d omega = twist.head<3>();
    const double angle = omega.norm();
    Eigen::Matrix3d rotation = angle > 0 ? Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
    Pose result = pose;
    result.block<3, 3>(0, 0) = rotation * pose.block<3, 3>(0, 0);
    result.block<3, 1>(0, 3) = pose.block<3, 1>(0, 3) + twist.tail<3>();
    // Keep the rotation orthonormal over many steps (each is orthonormal; their product drifts by rounding).
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(result.block<3, 3>(0, 0), Eigen::ComputeFullU | Eigen::ComputeFullV);
    result.block<3, 3>(0, 0) = svd.matrixU() * svd.matrixV().transpose();
    return result;
}

Intrinsics pyramidLevelIntrinsics(const Intrinsics& k, int level) {
    const float scale = 1.0f / float(1u << level);
    Intrinsics l = k;
    l.fx = k.fx * scale;
    l.fy = k.fy * scale;
    l.cx = (k.cx + 0.5f) * scale - 0.5f;
    l.cy = (k.cy + 0.5f) * scale - 0.5f;
    l.width = k.width >> level;
    l.height = k.height >> level;
    return l;
}

double rotationDegrees(const Pose& motion) {
    // atan2 of sin and cos of the angle: accurate for small angles too (acos of the trace is not).
    const Eigen::Matrix3d r = motion.block<3, 3>(0, 0);
    const double sine = 0.5 * Eigen::Vector3d(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1)).norm();
    const double cosine = 0.5 * (r.trace() - 1.0);
    return std::atan2(sine, cosine) * 180.0 / std::numbers::pi;
}

double translationMetres(const Pose& motion) { return motion.block<3, 1>(0, 3).norm(); }

}  // namespace vkmesh
