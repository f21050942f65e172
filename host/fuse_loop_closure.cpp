#include "fuse_loop_closure.h"

#include <limits>

namespace vkmesh::cli {
namespace {

void add(gpu::CorrectionReport& total, const gpu::CorrectionReport& r) {
    total.framesRefused += r.framesRefused;
    total.blocksFreed += r.blocksFreed;
    total.observationsDropped += r.observationsDropped;
    total.milliseconds += r.milliseconds;
}

}  // namespace

void FuseLoopClosure::beforeFrame(gpu::GpuVolume& volume, gpu::MapCorrector& corrector) {
    if (corrector.pending() > 0) add(applied_, corrector.apply(volume, budget_));
}

std::optional<gpu::TrackedFusion> FuseLoopClosure::relocalise(uint32_t index, gpu::GpuVolume& volume, gpu::PoseTracker& tracker,
                                                              const DepthImage& depth, const ColorImage* trackingColor,
                                                              const ColorImage* fusedColor, const Intrinsics& intrinsics, const Pose& predicted) {
    LoopClosureFrame frame{index, &depth, trackingColor, intrinsics, predicted};
    const std::vector<Pose> candidates = closer_.relocalisationCandidates(frame);
    int tried = 0;
    std::optional<gpu::TrackedFusion> found;
    for (const Pose& candidate : candidates) {
        ++tried;
        gpu::TrackedFusion f = tracker.relocalise(volume, candidate, depth, intrinsics, trackingColor, fusedColor);
        if (f.tracking.tracked) {
            found = std::move(f);
            break;
        }
    }
    closer_.relocalisationResult(index, found.has_value(), tried);
    if (relocalised_.size() < 1000)
        relocalised_.push_back({{"frame", index}, {"relocalised", found.has_value()}, {"candidates", candidates.size()}, {"tried", tried}});
    return found;
}

void FuseLoopClosure::frameFused(uint32_t index, const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                 const Pose& pose, gpu::MapCorrector& corrector, gpu::PoseTracker& tracker) {
    const PoseCorrections moved = closer_.frameFused({index, &depth, color, intrinsics, pose});
    if (moved.empty()) return;
    corrector.correct(moved.frames, moved.poses);
    // The tracker goes on from the current frame's corrected pose: the next frame is predicted in the corrected map.
    Pose corrected;
    if (closer_.latestPose(index, corrected)) tracker.correctLastPose(corrected);
}

void FuseLoopClosure::finish(gpu::GpuVolume& volume, gpu::MapCorrector& corrector) {
    if (corrector.pending() == 0) return;
    add(applied_, corrector.apply(volume, std::numeric_limits<size_t>::max()));
    volume.publishMesh();
}

nlohmann::json FuseLoopClosure::stats() const {
    const slam::LoopClosureStats& s = closer_.stats();
    nlohmann::json ms = nlohmann::json::object();
    for (const auto& [stage, sumCount] : s.milliseconds)
        ms[stage] = {{"total", sumCount.first}, {"count", sumCount.second}, {"mean", sumCount.second ? sumCount.first / sumCount.second : 0.0}};
    ms["correction"] = {{"total", applied_.milliseconds}, {"count", applied_.framesRefused},
                        {"mean", applied_.framesRefused ? applied_.milliseconds / applied_.framesRefused : 0.0}};
    nlohmann::json loops = nlohmann::json::array();
    for (const auto& l : s.loops) {
        if (loops.size() >= 1000) break;
        loops.push_back({{"frame", l.frame}, {"keyframe_frame", l.keyframeFrame}, {"dissimilarity", l.dissimilarity}, {"accepted", l.accepted},
                         {"reason", l.reason}, {"correction_m", l.correctionMetres}, {"correction_deg", l.correctionDegrees}});
    }
    nlohmann::json rejectedBy = nlohmann::json::object();
    for (const auto& [reason, n] : s.rejectedBy) rejectedBy[reason] = n;
    return {{"enabled", true},
            {"keyframes", s.keyframes},
            {"loops_detected", s.loopsDetected},
            {"loops_accepted", s.loopsAccepted},
            {"loops_rejected", s.loopsRejected},
            {"loops_consistent", s.loopsConsistent},
            {"rejected_by", rejectedBy},
            {"lost_frames", s.lostFrames},
            {"relocalisations", s.relocalisations},
            {"relocalisation_candidates_tried", s.relocalisationCandidatesTried},
            {"frames_corrected", s.framesCorrected},
            {"frames_refused", applied_.framesRefused},
            {"observations_dropped", applied_.observationsDropped},
            {"graph_solves", s.graphSolves},
            {"ms", ms},
            {"loops", loops},
            {"relocalisation", relocalised_}};
}

}  // namespace vkmesh::cli
