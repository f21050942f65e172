// The one frame loop of vkmesh. A Mapper owns a run: the GPU volume, the camera tracker, the map corrector (the
// kept frames) and the loop closer, and the sequence every frame goes through:
//
//   given pose ─────────────────────────────────────────────┐
//   no pose ── track against the mesh ── lost? ── relocalise ┤   (the loop closer's keyframes; still lost: not fused)
//                                                            ▼
//   queued corrections re-fused (correctionsPerFrame) ── fuse (allocate, fuse, mesh) ── keep the frame (frame store)
//        ── the loop closer sees it (an accepted loop queues corrections) ── sinks (trajectory, deltas, viewer,
//           pictures) ── RunStats
//   (a tracked frame the loop closer asks for, wantsOlderMap, is also registered against the older map before it
//   is fused; the loop closer sees that registration with it)
//
// Front ends only feed it: `vkmesh fuse` and `vkmesh soak` read their frames and hand them over, Reconstructor
// (the embedding and Python API) wraps one, and each attaches the sinks it needs.
//
//   vkmesh::Mapper mapper(context, options);
//   for each frame: mapper.process(frame);       // MapperFrame: images, intrinsics, a pose or none (track)
//   mapper.finish();                              // the corrections still queued, the final poses
//   mapper.stats(), mapper.trajectory(), mapper.volume().exportMesh()
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "api/loop_closure.h"
#include "api/run_stats.h"
#include "core/frame_store.h"
#include "core/map_format.h"
#include "core/types.h"
#include "gpu/gpu_volume.h"
#include "gpu/map_corrector.h"
#include "gpu/tracking/pose_tracker.h"
#include "vk/context.h"

namespace vkmesh {

struct MapperOptions {
    // Voxel size, truncation, capacities, mesh mode, ... An image size of 0 is taken from the first frame.
    gpu::GpuVolumeConfig volume;
    // Camera tracking for frames without a pose (docs/TRACKING.md); the tracker is created at the first such frame.
    gpu::TrackerOptions tracker;
    // Queued corrections re-fused before each frame (a de-integration and an integration each); finish() and
    // finishCorrections() re-fuse the rest.
    size_t correctionsPerFrame = 2;
    // ... and before the frame after a loop closed, at least this many: the frames the loop moved most (the most
    // recent) are the surface the camera sees next, and tracking against them left at their old poses pulls the
    // camera back to where the loop showed it was not.
    size_t correctionsAfterLoop = 30;
    // Loop closure and relocalisation for tracked frames (docs/LOOP_CLOSURE.md); needs kept frames (keepFrames()).
    std::shared_ptr<LoopClosure> loopClosure;
    // Loops against the older map (docs/LOOP_CLOSURE.md): at a frame the loop closer asks for (wantsOlderMap), the
    // tracked frame is registered, before it is fused, against the surface made before the volume's last
    // olderMapRecentFrames frames (ElasticFusion's inactive model: what the recent drift has not reached): the
    // triangles whose three vertices are older (a vertex keeps its age while the surface moves along its edge; a
    // revisit fuses into old blocks, so the blocks' last-seen frame would leave only the newest sliver of them).
    // Not while corrections are queued (the map is half corrected). 0: never.
    uint32_t olderMapRecentFrames = 30;
    // The registration's loss checks are tracking's, except that the older map covers part of the view: it must
    // match at least this share of the frame's pixels (the gallery's revisit shows 5 % of old surface 6 frames
    // before tracking has snapped back onto it), and the "share fell" check is off.
    double olderMapMinInlierFraction = 0.05;
    // How a lost camera is found again from the loop closer's keyframes (docs/LOOP_CLOSURE.md, "Relocalisation"):
    // a real camera in a place never mapped finds look-alikes that track well enough to pass tracking's loss checks
    // (ICL-NUIM office 0 without frames 59-98: 108 cm off at 65 % inliers), so a relocalisation is a hypothesis
    // until it is shown right.
    struct Relocalisation {
        // Frames after the relocalised one that must track from it and agree with the map before any is fused
        // (those frames and the relocalised one are tentative: not fused); the one after them is fused. 0: the
        // relocalised frame is fused at once.
        int confirmFrames = 2;
        // The relocalised frame and the confirming ones match the map at most this many times worse (inlier RMSE)
        // than the frames tracked before the loss did.
        double maxErrorRatio = 1.5;
        // A candidate the frame's features placed (RelocalisationCandidate::placed) that tracking confirms, landing
        // within placedAgree* of it, is held to tracking's own bound instead (TrackerOptions::maxErrorRise, 3):
        // appearance and geometry agree on the place. A view of an old part of a drifted map matches it worse than
        // the frames before the loss matched theirs: TUM fr1/rpy's 119-degree landing at 1.5-2.8 times, right within
        // its drift. The look-alike of ICL-NUIM office 0 that tracking settled on (not placed) matched 3.6 times worse.
        double placedMaxErrorRatio = 3.0;
        double placedAgreeMetres = 0.05, placedAgreeDegrees = 5.0;
        // Two candidates that track to places further apart than this: ambiguous, refused.
        double ambiguousMetres = 0.10;
        double ambiguousDegrees = 10.0;
    } relocalisation;
};

// One frame handed to the Mapper. The images must outlive the call only.
struct MapperFrame {
    uint32_t index = 0;          // the frame's number in the sequence (the frame store and the loop closer key on it)
    double timestamp = 0;        // kept with the frame and written in the trajectory
    const DepthImage* depth = nullptr;   // metres, 0 = no measurement
    const ColorImage* color = nullptr;   // registered to the depth (or empty): fused when the volume fuses colour,
                                         // and tracking's photometric term
    Intrinsics intrinsics;
    // Given: the frame is fused at this pose, and tracking (if any) restarts from it. None: the frame is tracked.
    std::optional<Pose> pose;
    // A tracked run's first frame (the tracker not started): fused at this pose without tracking. Without it the
    // first frame of an empty map is fused where the camera last was (identity at the start), and the first of a
    // map that holds frames is tracked from there.
    std::optional<Pose> startPose;
    // The frame's true pose where the input has one (a dataset's poses): tracking's position error is measured
    // against it.
    std::optional<Pose> reference;
    std::string source;          // where the depth came from, for messages ("frame 12 skipped: no valid depth in ...")
    vk::SubmitSync sync;
};

enum class FrameStatus {
    Fused,     // fused at `cameraToWorld`
    Lost,      // tracking lost it (and relocalisation did not find it): not fused, `cameraToWorld` is the prediction
    Tentative, // tracked from a relocalisation not yet confirmed (MapperOptions::relocalisation): not fused,
               // `cameraToWorld` is where it was tracked to
    Skipped,   // unreadable or without valid depth: not fused
};

// What the Mapper did with a frame.
struct MapperResult {
    uint32_t index = 0;
    FrameStatus status = FrameStatus::Skipped;
    Pose cameraToWorld = Pose::Identity();
    bool posed = false;                             // the frame has a pose (a skipped first frame of a tracked run has none)
    std::optional<gpu::TrackingReport> tracking;    // a tracked frame
    std::optional<gpu::FrameReport> fused;          // status Fused
    double fuseWallMs = 0;                          // wall time of the fusion (one submission: the whole frame's)
    bool oneSubmission = false;                     // a tracked frame tracked and fused in one submission
                                                    // (TrackerOptions::solveOnGpu; TrackedFusion::oneSubmission)
    bool relocalised = false;                       // lost from the prediction, found again from a keyframe's pose, and
                                                    // confirmed at this frame (the first fused since the loss)
    int relocalisationCandidatesTried = 0;
    uint32_t loopCorrections = 0;                   // fused frames a loop closing at this frame queued for re-fusion
    gpu::CorrectionReport corrections;              // what was re-fused before this frame
    std::vector<std::string> warnings;              // this frame's, as RunStats records them
    bool isFused() const { return status == FrameStatus::Fused; }
};

// A frame's outputs go to sinks (trajectory files, delta streams, the viewer, pictures, progress lines).
class FrameSink {
public:
    virtual ~FrameSink() = default;
    virtual void frameDone(const MapperResult& result, const MapperFrame& frame, gpu::GpuVolume& volume) = 0;
};

// One entry of the trajectory: every frame the Mapper saw, in order.
struct TrajectoryEntry {
    uint32_t index = 0;
    double timestamp = 0;
    bool posed = false;   // false: skipped before tracking had a pose for it
    std::optional<Pose> reference;
};

class Mapper {
public:
    Mapper(const vk::Context& context, MapperOptions options);
    ~Mapper();
    Mapper(const Mapper&) = delete;
    Mapper& operator=(const Mapper&) = delete;

    // The volume, at `width` x `height` (a no-op once there is one; process() creates it at the first frame's size).
    void createVolume(int width, int height);
    // Continues a saved map: its volume (with `config`'s capacities where larger, GpuVolume::load), and the loop
    // closer's state saved beside it when there is one.
    void loadMap(const map::MapData& map, const gpu::GpuVolumeConfig& config, const std::filesystem::path& path);
    // Keeps every fused frame in `store` so that fused frames can be corrected (correct()); needed by loop closure.
    void keepFrames(FrameStore store);

    MapperResult process(const MapperFrame& frame);
    // A frame the front end could not read: counted as skipped, with its warning.
    void skip(uint32_t index, const std::string& reason);
    // A warning of the front end's (counted in RunStats, as the Mapper's own).
    void warn(const std::string& warning) { stats_.addWarning(warning); }
    void addSink(FrameSink* sink) { sinks_.push_back(sink); }

    // New poses for fused frames, re-fused correctionsPerFrame before each later frame (MapCorrector::correct).
    void correct(const std::vector<uint32_t>& frames, const std::vector<Pose>& poses);
    size_t pendingCorrections() const { return corrector_ ? corrector_->pending() : 0; }
    // Re-fuses every queued correction now and publishes the mesh (its report: the delta); nothing queued, or not
    // `publish`: nullopt. `applied` (optional) receives what was re-fused.
    std::optional<gpu::FrameReport> finishCorrections(gpu::CorrectionReport* applied = nullptr, bool publish = true);
    // The end of a run: every queued correction re-fused, and with a loop closer every posed frame's trajectory
    // entry takes its latest pose (every loop's correction applied).
    void finish();
    // Writes the volume, the kept frames (beside it, frameStorePathOf) and the loop closer's state (loopClosurePathOf);
    // returns the save id that ties them together.
    uint64_t save(const std::filesystem::path& path);

    // A frame the caller fused itself at its given pose (Reconstructor's asynchronous and GPU-image frames): the
    // trajectory records it, tracking restarts from it, and with kept frames its host images (frame.depth) are kept.
    void recordGiven(const MapperFrame& frame);

    bool hasVolume() const { return volume_ != nullptr; }
    gpu::GpuVolume& volume() { return *volume_; }
    const gpu::GpuVolume& volume() const { return *volume_; }
    gpu::GpuVolume* volumePtr() { return volume_.get(); }
    const gpu::GpuVolume* volumePtr() const { return volume_.get(); }
    const gpu::PoseTracker* tracker() const { return tracker_.get(); }
    const gpu::MapCorrector* corrector() const { return corrector_ ? &*corrector_ : nullptr; }
    const FrameStore* frameStore() const { return corrector_ ? &corrector_->store() : nullptr; }
    const MapperOptions& options() const { return options_; }
    const vk::Context& context() const { return context_; }

    // Every frame the Mapper saw (process, recordGiven), in order, and the pose of each (given, tracked, predicted
    // for a lost frame; a corrected frame's once re-fused).
    const std::vector<TrajectoryEntry>& trajectory() const { return trajectory_; }
    const std::vector<Pose>& poses() const { return poses_; }
    // The counts so far (loop closure's taken from the loop closer now).
    RunStats stats() const;

private:
    const ColorImage* fusedColor(const MapperFrame& frame) const;
    void applyCorrections(size_t budget, gpu::CorrectionReport& report);
    void record(const MapperFrame& frame, const Pose& pose, bool posed);
    MapperResult tracked(const MapperFrame& frame, size_t validPixels);
    // Whether the loop closer wants this frame against the older map (MapperOptions::olderMapRecentFrames), and the
    // registration of a frame tracked to `tracking` there (kept in olderMap_ for its frameFused).
    bool wantsOlderMap(const MapperFrame& frame) const;
    void registerAgainstOlderMap(const MapperFrame& frame, const gpu::TrackingReport& tracking);
    // Relocalisation: a lost frame tracked from the loop closer's candidates; accepted, it is the hypothesis that
    // tracking goes on from (hypothesis_), tentative until confirmed.
    struct RelocalisationOutcome {
        bool accepted = false;
        gpu::TrackingReport tracking;   // accepted: the relocalised frame's; else the numbers of a refused candidate and why
        int candidate = 0;              // accepted: which of the loop closer's candidates (1-based)
        double maxErrorRatio = 0;       // accepted: the error ratio it was held to (placed candidates: a looser one)
        size_t statsEntry = 0;          // in stats_.relocalisations
    };
    // `baseline`: the inlier RMSE of the frames tracked before the loss. Records the attempt in the stats; tells
    // the loop closer when nothing was accepted.
    RelocalisationOutcome relocalise(const MapperFrame& frame, const Pose& predicted, const std::string& lostReason, double baseline,
                                     MapperResult& result);
    // Tracking goes on from an accepted relocalisation, tentatively; `atLoss` is put back if it is refused.
    void startHypothesis(const MapperFrame& frame, const RelocalisationOutcome& found, const gpu::PoseTracker::State& atLoss, double baseline);
    // Empty when `rmse` is at most `ratio` times `baseline` (Relocalisation::maxErrorRatio, or placedMaxErrorRatio for
    // a placed candidate tracking agreed with; always without a baseline), else why not.
    std::string errorAgainstBaseline(double rmse, double baseline, double ratio) const;
    // A frame after an unconfirmed relocalisation: tracked, not fused; confirms or refuses the hypothesis.
    MapperResult tentative(const MapperFrame& frame, size_t validPixels, MapperResult result);
    // A hypothesis's frame tracked to `tracked`, against where its own ORB features place it (`placed`, the loop
    // closer's placements): "" when one agrees (within placedAgree*), when there is none, or when every one is further
    // than tracking's jump bounds (a look-alike's, not this place's); else why the frame does not confirm the hypothesis.
    std::string placedElsewhere(const std::vector<RelocalisationCandidate>& placed, const Pose& tracked) const;
    MapperResult tentativeVerdict(const MapperFrame& frame, gpu::TrackingReport tracking, MapperResult result);
    MapperResult confirmRelocalisation(const MapperFrame& frame, gpu::TrackingReport tracking, MapperResult result);
    // A tracked frame's verdict recorded, and the frame fused (f.fused) or reported lost.
    MapperResult concludeTracked(const MapperFrame& frame, gpu::TrackedFusion f, MapperResult result);
    MapperResult fuseAt(const MapperFrame& frame, const Pose& pose, MapperResult result);
    void finishFrame(const MapperFrame& frame, MapperResult& result);
    void skipped(const MapperFrame& frame, MapperResult& result, const std::string& reason);

    const vk::Context& context_;
    MapperOptions options_;
    std::unique_ptr<gpu::GpuVolume> volume_;
    std::unique_ptr<gpu::PoseTracker> tracker_;
    std::optional<gpu::MapCorrector> corrector_;
    std::vector<FrameSink*> sinks_;
    std::vector<TrajectoryEntry> trajectory_;
    std::vector<Pose> poses_;
    RunStats stats_;
    struct Hypothesis {
        uint32_t frame = 0;                // the relocalised frame
        int candidate = 0;                 // which of the loop closer's candidates (1-based; 0: picked up from the last pose)
        Pose pose;                         // of the last frame tracked from it
        gpu::PoseTracker::State before;    // the tracker's state at the loss, put back if it is refused
        double baselineRmse = 0;           // of the frames tracked before the loss
        double maxErrorRatio = 0;          // how much worse than baselineRmse its frames may match (placed or not)
        int confirmed = 0;                 // frames that agreed since
        size_t statsEntry = SIZE_MAX;      // in stats_.relocalisations
    };
    std::optional<Hypothesis> hypothesis_;
    std::optional<std::pair<uint32_t, OlderMapRegistration>> olderMap_;   // of this frame (its index), for frameFused
    size_t correctionBurst_ = 0;   // the next frame's correction budget when a loop just closed (correctionsAfterLoop)
    bool lost_ = false;                    // a frame with depth was lost since the last fused one
    bool started_ = false;   // the run's clock (RunStats::fusionSeconds) runs from the first frame
    std::chrono::steady_clock::time_point start_;
};

}  // namespace vkmesh
