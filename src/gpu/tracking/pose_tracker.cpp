#include "gpu/tracking/pose_tracker.h"

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <vector>

#include "core/camera.h"

namespace vkmesh::gpu {
namespace {

constexpr size_t kRecentFrames = 10;

}  // namespace

DepthImage halveTrackingDepth(const DepthImage& in, float band) {
    DepthImage out;
    out.width = in.width / 2;
    out.height = in.height / 2;
    out.meters.assign(size_t(out.width) * out.height, 0.0f);
    for (int y = 0; y < out.height; ++y) {
        for (int x = 0; x < out.width; ++x) {
            float samples[4], reference = 0, sum = 0;
            int count = 0;
            for (int k = 0; k < 4; ++k) {
                const float d = in.meters[size_t(2 * y + (k >> 1)) * in.width + size_t(2 * x + (k & 1))];
                samples[k] = std::isfinite(d) && d > 0 ? d : 0.0f;
                if (reference == 0 && samples[k] > 0) reference = samples[k];
            }
            for (float d : samples)
                if (d > 0 && std::abs(d - reference) <= band) sum += d, ++count;
            out.meters[size_t(y) * out.width + x] = count > 0 ? sum / float(count) : 0.0f;
        }
    }
    return out;
}

namespace {

// Halves a colour image: each pixel the mean of the 2 x 2 (rounded).
ColorImage halveColor(const ColorImage& in) {
    ColorImage out;
    out.width = in.width / 2;
    out.height = in.height / 2;
    out.rgb.resize(size_t(out.width) * out.height * 3);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < 3; ++c) {
                int sum = 0;
                for (int k = 0; k < 4; ++k) sum += in.rgb[(size_t(2 * y + (k >> 1)) * in.width + size_t(2 * x + (k & 1))) * 3 + c];
                out.rgb[(size_t(y) * out.width + x) * 3 + c] = uint8_t((sum + 2) / 4);
            }
    return out;
}

std::string format(const char* pattern, double a, double b) {
    char text[200];
    std::snprintf(text, sizeof(text), pattern, a, b);
    return text;
}

}  // namespace

int trackingDownsample(const TrackerOptions& options, int width) {
    // 640 x 480 (the common RGB-D frame) tracks as well at 320 x 240, at a quarter of the finest level's work;
    // smaller frames keep every pixel (docs/RESULTS.md, "Tracking").
    if (options.downsample == 0) return width >= 640 ? 2 : 1;
    return options.downsample;
}

PoseTracker::PoseTracker(const vk::Context& context, const TrackerOptions& options) : context_(context), options_(options) {
    if (options.downsample != 0 && options.downsample != 1 && options.downsample != 2 && options.downsample != 4)
        throw Error("tracking: downsample " + std::to_string(options.downsample) + " is not 0 (by the frame's width), 1, 2 or 4");
    trackParamsFor(options);   // every other setting checked before the first frame
}

PoseTracker::~PoseTracker() = default;

PoseTracker::TrackingInput PoseTracker::trackingInput(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics) {
    const int downsample = trackingDownsample(options_, depth.width);
    if (downsample == 1) return {&depth, color, intrinsics};   // CameraTracker checks the sizes
    // Checked before they are read here.
    if (depth.width < 0 || depth.height < 0 || depth.meters.size() != size_t(depth.width) * size_t(depth.height))
        throw Error("tracking: a depth image of " + std::to_string(depth.meters.size()) + " samples is not " + std::to_string(depth.width) +
                    "x" + std::to_string(depth.height));
    if (color && !color->empty() && options_.colorWeight > 0 && (color->width != depth.width || color->height != depth.height ||
                                     color->rgb.size() != size_t(color->width) * size_t(color->height) * 3))
        throw Error("tracking: a " + std::to_string(color->width) + "x" + std::to_string(color->height) + " colour image for a " +
                    std::to_string(depth.width) + "x" + std::to_string(depth.height) + " depth image");
    const float band = 3.0f * options_.filterDepthSigma;
    smallDepth_ = halveTrackingDepth(depth, band);
    const bool withColor = color && !color->empty() && options_.colorWeight > 0;
    if (withColor) smallColor_ = halveColor(*color);
    int levels = 1;
    if (downsample == 4) {
        smallDepth_ = halveTrackingDepth(smallDepth_, band);
        if (withColor) smallColor_ = halveColor(smallColor_);
        levels = 2;
    }
    return {&smallDepth_, withColor ? &smallColor_ : nullptr, pyramidLevelIntrinsics(intrinsics, levels)};
}

TrackingReport PoseTracker::start(const Pose& cameraToWorld) {
    started_ = true;
    lastTracked_ = cameraToWorld;
    velocity_ = Pose::Identity();
    recentRmse_.clear();
    recentShare_.clear();
    modelFresh_ = false;   // a new start (a jump, a new map): the mesh is drawn again
    TrackingReport report;
    report.cameraToWorld = cameraToWorld;
    report.tracked = true;
    report.first = true;
    return report;
}

uint32_t trackingLoss(const IcpSystem& system, bool solved, double conditioning, const Pose& motion, const RecentFrames& recent,
                      const TrackerOptions& o) {
    // Written as track_decide.comp makes them (a NaN motion is a jump there too).
    if (system.validPixels == 0) return TRACK_LOST_NO_DEPTH;
    if (system.modelHits == 0) return TRACK_LOST_NO_MODEL;
    if (system.inliers < o.minInliers || system.inliers < o.minInlierFraction * system.validPixels) return TRACK_LOST_FEW_INLIERS;
    if (!solved || !(conditioning >= o.minConditioning)) return TRACK_LOST_ILL_CONDITIONED;
    if (!(translationMetres(motion) <= o.maxJumpMetres)) return TRACK_LOST_JUMP;
    if (!(rotationDegrees(motion) <= o.maxJumpDegrees)) return TRACK_LOST_TURN;
    const double rmse = system.rmse();
    if (recent.rmse > 0 && rmse > o.minErrorForRise && rmse > o.maxErrorRise * recent.rmse) return TRACK_LOST_ERROR_ROSE;
    if (system.inliers < o.minShareOfRecent * recent.inlierShare * system.validPixels) return TRACK_LOST_SHARE_FELL;
    return TRACK_TRACKED;
}

std::string lossText(uint32_t reason, const IcpSystem& system, double conditioning, const Pose& motion, const RecentFrames& recent,
                     const TrackerOptions& o) {
    switch (reason) {
        case TRACK_TRACKED: return "";
        case TRACK_LOST_NO_DEPTH: return "no valid depth";
        case TRACK_LOST_NO_MODEL: return "no model in view";
        case TRACK_LOST_FEW_INLIERS: return format("too few inliers (%.0f of %.0f pixels)", system.inliers, system.validPixels);
        case TRACK_LOST_ILL_CONDITIONED:
            return format("ill-conditioned system (conditioning %.3g, limit %.3g)", conditioning, o.minConditioning);
        case TRACK_LOST_JUMP: return format("a jump of %.3f m (limit %.3f m)", translationMetres(motion), o.maxJumpMetres);
        case TRACK_LOST_TURN: return format("a turn of %.1f degrees (limit %.1f)", rotationDegrees(motion), o.maxJumpDegrees);
        case TRACK_LOST_ERROR_ROSE: return format("the error rose to %.4f m (recent frames: %.4f m)", system.rmse(), recent.rmse);
        case TRACK_LOST_SHARE_FELL:
            return format("the share of pixels matching the map fell to %.2f (recent frames: %.2f)",
                          system.validPixels > 0 ? system.inliers / system.validPixels : 0.0, recent.inlierShare);
        default: return "lost (reason " + std::to_string(reason) + ")";
    }
}

CameraTracker& PoseTracker::trackerFor(const DepthImage& depth) {
    if (!started_) throw Error("tracking: start() with the first frame's pose before tracking");
    if (!tracker_ || tracker_->width() != depth.width || tracker_->height() != depth.height)
        tracker_ = std::make_unique<CameraTracker>(context_, depth.width, depth.height, options_);
    return *tracker_;
}

bool PoseTracker::reuseModelMaps(CameraTracker& tracker, const Pose& predicted) {
    bool reuse = modelFresh_ && tracker.hasModelMaps() && modelReuses_ < options_.modelReuseFrames;
    if (reuse) {
        const Pose moved = inverseRigid(tracker.modelPose()) * predicted;
        reuse = translationMetres(moved) <= options_.modelReuseMetres && rotationDegrees(moved) <= options_.modelReuseDegrees;
    }
    modelReuses_ = reuse ? modelReuses_ + 1 : 0;
    modelFresh_ = true;
    tracker.keepModelMaps(reuse);
    return reuse;
}

RecentFrames PoseTracker::recent() const {
    const auto mean = [](const std::deque<double>& v) { return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size()); };
    return {mean(recentRmse_), mean(recentShare_)};
}

TrackingReport PoseTracker::conclude(const IcpResult& icp, uint32_t reason, double conditioning, const Pose& estimate, const Pose& predicted,
                                     const TrackerOptions& bounds) {
    TrackingReport report;
    report.iterations = icp.iterations;
    report.submissions = icp.submissions;
    report.inliers = icp.finalSystem.inliers;
    report.validPixels = icp.finalSystem.validPixels;
    report.rmse = icp.finalSystem.rmse();
    report.conditioning = conditioning;
    report.gpuMilliseconds = tracker_->gpuMilliseconds();
    report.gpuStageMilliseconds = tracker_->gpuStageMilliseconds();
    const Pose motion = inverseRigid(lastTracked_) * estimate;
    if (reason == TRACK_TRACKED) {
        report.tracked = true;
        report.cameraToWorld = estimate;
        velocity_ = motion;
        lastTracked_ = estimate;
        recentRmse_.push_back(report.rmse);
        recentShare_.push_back(report.inlierShare());
        if (recentRmse_.size() > kRecentFrames) recentRmse_.pop_front(), recentShare_.pop_front();
    } else {
        report.tracked = false;
        report.lostReason = lossText(reason, icp.finalSystem, conditioning, motion, recent(), bounds);
        report.cameraToWorld = predicted;
        velocity_ = Pose::Identity();   // the motion is unknown now: predict the last tracked pose
        modelFresh_ = false;            // and draw the mesh for the next frame
    }
    return report;
}

TrackingReport PoseTracker::track(const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model, const ColorImage* color) {
    return track(depth, intrinsics, model, color, options_);
}

TrackingReport PoseTracker::track(const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model, const ColorImage* color,
                                  const TrackerOptions& bounds) {
    const auto t0 = std::chrono::steady_clock::now();
    const TrackingInput in = trackingInput(depth, color, intrinsics);
    CameraTracker& tracker = trackerFor(*in.depth);
    const Pose predicted = prediction();
    const bool reused = reuseModelMaps(tracker, predicted);
    IcpResult icp;
    if (options_.solveOnGpu) {
        icp = tracker.trackInOneSubmission(*in.depth, in.intrinsics, model, predicted, predicted, in.color);
    } else {
        tracker.prepare(*in.depth, in.intrinsics, model, predicted, in.color);
        icp = tracker.align(predicted);
    }
    const Pose motion = inverseRigid(lastTracked_) * icp.cameraToWorld;
    const uint32_t reason = trackingLoss(icp.finalSystem, icp.finalStep.solved, icp.finalStep.conditioning, motion, recent(), bounds);
    TrackingReport report = conclude(icp, reason, icp.finalStep.conditioning, icp.cameraToWorld, predicted, bounds);
    report.modelDrawn = !reused;
    report.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return report;
}

TrackedFusion PoseTracker::trackAndFuse(GpuVolume& volume, const DepthImage& depth, const Intrinsics& intrinsics,
                                        const ColorImage* trackingColor, const ColorImage* fusedColor, const vk::SubmitSync& sync) {
    TrackedFusion out;
    if (!options_.solveOnGpu) {
        out.tracking = track(depth, intrinsics, volume, trackingColor);
        if (!out.tracking.tracked) return out;
        const auto t0 = std::chrono::steady_clock::now();
        out.fused = volume.integrate(depth, fusedColor, intrinsics, out.tracking.cameraToWorld, sync);
        out.fuseMilliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        return out;
    }
    // One submission: the tracker's passes start the volume's frame and write its pose; the volume fuses
    // nothing if track_decide lost the frame.
    const auto t0 = std::chrono::steady_clock::now();
    const TrackingInput in = trackingInput(depth, trackingColor, intrinsics);
    CameraTracker& tracker = trackerFor(*in.depth);
    tracker.checkFrame(*in.depth, in.color);   // recordPose must not throw: the frame would be half recorded
    const Pose predicted = prediction();
    const bool reused = reuseModelMaps(tracker, predicted);
    const Pose lastTracked = lastTracked_;
    const RecentFrames recentFrames = recent();
    FrameInput input = FrameInput::fromHost(depth, fusedColor, intrinsics, predicted);   // the pose is not read: the tracker's is
    input.sync = sync;
    input.recordPose = [&](VkCommandBuffer cmd, const vk::Buffer& framePose) {
        tracker.recordTrackAndDecide(cmd, *in.depth, in.intrinsics, volume, predicted, predicted, in.color, lastTracked, recentFrames, framePose);
    };
    volume.submitFrame(input);
    FrameReport frame = volume.finishFrame();
    const IcpResult icp = tracker.gpuSolvedResult();
    // The GPU's verdict is what happened (the frame was fused or not); the pose is the GPU's own estimate, the one
    // the volume fused at.
    out.tracking = conclude(icp, icp.gpuLostReason, icp.gpuConditioning, icp.gpuEstimate, predicted, options_);
    out.tracking.modelDrawn = !reused;
    out.oneSubmission = true;
    out.tracking.milliseconds = out.fuseMilliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (frame.skipped != !out.tracking.tracked)
        throw Error("tracking: the volume " + std::string(frame.skipped ? "skipped" : "fused") + " a frame that tracking " +
                    (out.tracking.tracked ? "kept" : "lost"));
    if (out.tracking.tracked) out.fused = std::move(frame);
    return out;
}

TrackingReport PoseTracker::trackFrom(const Pose& start, const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model,
                                      const ColorImage* color, const TrackerOptions* bounds) {
    const State before = state();
    lastTracked_ = start;
    velocity_ = Pose::Identity();
    modelFresh_ = false;   // drawn at `start`
    TrackingReport report = track(depth, intrinsics, model, color, bounds ? *bounds : options_);
    restore(before);
    return report;
}

IcpSystem PoseTracker::fitAt(const Pose& cameraToWorld) {
    if (!tracker_ || !tracker_->hasModelMaps()) throw Error("tracking: fitAt() before any frame was tracked");
    return icpSystem(tracker_->sums(0, cameraToWorld));
}

void PoseTracker::resumeAt(const Pose& pose, const Pose& motion) {
    lastTracked_ = pose;
    velocity_ = motion;   // not the move from the last tracked frame: that is a jump, not a motion to go on with
    modelFresh_ = false;
}

void PoseTracker::restore(const State& state) {
    lastTracked_ = state.lastTracked;
    velocity_ = state.velocity;
    recentRmse_ = state.recentRmse;
    recentShare_ = state.recentShare;
    modelFresh_ = false;
}

void PoseTracker::correctLastPose(const Pose& corrected) {
    lastTracked_ = corrected;
    modelFresh_ = false;
}

}  // namespace vkmesh::gpu
