#include "api/mapper.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "core/camera.h"
#include "core/icp_solve.h"

namespace vkmesh {

namespace {

double millisecondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

size_t validPixels(const DepthImage& depth) {
    return size_t(std::count_if(depth.meters.begin(), depth.meters.end(), [](float d) { return d > 0.0f; }));
}

double positionError(const Pose& a, const Pose& b) { return (a.block<3, 1>(0, 3) - b.block<3, 1>(0, 3)).norm(); }

}  // namespace

Mapper::Mapper(const vk::Context& context, MapperOptions options) : context_(context), options_(std::move(options)) {}

// The tracker's GPU resources and the volume's buffers go before the context they were made on (the caller's).
Mapper::~Mapper() {
    tracker_.reset();
    volume_.reset();
}

void Mapper::createVolume(int width, int height) {
    if (volume_) return;
    if (width <= 0 || height <= 0) throw Error("the first depth image is empty");
    gpu::GpuVolumeConfig config = options_.volume;
    config.imageWidth = width;
    config.imageHeight = height;
    volume_ = std::make_unique<gpu::GpuVolume>(context_, config);
}

void Mapper::loadMap(const map::MapData& map, const gpu::GpuVolumeConfig& config, const std::filesystem::path& path) {
    volume_ = gpu::GpuVolume::load(context_, map, config, path.string());
    // The loop closer's keyframes and graph saved with the map (absent: it starts empty).
    if (options_.loopClosure && std::filesystem::exists(loopClosurePathOf(path))) options_.loopClosure->load(loopClosurePathOf(path), map.saveId);
}

void Mapper::keepFrames(FrameStore store) { corrector_.emplace(std::move(store)); }

const ColorImage* Mapper::fusedColor(const MapperFrame& frame) const { return volume_->fusesColor() ? frame.color : nullptr; }

void Mapper::record(const MapperFrame& frame, const Pose& pose, bool posed) {
    trajectory_.push_back({frame.index, frame.timestamp, posed, frame.reference});
    poses_.push_back(pose);
}

void Mapper::recordGiven(const MapperFrame& frame) {
    record(frame, *frame.pose, true);
    if (tracker_) tracker_->start(*frame.pose);
    hypothesis_.reset(), lost_ = false;
    if (corrector_ && frame.depth) corrector_->keep(frame.index, frame.timestamp, frame.intrinsics, *frame.pose, *frame.depth, fusedColor(frame));
}

void Mapper::skip(uint32_t index, const std::string& reason) {
    if (!started_) started_ = true, start_ = std::chrono::steady_clock::now();
    ++stats_.skipped;
    stats_.addWarning("frame " + std::to_string(index) + " skipped: " + reason);
}

void Mapper::skipped(const MapperFrame& frame, MapperResult& result, const std::string& reason) {
    result.status = FrameStatus::Skipped;
    ++stats_.skipped;
    result.warnings.push_back("frame " + std::to_string(frame.index) + " skipped: " + reason);
    stats_.addWarning(result.warnings.back());
    for (FrameSink* sink : sinks_) sink->frameDone(result, frame, *volume_);
}

MapperResult Mapper::process(const MapperFrame& frame) {
    if (!frame.depth) throw Error("frame " + std::to_string(frame.index) + ": no depth image");
    if (!started_) started_ = true, start_ = std::chrono::steady_clock::now();
    createVolume(frame.depth->width, frame.depth->height);
    const size_t valid = validPixels(*frame.depth);
    if (volume_->fusesColor() && frame.color && !frame.color->empty()) ++stats_.framesWithColor;
    if (!frame.pose) return tracked(frame, valid);

    MapperResult result;
    result.index = frame.index;
    result.cameraToWorld = *frame.pose;
    result.posed = true;
    record(frame, *frame.pose, true);
    if (tracker_) tracker_->start(*frame.pose);   // tracking goes on from a given pose
    hypothesis_.reset(), lost_ = false;
    if (valid == 0) {
        skipped(frame, result, "no valid depth in " + frame.source);
        return result;
    }
    applyCorrections(options_.correctionsPerFrame, result.corrections);
    return fuseAt(frame, *frame.pose, std::move(result));
}

MapperResult Mapper::tracked(const MapperFrame& frame, size_t valid) {
    MapperResult result;
    result.index = frame.index;
    stats_.tracking.enabled = true;
    if (!tracker_) tracker_ = std::make_unique<gpu::PoseTracker>(context_, options_.tracker);
    const Pose lastPose = poses_.empty() ? Pose::Identity() : poses_.back();
    // The run's first tracked frame starts the map where the camera stands: at its start pose, or in an empty map
    // where the camera last was. A map that already holds frames is tracked against from there.
    const bool startsHere = volume_->framesIntegrated() == 0 || (!tracker_->started() && frame.startPose.has_value());
    if (startsHere) {
        const Pose start = frame.startPose ? *frame.startPose : tracker_->started() ? tracker_->prediction() : lastPose;
        result.cameraToWorld = start;
        if (valid == 0) {   // no pose is established for it: not in the trajectory a front end writes
            record(frame, start, false);
            skipped(frame, result, "no valid depth in " + frame.source);
            return result;
        }
        result.tracking = tracker_->start(start);
        result.posed = true;
        record(frame, start, true);
        if (frame.reference) stats_.tracking.positionError.push_back(positionError(start, *frame.reference));
        return fuseAt(frame, start, std::move(result));
    }
    if (!tracker_->started()) tracker_->start(lastPose);

    applyCorrections(options_.correctionsPerFrame, result.corrections);
    if (hypothesis_) return tentative(frame, valid, std::move(result));
    gpu::TrackedFusion f;
    const double baseline = tracker_->recentRmse();   // lost frames leave it as the last tracked ones made it
    if (lost_ && options_.relocalisation.confirmFrames > 0) {
        const gpu::PoseTracker::State atLoss = tracker_->state();
        // After a loss, tracking that picks up again from the last pose is a hypothesis as a relocalisation is: on
        // real data it picks up next to the old pose after a jump (frames 98 and 100 of ICL-NUIM office 0 without
        // frames 59-98, 1 m off).
        f.tracking = tracker_->track(*frame.depth, frame.intrinsics, *volume_, frame.color);
        const double ratio = options_.relocalisation.maxErrorRatio;
        const std::string why = f.tracking.tracked ? errorAgainstBaseline(f.tracking.rmse, baseline, ratio) : f.tracking.lostReason;
        if (why.empty()) {
            hypothesis_ = Hypothesis{frame.index, 0, f.tracking.cameraToWorld, atLoss, baseline, ratio, 0, SIZE_MAX};
            return tentativeVerdict(frame, std::move(f.tracking), std::move(result));
        }
        tracker_->restore(atLoss);
        f.tracking.tracked = false;
        f.tracking.cameraToWorld = tracker_->prediction();
        f.tracking.lostReason = why;
    } else if (const bool olderMap = wantsOlderMap(frame); olderMap || volume_->paging()) {
        // Tracked, then fused in a submission of its own (trackAndFuse's steps): registered against the older map
        // before the frame touches it; or, on a paged map, so that the blocks the tracked pose reaches come back before
        // the frame is fused (trackAndFuse computes the pose in the frame's own submission).
        f.tracking = tracker_->track(*frame.depth, frame.intrinsics, *volume_, frame.color);
        if (f.tracking.tracked) {
            if (olderMap) registerAgainstOlderMap(frame, f.tracking);
            const auto t0 = std::chrono::steady_clock::now();
            f.fused = volume_->integrate(*frame.depth, fusedColor(frame), frame.intrinsics, f.tracking.cameraToWorld, frame.sync);
            f.fuseMilliseconds = millisecondsSince(t0);
        }
    } else {
        f = tracker_->trackAndFuse(*volume_, *frame.depth, frame.intrinsics, frame.color, fusedColor(frame), frame.sync);
    }
    if (!f.tracking.tracked && options_.loopClosure && valid > 0) {
        const gpu::PoseTracker::State atLoss = tracker_->state();   // a lost frame's: no motion to predict with
        RelocalisationOutcome found = relocalise(frame, f.tracking.cameraToWorld, f.tracking.lostReason, baseline, result);
        if (found.accepted) {
            startHypothesis(frame, found, atLoss, baseline);
            // Fused once it is confirmed (options.relocalisation.confirmFrames), or now.
            if (options_.relocalisation.confirmFrames > 0) return tentativeVerdict(frame, std::move(found.tracking), std::move(result));
            return confirmRelocalisation(frame, std::move(found.tracking), std::move(result));
        }
        f.tracking.lostReason = found.tracking.lostReason;
    }
    return concludeTracked(frame, std::move(f), std::move(result));
}

bool Mapper::wantsOlderMap(const MapperFrame& frame) const {
    const uint32_t recent = options_.olderMapRecentFrames;
    return options_.loopClosure && recent > 0 && volume_->frameNumber() > recent && corrector_ && corrector_->pending() == 0 &&
           options_.loopClosure->wantsOlderMap(frame.index, tracker_->prediction());
}

void Mapper::registerAgainstOlderMap(const MapperFrame& frame, const gpu::TrackingReport& tracking) {
    const auto t0 = std::chrono::steady_clock::now();
    // The triangles whose vertices came before the last olderMapRecentFrames frames (the next is frameNumber() + 1).
    const uint32_t createdBefore = volume_->frameNumber() + 1 - options_.olderMapRecentFrames;
    // The older map covers part of the view: its share is not held against that of the frames tracked on the whole map.
    gpu::TrackerOptions bounds = tracker_->options();
    bounds.minShareOfRecent = 0;
    bounds.minInlierFraction = options_.olderMapMinInlierFraction;
    const gpu::TrackingReport r = tracker_->trackFrom(tracking.cameraToWorld, *frame.depth, frame.intrinsics,
                                                      gpu::TrackingModel::olderMap(*volume_, createdBefore), frame.color, &bounds);
    OlderMapRegistration older;
    older.tracked = r.tracked;
    older.cameraToWorld = r.cameraToWorld;
    if (r.tracked) {
        // The older map's fit at both poses, on the same maps: a registration that slid along what geometry leaves
        // free fits no better than the tracked pose (ICL-NUIM office 0: 1.2 mm at both, 3.8 cm apart), a measured
        // drift fits far better (the gallery: 22.1 -> 5.0 mm).
        older.rmse = tracker_->fitAt(r.cameraToWorld).rmse();
        older.rmseAtTracked = tracker_->fitAt(tracking.cameraToWorld).rmse();
    }
    older.milliseconds = millisecondsSince(t0);
    olderMap_ = {frame.index, older};
}

Mapper::RelocalisationOutcome Mapper::relocalise(const MapperFrame& frame, const Pose& predicted, const std::string& lostReason,
                                                 double baseline, MapperResult& result) {
    LoopClosure& loops = *options_.loopClosure;
    const MapperOptions::Relocalisation& o = options_.relocalisation;
    const std::vector<RelocalisationCandidate> candidates = loops.relocalisationCandidates({frame.index, frame.depth, frame.color, frame.intrinsics, predicted});
    RunStats::Relocalisation attempt;
    attempt.frame = frame.index;
    attempt.candidates = candidates.size();
    attempt.placedCandidates = size_t(std::count_if(candidates.begin(), candidates.end(), [](const RelocalisationCandidate& c) { return c.placed; }));
    // Every candidate is tracked from (a few): the map must match the frame at one place only. Each must also
    // match as closely as the frames tracked before the loss did (`baseline`: a look-alike matches, but worse).
    RelocalisationOutcome out;
    std::optional<gpu::TrackingReport> best;
    int bestCandidate = 0;
    bool bestPlaced = false;   // placed by the features, and tracking agreed: held to placedMaxErrorRatio
    std::string refusals;
    for (size_t c = 0; c < candidates.size(); ++c) {
        const RelocalisationCandidate& candidate = candidates[c];
        gpu::TrackingReport r = tracker_->trackFrom(candidate.cameraToWorld, *frame.depth, frame.intrinsics, *volume_, frame.color);
        ++result.relocalisationCandidatesTried;
        const Pose fromPlaced = inverseRigid(candidate.cameraToWorld) * r.cameraToWorld;
        const bool agrees = candidate.placed && translationMetres(fromPlaced) <= o.placedAgreeMetres && rotationDegrees(fromPlaced) <= o.placedAgreeDegrees;
        const double ratio = agrees ? o.placedMaxErrorRatio : o.maxErrorRatio;
        std::string why = r.tracked ? errorAgainstBaseline(r.rmse, baseline, ratio) : r.lostReason;
        const Pose apart = best ? Pose(inverseRigid(best->cameraToWorld) * r.cameraToWorld) : Pose(Pose::Identity());
        if (why.empty() && (translationMetres(apart) > o.ambiguousMetres || rotationDegrees(apart) > o.ambiguousDegrees)) {
            char text[160];
            std::snprintf(text, sizeof text, "ambiguous: candidates %d and %zu match the frame at places %.2f m apart", bestCandidate,
                          c + 1, translationMetres(apart));
            out.tracking = std::move(r);
            out.tracking.tracked = false;
            out.tracking.lostReason = text;
            best.reset();
            break;
        }
        if (why.empty()) {
            if (!best || r.rmse < best->rmse) best = r, bestCandidate = int(c + 1), bestPlaced = agrees;
        } else {
            refusals += (refusals.empty() ? "" : "; ") + ("candidate " + std::to_string(c + 1) + ": " + why);
            if (!best && out.tracking.lostReason.empty()) out.tracking = r;   // the numbers of the first refused, for the report
        }
    }
    if (best) {
        out.accepted = true;
        out.candidate = bestCandidate;
        out.maxErrorRatio = bestPlaced ? o.placedMaxErrorRatio : o.maxErrorRatio;
        out.statsEntry = stats_.relocalisations.size();
        out.tracking = std::move(*best);
        out.tracking.lostReason = "lost (" + lostReason + "), relocalised from candidate " + std::to_string(bestCandidate);
    } else {
        if (out.tracking.lostReason.rfind("ambiguous", 0) != 0)
            out.tracking.lostReason = lostReason + (candidates.empty() ? "; no keyframe looks alike" : "; relocalisation refused (" + refusals + ")");
        out.tracking.cameraToWorld = predicted;
        loops.relocalisationResult(frame.index, false, result.relocalisationCandidatesTried);
    }
    attempt.tried = result.relocalisationCandidatesTried;
    attempt.inlierShare = out.tracking.inlierShare();
    attempt.rmse = out.tracking.rmse;
    attempt.reason = out.accepted ? std::string() : out.tracking.lostReason;
    attempt.tentative = out.accepted;
    attempt.placed = out.accepted && bestPlaced;
    if (stats_.relocalisations.size() < kRunStatsListLimit) stats_.relocalisations.push_back(attempt);
    return out;
}

void Mapper::startHypothesis(const MapperFrame& frame, const RelocalisationOutcome& found, const gpu::PoseTracker::State& atLoss,
                             double baseline) {
    hypothesis_ = Hypothesis{frame.index, found.candidate, found.tracking.cameraToWorld, atLoss, baseline, found.maxErrorRatio, 0, found.statsEntry};
    tracker_->resumeAt(found.tracking.cameraToWorld);
}

std::string Mapper::errorAgainstBaseline(double rmse, double baseline, double ratio) const {
    const double limit = ratio * baseline;
    if (baseline <= 0 || rmse <= limit) return {};
    char text[160];
    std::snprintf(text, sizeof text, "its error %.4f m is over %.1f times that of the frames tracked before the loss (%.4f m)", rmse,
                  ratio, baseline);
    return text;
}

std::string Mapper::placedElsewhere(const std::vector<RelocalisationCandidate>& placed, const Pose& tracked) const {
    const MapperOptions::Relocalisation& o = options_.relocalisation;
    const gpu::TrackerOptions& t = tracker_->options();
    double nearest = std::numeric_limits<double>::infinity();
    for (const RelocalisationCandidate& candidate : placed) {
        if (!candidate.placed) continue;
        const Pose apart = inverseRigid(candidate.cameraToWorld) * tracked;
        if (translationMetres(apart) <= o.placedAgreeMetres && rotationDegrees(apart) <= o.placedAgreeDegrees) return {};
        if (translationMetres(apart) <= t.maxJumpMetres && rotationDegrees(apart) <= t.maxJumpDegrees)
            nearest = std::min(nearest, translationMetres(apart));
    }
    if (!std::isfinite(nearest)) return {};
    char text[160];
    std::snprintf(text, sizeof text, "its ORB features place it %.3f m from where tracking from the hypothesis put it", nearest);
    return text;
}

MapperResult Mapper::tentative(const MapperFrame& frame, size_t valid, MapperResult result) {
    Hypothesis& h = *hypothesis_;
    gpu::TrackingReport r = tracker_->track(*frame.depth, frame.intrinsics, *volume_, frame.color);
    std::string why = r.tracked ? errorAgainstBaseline(r.rmse, h.baselineRmse, h.maxErrorRatio) : r.lostReason;
    // Geometry alone can let a hypothesis's frames slide: after a landing onto a wall, tracking from the hypothesis
    // matched the wall as well as the frames before the loss matched theirs, 9-11 cm along it (ICL-NUIM, frames
    // 0-129 then 160-251: the confirming frame was fused 9 cm off). The frame's features, where they place it, must
    // agree with tracking (LoopClosure::placements: the hypothesis's candidate, which confirmation reports, is left
    // as it was).
    if (why.empty() && valid > 0 && options_.loopClosure)
        why = placedElsewhere(options_.loopClosure->placements({frame.index, frame.depth, frame.color, frame.intrinsics, r.cameraToWorld}),
                              r.cameraToWorld);
    if (!why.empty()) {
        // Not tracked from the hypothesis (after a relocalisation the camera's motion is unknown: a fast one is
        // not followed from a standstill): found again from the keyframes at a place it could have moved to from
        // the hypothesis, it agrees; elsewhere or not found, the hypothesis was wrong.
        const std::string lostFromIt = "frame " + std::to_string(frame.index) + " tracked from the relocalisation at frame " +
                                       std::to_string(h.frame) + " is lost: " + why;
        RelocalisationOutcome found;
        if (valid > 0 && options_.loopClosure) found = relocalise(frame, h.pose, lostFromIt, h.baselineRmse, result);
        else found.tracking.lostReason = lostFromIt;
        const Pose moved = inverseRigid(h.pose) * found.tracking.cameraToWorld;
        const gpu::TrackerOptions& t = tracker_->options();
        if (found.accepted && translationMetres(moved) <= t.maxJumpMetres && rotationDegrees(moved) <= t.maxJumpDegrees) {
            h.candidate = found.candidate;   // of the loop closer's latest candidates
            h.maxErrorRatio = found.maxErrorRatio;
            h.pose = found.tracking.cameraToWorld;
            tracker_->resumeAt(h.pose, moved);
            r = std::move(found.tracking);
        } else {
            // The relocalisation was wrong (or the camera moved on too fast to tell): back to lost, as before it.
            const std::string reason = "the relocalisation at frame " + std::to_string(h.frame) + " is refused: " + lostFromIt;
            if (h.statsEntry < stats_.relocalisations.size()) stats_.relocalisations[h.statsEntry].refusedBy = reason;
            const Hypothesis refused = h;
            tracker_->restore(refused.before);
            hypothesis_.reset();
            if (found.accepted) {   // found elsewhere: a new hypothesis
                startHypothesis(frame, found, refused.before, refused.baselineRmse);
                return tentativeVerdict(frame, std::move(found.tracking), std::move(result));
            }
            gpu::TrackedFusion f;
            f.tracking = std::move(r);
            f.tracking.tracked = false;
            f.tracking.cameraToWorld = tracker_->prediction();
            f.tracking.lostReason = reason + "; " + found.tracking.lostReason;
            return concludeTracked(frame, std::move(f), std::move(result));
        }
    } else {
        h.pose = r.cameraToWorld;
    }
    if (++h.confirmed < options_.relocalisation.confirmFrames) return tentativeVerdict(frame, std::move(r), std::move(result));
    return confirmRelocalisation(frame, std::move(r), std::move(result));
}

MapperResult Mapper::tentativeVerdict(const MapperFrame& frame, gpu::TrackingReport tracking, MapperResult result) {
    const Hypothesis& h = *hypothesis_;
    tracking.tracked = false;   // not fused: for a caller (and the tracked frames' statistics), lost until confirmed
    stats_.addTracking(tracking);
    const std::string why = "tentative: tracked from the relocalisation at frame " + std::to_string(h.frame) + ", not fused until " +
                            std::to_string(options_.relocalisation.confirmFrames) + " more frames agree with the map (" +
                            std::to_string(h.confirmed) + " so far)";
    if (stats_.tracking.verdicts.size() < kRunStatsListLimit)
        stats_.tracking.verdicts.push_back({frame.index, "tentative", tracking.inlierShare(), tracking.rmse, tracking.conditioning, why});
    ++stats_.tracking.tentativeFrames;
    tracking.lostReason = why;
    result.status = FrameStatus::Tentative;
    result.cameraToWorld = tracking.cameraToWorld;
    result.posed = true;
    record(frame, result.cameraToWorld, true);
    if (frame.reference) stats_.tracking.positionError.push_back(positionError(result.cameraToWorld, *frame.reference));
    result.tracking = std::move(tracking);
    for (FrameSink* sink : sinks_) sink->frameDone(result, frame, *volume_);
    return result;
}

MapperResult Mapper::confirmRelocalisation(const MapperFrame& frame, gpu::TrackingReport tracking, MapperResult result) {
    const Hypothesis h = *hypothesis_;
    hypothesis_.reset();
    if (h.candidate > 0) {   // from a keyframe (else picked up from the last pose)
        options_.loopClosure->relocalisationResult(h.frame, true, h.candidate);
        if (h.statsEntry < stats_.relocalisations.size()) {
            stats_.relocalisations[h.statsEntry].relocalised = true;
            stats_.relocalisations[h.statsEntry].confirmedAt = int64_t(frame.index);
        }
        ++stats_.tracking.relocalisedFrames;
        result.relocalised = true;
    }
    const auto t0 = std::chrono::steady_clock::now();
    gpu::TrackedFusion f;
    f.fused = volume_->integrate(*frame.depth, fusedColor(frame), frame.intrinsics, tracking.cameraToWorld, frame.sync);
    f.fuseMilliseconds = millisecondsSince(t0);
    f.tracking = std::move(tracking);
    return concludeTracked(frame, std::move(f), std::move(result));
}

MapperResult Mapper::concludeTracked(const MapperFrame& frame, gpu::TrackedFusion f, MapperResult result) {
    stats_.addTracking(f.tracking);
    if (stats_.tracking.verdicts.size() < kRunStatsListLimit)
        stats_.tracking.verdicts.push_back({frame.index, !f.tracking.tracked ? "lost" : result.relocalised ? "relocalised" : "tracked",
                                            f.tracking.inlierShare(), f.tracking.rmse, f.tracking.conditioning, f.tracking.lostReason});
    result.oneSubmission = f.oneSubmission;
    result.cameraToWorld = f.tracking.cameraToWorld;
    result.posed = true;
    record(frame, result.cameraToWorld, true);
    if (frame.reference) stats_.tracking.positionError.push_back(positionError(result.cameraToWorld, *frame.reference));
    const bool isTracked = f.tracking.tracked;
    result.tracking = std::move(f.tracking);
    if (!isTracked) {
        // A frame the tracker is not sure of stays out of the map: it keeps the predicted pose, nothing is fused.
        result.status = FrameStatus::Lost;
        // A frame lost for want of depth says nothing about where the camera is; one that disagreed with the map
        // makes tracking that picks up again a hypothesis (tracked()).
        if (result.tracking->validPixels > 0) lost_ = true;
        ++stats_.tracking.lostFrames;
        if (stats_.tracking.lost.size() < kRunStatsListLimit) stats_.tracking.lost.push_back({frame.index, result.tracking->lostReason});
        result.warnings.push_back("frame " + std::to_string(frame.index) + " lost (not fused): " + result.tracking->lostReason);
        stats_.addWarning(result.warnings.back());
        for (FrameSink* sink : sinks_) sink->frameDone(result, frame, *volume_);
        return result;
    }
    result.fused = std::move(f.fused);
    result.fuseWallMs = f.fuseMilliseconds;
    finishFrame(frame, result);
    return result;
}

MapperResult Mapper::fuseAt(const MapperFrame& frame, const Pose& pose, MapperResult result) {
    const auto t0 = std::chrono::steady_clock::now();
    result.fused = volume_->integrate(*frame.depth, fusedColor(frame), frame.intrinsics, pose, frame.sync);
    result.fuseWallMs = millisecondsSince(t0);
    finishFrame(frame, result);
    return result;
}

void Mapper::finishFrame(const MapperFrame& frame, MapperResult& result) {
    result.status = FrameStatus::Fused;
    lost_ = false;
    const gpu::FrameReport& report = *result.fused;
    const gpu::GpuVolumeConfig& config = volume_->config();
    stats_.addFusedFrame(frame.index, report, result.fuseWallMs, config.meshMode == gpu::MeshMode::Incremental, config.touchedCapacity,
                         config.vertexCapacity);
    for (const auto& w : report.warnings) result.warnings.push_back("frame " + std::to_string(frame.index) + ": " + w);
    if (corrector_) corrector_->keep(frame.index, frame.timestamp, frame.intrinsics, result.cameraToWorld, *frame.depth, fusedColor(frame));
    // The loop closer sees every frame of a tracked run as fused (given frames are not its business).
    if (LoopClosure* loops = options_.loopClosure.get(); loops && result.tracking) {
        const OlderMapRegistration* older = olderMap_ && olderMap_->first == frame.index ? &olderMap_->second : nullptr;
        const PoseCorrections moved = loops->frameFused({frame.index, frame.depth, frame.color, frame.intrinsics, result.cameraToWorld, older});
        olderMap_.reset();
        if (!moved.empty()) {
            corrector_->correct(moved.frames, moved.poses);
            result.loopCorrections = uint32_t(moved.frames.size());
            correctionBurst_ = options_.correctionsAfterLoop;
            // Tracking goes on from this frame's corrected pose (the next frame is predicted in the corrected map).
            if (Pose corrected; loops->latestPose(frame.index, corrected)) tracker_->correctLastPose(corrected);
        }
    }
    for (FrameSink* sink : sinks_) sink->frameDone(result, frame, *volume_);
}

void Mapper::applyCorrections(size_t budget, gpu::CorrectionReport& report) {
    if (!corrector_ || corrector_->pending() == 0) return;
    // Right after a loop closed, the newest frames it moved: the surface the camera sees next.
    const bool afterLoop = correctionBurst_ > 0;
    report = corrector_->apply(*volume_, std::max(budget, std::exchange(correctionBurst_, 0)),
                               afterLoop ? gpu::MapCorrector::Order::Newest : gpu::MapCorrector::Order::LargestChange);
    stats_.addCorrections(report);
    for (uint32_t index : report.frames) {
        auto at = std::lower_bound(trajectory_.begin(), trajectory_.end(), index,
                                   [](const TrajectoryEntry& e, uint32_t i) { return e.index < i; });
        if (at != trajectory_.end() && at->index == index) poses_[size_t(at - trajectory_.begin())] = corrector_->store().pose(index);
    }
}

void Mapper::correct(const std::vector<uint32_t>& frames, const std::vector<Pose>& poses) {
    if (!corrector_)
        throw Error("correct: no frames are kept (Reconstructor: keepFrames, Python keep_frames=True; vkmesh fuse: --save or "
                    "--keep-frames), so a fused frame cannot be taken out again");
    corrector_->correct(frames, poses);
}

std::optional<gpu::FrameReport> Mapper::finishCorrections(gpu::CorrectionReport* applied, bool publish) {
    if (!volume_ || pendingCorrections() == 0) return std::nullopt;
    gpu::CorrectionReport report;
    applyCorrections(std::numeric_limits<size_t>::max(), report);
    if (applied) *applied = report;
    if (!publish) return std::nullopt;
    return volume_->publishMesh();
}

void Mapper::finish() {
    finishCorrections();
    if (const LoopClosure* loops = options_.loopClosure.get())
        for (size_t k = 0; k < trajectory_.size(); ++k)
            if (Pose latest; trajectory_[k].posed && loops->latestPose(trajectory_[k].index, latest)) poses_[k] = latest;
    stats_.finalPositionError.clear();
    for (size_t k = 0; k < trajectory_.size(); ++k)
        if (trajectory_[k].posed && trajectory_[k].reference) stats_.finalPositionError.push_back(positionError(poses_[k], *trajectory_[k].reference));
    if (started_) stats_.fusionSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

uint64_t Mapper::save(const std::filesystem::path& path) {
    if (!volume_) throw Error("cannot save " + path.string() + ": no frame has been integrated yet");
    const uint64_t saveId = volume_->save(path);
    // Queued corrections are not saved: the store holds the poses the map was fused at.
    if (corrector_) corrector_->store().save(gpu::frameStorePathOf(path).string(), saveId);
    if (options_.loopClosure) options_.loopClosure->save(loopClosurePathOf(path), saveId);
    return saveId;
}

RunStats Mapper::stats() const {
    RunStats s = stats_;
    if (options_.loopClosure) s.loopClosure = options_.loopClosure->stats();
    return s;
}

}  // namespace vkmesh
