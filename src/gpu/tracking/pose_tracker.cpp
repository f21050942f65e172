#include "gpu/tracking/pose_tracker.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <vector>

#include "core/camera.h"

namespace vkmesh::gpu {
namespace {

constexpr size_t kRecentFrames = 10;

std::string format(const char* pattern, double a, double b) {
    char text[200];
    std::snprintf(text, sizeof(text), pattern, a, b);
    return text;
}

}  // namespace

PoseTracker::PoseTracker(const vk::Context& context, const TrackerOptions& options) : context_(context), options_(options) {}
PoseTracker::~PoseTracker() = default;

TrackingReport PoseTracker::start(const Pose& cameraToWorld) {
    started_ = true;
    lastTracked_ = cameraToWorld;
    velocity_ = Pose::Identity();
    recentRmse_.clear();
    TrackingReport report;
    report.cameraToWorld = cameraToWorld;
    report.tracked = true;
    report.first = true;
    return report;
}

TrackingReport PoseTracker::track(const DepthImage& depth, const Intrinsics& intrinsics, const MeshBuffers& mesh, const ColorImage* color) {
    if (!started_) throw Error("tracking: start() with the first frame's pose before tracking");
    const auto t0 = std::chrono::steady_clock::now();
    if (!tracker_ || tracker_->width() != depth.width || tracker_->height() != depth.height)
        tracker_ = std::make_unique<CameraTracker>(context_, depth.width, depth.height, options_);
    const Pose predicted = prediction();
    IcpResult icp;
    if (options_.solveOnGpu) {
        icp = tracker_->trackInOneSubmission(depth, intrinsics, mesh, predicted, predicted, color);
    } else {
        tracker_->prepare(depth, intrinsics, mesh, predicted, color);
        icp = tracker_->align(predicted);
    }
    TrackingReport report;
    report.iterations = icp.iterations;
    report.submissions = icp.submissions;
    report.inliers = icp.finalSystem.inliers;
    report.validPixels = icp.finalSystem.validPixels;
    report.rmse = icp.finalSystem.rmse();
    report.conditioning = icp.finalStep.conditioning;
    report.gpuMilliseconds = tracker_->gpuMilliseconds();
    report.gpuStageMilliseconds = tracker_->gpuStageMilliseconds();

    const Pose motion = inverseRigid(lastTracked_) * icp.cameraToWorld;
    const double recent = recentRmse_.empty() ? 0.0
                                              : std::accumulate(recentRmse_.begin(), recentRmse_.end(), 0.0) / double(recentRmse_.size());
    std::string lost;
    if (report.validPixels == 0)
        lost = "no valid depth";
    else if (icp.finalSystem.modelHits == 0)
        lost = "no model in view";
    else if (report.inliers < options_.minInliers || report.inliers < options_.minInlierFraction * report.validPixels)
        lost = format("too few inliers (%.0f of %.0f pixels)", report.inliers, report.validPixels);
    else if (!icp.finalStep.solved || report.conditioning < options_.minConditioning)
        lost = format("ill-conditioned system (conditioning %.3g, limit %.3g)", report.conditioning, options_.minConditioning);
    else if (translationMetres(motion) > options_.maxJumpMetres)
        lost = format("a jump of %.3f m (limit %.3f m)", translationMetres(motion), options_.maxJumpMetres);
    else if (rotationDegrees(motion) > options_.maxJumpDegrees)
        lost = format("a turn of %.1f degrees (limit %.1f)", rotationDegrees(motion), options_.maxJumpDegrees);
    else if (recent > 0 && report.rmse > options_.minErrorForRise && report.rmse > options_.maxErrorRise * recent)
        lost = format("the error rose to %.4f m (recent frames: %.4f m)", report.rmse, recent);

    if (lost.empty()) {
        report.tracked = true;
        report.cameraToWorld = icp.cameraToWorld;
        velocity_ = motion;
        lastTracked_ = icp.cameraToWorld;
        recentRmse_.push_back(report.rmse);
        if (recentRmse_.size() > kRecentFrames) recentRmse_.pop_front();
    } else {
        report.tracked = false;
        report.lostReason = lost;
        report.cameraToWorld = predicted;
        velocity_ = Pose::Identity();   // the motion is unknown now: predict the last tracked pose
    }
    report.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return report;
}

}  // namespace vkmesh::gpu
