#include "slam/loop_closer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include "core/camera.h"
#include "gpu/tracking/pose_tracker.h"

namespace vkmesh::slam {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;

}  // namespace

LoopCloser::LoopCloser(const LoopClosureOptions& options) : options_(options), ferns_(options.ferns) {
    gpu::trackParamsFor(options.tracker);   // checked now
    if (options.registrationWidth < 40 || options.candidates < 1 || options.relocaliseCandidates < 1 || !(options.keyframeMetres > 0) ||
        !(options.keyframeDegrees > 0))
        throw Error("loop closure: the registration must be at least 40 pixels wide, candidates at least 1 and the keyframe spacing positive");
}

void LoopCloser::time(const std::string& stage, double ms) {
    auto& [sum, count] = stats_.milliseconds[stage];
    sum += ms;
    ++count;
}

bool LoopCloser::latestPose(uint32_t frame, Pose& pose) const {
    const auto it = frames_.find(frame);
    if (it == frames_.end()) return false;
    pose = graph_.pose(keyframes_[size_t(it->second.keyframe)].node) * it->second.relative;
    return true;
}

PoseCorrections LoopCloser::corrections() {
    PoseCorrections out;
    for (auto& [index, fused] : frames_) {
        const Pose pose = graph_.pose(keyframes_[size_t(fused.keyframe)].node) * fused.relative;
        const Pose moved = inverseRigid(fused.handed) * pose;
        // Re-fusing a frame costs two frames' fusion: not for a move far below a voxel.
        if (translationMetres(moved) < options_.minCorrectionMetres && rotationDegrees(moved) < options_.minCorrectionDegrees) continue;
        fused.handed = pose;
        out.frames.push_back(index);
        out.poses.push_back(pose);
    }
    return out;
}

PoseCorrections LoopCloser::frameFused(const LoopClosureFrame& frame) {
    const auto t0 = Clock::now();
    if (!frame.depth) throw Error("loop closure: frame " + std::to_string(frame.index) + " has no depth");
    // The path travelled (a relocalised frame's jump is not travel).
    if (lastPose_ && !relocalisedFrom_) pathMetres_ += translationMetres(inverseRigid(*lastPose_) * frame.cameraToWorld);
    lastPose_ = frame.cameraToWorld;

    // A keyframe when the camera moved or turned far enough from the last one (the first frame is one, and so is
    // a relocalised frame: the chain of odometry edges broke there).
    bool newKeyframe = keyframes_.empty() || relocalisedFrom_.has_value();
    if (!newKeyframe) {
        const Pose moved = inverseRigid(graph_.pose(keyframes_.back().node)) * frame.cameraToWorld;
        newKeyframe = translationMetres(moved) >= options_.keyframeMetres || rotationDegrees(moved) >= options_.keyframeDegrees;
    }
    PoseCorrections result;
    if (!newKeyframe) {
        const Keyframe& k = keyframes_.back();
        frames_[frame.index] = {int(keyframes_.size()) - 1, inverseRigid(graph_.pose(k.node)) * frame.cameraToWorld, frame.cameraToWorld};
        time("frame", msSince(t0));
        return result;
    }

    auto t = Clock::now();
    Keyframe key;
    key.frame = frame.index;
    key.code = ferns_.encode(ferns_.shrink(*frame.depth, frame.color));
    time("encode", msSince(t));
    t = Clock::now();
    DepthImage small = *frame.depth;
    int halvings = 0;
    while (small.width > options_.registrationWidth && small.width % 2 == 0 && small.height % 2 == 0) {
        small = gpu::halveTrackingDepth(small, 3.0f * options_.tracker.filterDepthSigma);
        ++halvings;
    }
    key.depth = std::move(small);
    key.intrinsics = pyramidLevelIntrinsics(frame.intrinsics, halvings);
    key.pathMetres = pathMetres_;
    key.node = graph_.addNode(frame.cameraToWorld);
    const int id = int(keyframes_.size());
    if (relocalisedFrom_) {
        // Tied to the keyframe it was relocalised from, as precisely as a registration: tracking against the mesh
        // from that keyframe's pose measured where this frame is relative to it.
        const Keyframe& from = keyframes_[size_t(*relocalisedFrom_)];
        graph_.addEdge({from.node, key.node, inverseRigid(graph_.pose(from.node)) * frame.cameraToWorld,
                        diagonalInformation(options_.loopSigmaMetres, options_.loopSigmaDegrees * kRadiansPerDegree), false});
        relocalisedFrom_.reset();
    } else if (id > 0) {
        const Keyframe& previous = keyframes_.back();
        Pose motion = inverseRigid(graph_.pose(previous.node)) * frame.cameraToWorld;
        // The tracked motion is measured against the mesh: when the camera comes back to a place mapped before,
        // frame-to-model tracking snaps onto the old surface, and the drift of the way there ends up in this one
        // motion. The same motion registered frame to frame (independent of the mesh) does not contain it; where
        // the two disagree, the edge takes the registered one, so that a loop closed later spreads the snap back
        // over the way it accumulated (a consistent trajectory keeps the tracked motions: no registration noise).
        currentRegistration_ = registrationFrame(key.depth, key.intrinsics, options_.tracker, options_.registrationWidth);
        if (options_.odometryCheck && !previousRegistration_.empty()) {
            const auto tr = Clock::now();
            const Registration r = registerFrame(currentRegistration_, previousRegistration_, graph_.pose(previous.node), frame.cameraToWorld,
                                                 options_.tracker);
            if (verified(r, frame.cameraToWorld).empty()) {
                const Pose registered = inverseRigid(graph_.pose(previous.node)) * r.cameraToWorld;
                const Pose disagreement = inverseRigid(motion) * registered;
                if (translationMetres(disagreement) > options_.odometryCheckMetres || rotationDegrees(disagreement) > options_.odometryCheckDegrees) {
                    motion = registered;
                    ++stats_.odometryRegistered;
                }
            }
            time("odometry", msSince(tr));
        }
        const double sigmaMetres = options_.odometrySigmaMetres + options_.odometrySigmaPerMetre * translationMetres(motion);
        const double sigmaDegrees = options_.odometrySigmaDegrees + options_.odometrySigmaPerDegree * rotationDegrees(motion);
        graph_.addEdge({previous.node, key.node, motion, diagonalInformation(sigmaMetres, sigmaDegrees * kRadiansPerDegree), false});
    }
    if (currentRegistration_.empty())
        currentRegistration_ = registrationFrame(key.depth, key.intrinsics, options_.tracker, options_.registrationWidth);
    keyframes_.push_back(std::move(key));
    frames_[frame.index] = {id, Pose::Identity(), frame.cameraToWorld};
    ++stats_.keyframes;
    time("keyframe", msSince(t));

    // Loop candidates: old enough keyframes whose codes look alike, most alike first (ties: the older first).
    t = Clock::now();
    const Keyframe& current = keyframes_.back();
    std::vector<std::pair<double, int>> alike;
    for (int k = 0; k + options_.minKeyframeGap <= id; ++k) {
        if (keyframes_[size_t(k)].frame + options_.minFrameGap > current.frame) continue;
        const double d = RandomFerns::dissimilarity(current.code, keyframes_[size_t(k)].code);
        if (d <= options_.loopDissimilarity) alike.emplace_back(d, k);
    }
    std::sort(alike.begin(), alike.end());
    if (alike.size() > size_t(options_.candidates)) alike.resize(size_t(options_.candidates));
    time("search", msSince(t));
    if (!alike.empty()) {
        for (const auto& [d, k] : alike) {
            const LoopOutcome outcome = tryLoop(current, currentRegistration_, k, d);
            if (outcome == LoopOutcome::Closed) {
                result = corrections();
                stats_.framesCorrected += uint32_t(result.frames.size());
            }
            if (outcome != LoopOutcome::Rejected) break;
        }
    }
    previousRegistration_ = std::move(currentRegistration_);
    currentRegistration_ = {};
    time("frame", msSince(t0));
    return result;
}

std::string LoopCloser::verified(const Registration& r, const Pose& initial) const {
    const Pose motion = inverseRigid(initial) * r.cameraToWorld;
    gpu::TrackerOptions checks = options_.tracker;
    checks.maxJumpMetres = checks.maxJumpDegrees = 1e9;   // the plausibility test bounds a loop's correction
    const uint32_t verdict = gpu::trackingLoss(r.system, r.solved, r.conditioning, motion, 0.0, checks);
    if (verdict != gpu::TRACK_TRACKED) return gpu::lossText(verdict, r.system, r.conditioning, motion, 0.0, checks);
    if (r.inlierShare() < options_.minInlierShare)
        return "inliers cover " + std::to_string(int(std::lround(100 * r.inlierShare()))) + " % of the frame";
    if (r.system.rmse() > options_.maxRmse) return "RMSE " + std::to_string(r.system.rmse()) + " m";
    return "";
}

LoopCloser::LoopOutcome LoopCloser::tryLoop(const Keyframe& current, const RegistrationFrame& currentFrame, int candidate, double dissimilarity) {
    ++stats_.loopsDetected;
    const Keyframe& old = keyframes_[size_t(candidate)];
    LoopClosureStats::Loop loop;
    loop.frame = current.frame;
    loop.keyframeFrame = old.frame;
    loop.dissimilarity = dissimilarity;
    auto reject = [&](const std::string& reason) {
        loop.reason = reason;
        ++stats_.loopsRejected;
        ++stats_.rejectedBy[reason.substr(0, reason.find(':'))];
        stats_.loops.push_back(loop);
        return LoopOutcome::Rejected;
    };

    // Verification: the tracker's ICP against the old keyframe's depth, from where tracking thinks the camera is,
    // and from the old keyframe's own pose when that fails (a larger drift than the gates catch).
    auto t = Clock::now();
    const RegistrationFrame oldFrame = registrationFrame(old.depth, old.intrinsics, options_.tracker, options_.registrationWidth);
    const Pose oldPose = graph_.pose(old.node), currentPose = graph_.pose(current.node);
    std::string failure;
    std::optional<Registration> match;
    for (const Pose& initial : {currentPose, oldPose}) {
        const Registration r = registerFrame(currentFrame, oldFrame, oldPose, initial, options_.tracker);
        failure = verified(r, initial);
        if (failure.empty()) {
            match = r;
            break;
        }
    }
    time("verify", msSince(t));
    if (!match) return reject("registration: " + failure);

    // Plausibility: no further than tracking can have drifted along the path between the two keyframes.
    const Pose correction = inverseRigid(currentPose) * match->cameraToWorld;
    loop.correctionMetres = translationMetres(correction);
    loop.correctionDegrees = rotationDegrees(correction);
    const double path = current.pathMetres - old.pathMetres;
    const double maxMetres = options_.driftBaseMetres + options_.driftPerMetre * path;
    const double maxDegrees = options_.driftBaseDegrees + options_.driftDegreesPerMetre * path;
    if (loop.correctionMetres > maxMetres || loop.correctionDegrees > maxDegrees)
        return reject("implausible: moves the camera " + std::to_string(loop.correctionMetres) + " m, " +
                      std::to_string(loop.correctionDegrees) + " degrees after " + std::to_string(path) + " m of path");

    // A loop that agrees with the trajectory within what a registration at registration size can tell corrects
    // nothing: no edge, no solve (re-solving for a registration's noise moved poses by its noise: TUM fr1/rpy's and
    // ICL-NUIM's ATE got worse).
    if (loop.correctionMetres < options_.minLoopCorrectionMetres && loop.correctionDegrees < options_.minLoopCorrectionDegrees) {
        ++stats_.loopsConsistent;
        loop.accepted = true;
        loop.reason = "consistent";
        stats_.loops.push_back(loop);
        return LoopOutcome::Consistent;
    }

    // The loop edge, the solve, and the check that the loop now fits.
    t = Clock::now();
    const std::vector<Pose> before = graph_.poses();
    const int edge = graph_.addEdge({old.node, current.node, inverseRigid(oldPose) * match->cameraToWorld,
                                     diagonalInformation(options_.loopSigmaMetres, options_.loopSigmaDegrees * kRadiansPerDegree), true});
    graph_.optimise(50, options_.huber);
    ++stats_.graphSolves;
    const double error = graph_.whitenedError(size_t(edge));
    time("solve", msSince(t));
    if (!(error <= options_.maxLoopError)) {
        graph_.removeLastEdge();
        graph_.setPoses(before);
        return reject("graph: the loop stays " + std::to_string(error) + " standard deviations off after the solve");
    }
    ++stats_.loopsAccepted;
    loop.accepted = true;
    stats_.loops.push_back(loop);
    return LoopOutcome::Closed;
}

std::vector<Pose> LoopCloser::relocalisationCandidates(const LoopClosureFrame& frame) {
    const auto t = Clock::now();
    ++stats_.lostFrames;
    lastCandidates_.clear();
    std::vector<Pose> poses;
    if (!frame.depth || keyframes_.empty()) return poses;
    const FernCode code = ferns_.encode(ferns_.shrink(*frame.depth, frame.color));
    std::vector<std::pair<double, int>> alike;
    for (int k = 0; k < int(keyframes_.size()); ++k) {
        const double d = RandomFerns::dissimilarity(code, keyframes_[size_t(k)].code);
        if (d <= options_.relocaliseDissimilarity) alike.emplace_back(d, k);
    }
    std::sort(alike.begin(), alike.end());
    for (const auto& [d, k] : alike) {
        if (int(poses.size()) >= options_.relocaliseCandidates) break;
        lastCandidates_.push_back(k);
        poses.push_back(graph_.pose(keyframes_[size_t(k)].node));
    }
    time("relocalise_search", msSince(t));
    return poses;
}

void LoopCloser::relocalisationResult(uint32_t, bool relocalised, int candidatesTried) {
    stats_.relocalisationCandidatesTried += uint32_t(std::max(candidatesTried, 0));
    if (!relocalised) return;
    if (candidatesTried < 1 || size_t(candidatesTried) > lastCandidates_.size())
        throw Error("loop closure: relocalised by candidate " + std::to_string(candidatesTried) + " of " + std::to_string(lastCandidates_.size()));
    ++stats_.relocalisations;
    relocalisedFrom_ = lastCandidates_[size_t(candidatesTried) - 1];
}

}  // namespace vkmesh::slam
