#include "api/mapper.h"

#include <algorithm>
#include <limits>

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
    LoopClosure* loops = options_.loopClosure.get();
    gpu::TrackedFusion f = tracker_->trackAndFuse(*volume_, *frame.depth, frame.intrinsics, frame.color, fusedColor(frame), frame.sync);
    if (!f.tracking.tracked && loops && valid > 0) {
        // Relocalisation: tracked again from the poses of the keyframes that look like this frame.
        const Pose predicted = f.tracking.cameraToWorld;
        const std::vector<Pose> candidates =
            loops->relocalisationCandidates({frame.index, frame.depth, frame.color, frame.intrinsics, predicted});
        for (const Pose& candidate : candidates) {
            ++result.relocalisationCandidatesTried;
            gpu::TrackedFusion g = tracker_->relocalise(*volume_, candidate, *frame.depth, frame.intrinsics, frame.color, fusedColor(frame));
            if (g.tracking.tracked) {
                f = std::move(g);
                result.relocalised = true;
                break;
            }
        }
        loops->relocalisationResult(frame.index, result.relocalised, result.relocalisationCandidatesTried);
        if (stats_.relocalisations.size() < kRunStatsListLimit)
            stats_.relocalisations.push_back({frame.index, result.relocalised, candidates.size(), result.relocalisationCandidatesTried});
        if (result.relocalised) ++stats_.tracking.relocalisedFrames;
    }
    stats_.addTracking(f.tracking);
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
    const gpu::FrameReport& report = *result.fused;
    const gpu::GpuVolumeConfig& config = volume_->config();
    stats_.addFusedFrame(frame.index, report, result.fuseWallMs, config.meshMode == gpu::MeshMode::Incremental, config.touchedCapacity,
                         config.vertexCapacity);
    for (const auto& w : report.warnings) result.warnings.push_back("frame " + std::to_string(frame.index) + ": " + w);
    if (corrector_) corrector_->keep(frame.index, frame.timestamp, frame.intrinsics, result.cameraToWorld, *frame.depth, fusedColor(frame));
    // The loop closer sees every frame of a tracked run as fused (given frames are not its business).
    if (LoopClosure* loops = options_.loopClosure.get(); loops && result.tracking) {
        const PoseCorrections moved = loops->frameFused({frame.index, frame.depth, frame.color, frame.intrinsics, result.cameraToWorld});
        if (!moved.empty()) {
            corrector_->correct(moved.frames, moved.poses);
            result.loopCorrections = uint32_t(moved.frames.size());
            // Tracking goes on from this frame's corrected pose (the next frame is predicted in the corrected map).
            if (Pose corrected; loops->latestPose(frame.index, corrected)) tracker_->correctLastPose(corrected);
        }
    }
    for (FrameSink* sink : sinks_) sink->frameDone(result, frame, *volume_);
}

void Mapper::applyCorrections(size_t budget, gpu::CorrectionReport& report) {
    if (!corrector_ || corrector_->pending() == 0) return;
    report = corrector_->apply(*volume_, budget);
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
