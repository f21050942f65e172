#include "slam/frame_registration.h"

#include <cmath>

#include "core/camera.h"
#include "gpu/tracking/pose_tracker.h"

namespace vkmesh::slam {

RegistrationFrame registrationFrame(const DepthImage& depth, const Intrinsics& intrinsics, const gpu::TrackerOptions& tracker,
                                    int maxWidth) {
    DepthImage small = depth;
    int halvings = 0;
    while (small.width > maxWidth && small.width % 2 == 0 && small.height % 2 == 0) {
        small = gpu::halveTrackingDepth(small, 3.0f * tracker.filterDepthSigma);
        ++halvings;
    }
    RegistrationFrame out;
    out.levels = cpu::referenceTrackingPyramid(small, pyramidLevelIntrinsics(intrinsics, halvings), gpu::trackParamsFor(tracker));
    return out;
}

Registration registerFrame(const RegistrationFrame& frame, const RegistrationFrame& keyframe, const Pose& keyframePose,
                           const Pose& initial, const gpu::TrackerOptions& tracker, const std::array<int, 3>& iterations) {
    Registration result;
    result.cameraToWorld = initial;
    if (frame.levels.size() != keyframe.levels.size()) throw Error("registration: the frame and the keyframe have different pyramids");
    result.solved = true;
    const Eigen::Matrix3f rotation = keyframePose.block<3, 3>(0, 0).cast<float>();
    const Eigen::Vector3f translation = keyframePose.block<3, 1>(0, 3).cast<float>();
    for (int level = int(frame.levels.size()) - 1; level >= 0; --level) {
        const cpu::TrackingLevel& f = frame.levels[size_t(level)];
        const cpu::TrackingLevel& k = keyframe.levels[size_t(level)];
        if (f.width != k.width || f.height != k.height) throw Error("registration: the frame and the keyframe differ in size");
        // The keyframe's points and normals in world space: its "model maps".
        std::vector<Eigen::Vector4f> positions(k.points.size(), Eigen::Vector4f::Zero()), normals(k.points.size(), Eigen::Vector4f::Zero());
        for (size_t i = 0; i < k.points.size(); ++i) {
            if (k.points[i].w() == 0.0f || k.normals[i].w() == 0.0f) continue;
            const Eigen::Vector3f p = rotation * Eigen::Vector3f(k.points[i].head<3>()) + translation;
            const Eigen::Vector3f n = rotation * Eigen::Vector3f(k.normals[i].head<3>());
            positions[i] = Eigen::Vector4f(p.x(), p.y(), p.z(), 1.0f);
            normals[i] = Eigen::Vector4f(n.x(), n.y(), n.z(), 1.0f);
        }
        const IcpGates gates = gpu::icpGatesFor(tracker, level);
        const int count = level < 3 ? iterations[size_t(level)] : 4;
        for (int it = 0; it < count; ++it) {
            const IcpSystem system = icpSystem(cpu::referenceIcpSums(f, positions, normals, result.cameraToWorld, keyframePose, gates));
            ++result.iterations;
            const IcpStep step = solveIcpStep(system);
            if (level == 0) result.system = system, result.conditioning = step.conditioning;
            if (!step.solved) {
                result.solved = false;
                break;
            }
            result.cameraToWorld = applyTwist(step.twist, result.cameraToWorld);
            if (step.twist.head<3>().norm() < tracker.stopRotation && step.twist.tail<3>().norm() < tracker.stopTranslation) break;
        }
    }
    return result;
}

std::string registrationFailure(const Registration& r, const Pose& initial, const gpu::TrackerOptions& tracker, const VerificationGates& gates) {
    const Pose motion = inverseRigid(initial) * r.cameraToWorld;
    gpu::TrackerOptions checks = tracker;
    checks.maxJumpMetres = checks.maxJumpDegrees = 1e9;
    const uint32_t verdict = gpu::trackingLoss(r.system, r.solved, r.conditioning, motion, {}, checks);
    if (verdict != gpu::TRACK_TRACKED) return gpu::lossText(verdict, r.system, r.conditioning, motion, {}, checks);
    if (r.inlierShare() < gates.minInlierShare)
        return "inliers cover " + std::to_string(int(std::lround(100 * r.inlierShare()))) + " % of the frame";
    if (r.system.rmse() > gates.maxRmse) return "RMSE " + std::to_string(r.system.rmse()) + " m";
    return "";
}

VerifiedRegistration verifyRegistration(const RegistrationFrame& frame, const RegistrationFrame& keyframe, const Pose& keyframePose,
                                        const std::vector<Pose>& initials, const gpu::TrackerOptions& tracker, const VerificationGates& gates) {
    VerifiedRegistration out;
    for (const Pose& initial : initials) {
        const Registration r = registerFrame(frame, keyframe, keyframePose, initial, tracker);
        out.failure = registrationFailure(r, initial, tracker, gates);
        if (out.failure.empty()) {
            out.match = r;
            break;
        }
    }
    if (!out.match) return out;
    const Registration back = registerFrame(keyframe, frame, out.match->cameraToWorld, keyframePose, tracker);
    const Pose disagreement = inverseRigid(keyframePose) * back.cameraToWorld;
    const std::string backFailure = registrationFailure(back, keyframePose, tracker, gates);
    if (!backFailure.empty()) {
        out.failure = "the registration back from the keyframe fails: " + backFailure;
        out.match.reset();
    } else if (translationMetres(disagreement) > gates.symmetricMetres || rotationDegrees(disagreement) > gates.symmetricDegrees) {
        out.failure = "the registration back from the keyframe disagrees by " + std::to_string(translationMetres(disagreement)) + " m, " +
                      std::to_string(rotationDegrees(disagreement)) + " degrees";
        out.match.reset();
    }
    return out;
}

}  // namespace vkmesh::slam
