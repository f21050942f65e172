// Camera tracking over a sequence (docs/TRACKING.md): the prediction, the ICP against the mesh (CameraTracker)
// and the decision whether a frame is tracked or lost. Used the same way by the CLI (`vkmesh fuse --track`),
// Reconstructor::integrate without a pose, gpubench and the Python module:
//   PoseTracker tracker(context, options);
//   tracker.start(firstPose);                            // the first frame is fused at this pose
//   for every later frame:
//       TrackedFusion f = tracker.trackAndFuse(volume, depth, intrinsics, color, color);
//       // f.tracking.tracked: fused at f.tracking.cameraToWorld (f.fused is its FrameReport); else not fused
// trackAndFuse is track() followed by volume.integrate() at the tracked pose, or with options.solveOnGpu all of
// it in one submission: the loss policy decided on the GPU, which fuses the frame only when it is tracked.
// A lost frame (too few inliers, an ill-conditioned system, a jump past a bound, an error that rises, or no
// valid depth) gets the predicted pose and is not fused: the map stays bit-identical. The next frame is
// predicted from the last tracked pose and tracks again as soon as it matches.
#pragma once

#include <deque>
#include <memory>
#include <optional>
#include <string>

#include "gpu/tracking/camera_tracker.h"

namespace vkmesh::gpu {

struct TrackingReport {
    Pose cameraToWorld = Pose::Identity();  // tracked: the estimate; lost: the prediction
    bool tracked = false;
    bool first = false;                     // the first frame: its pose was given, nothing was tracked
    std::string lostReason;                 // why the frame was lost (empty when tracked)
    int iterations = 0;
    uint32_t submissions = 0;               // GPU submissions waited for (host round trips)
    double inliers = 0;                     // level 0, last iteration
    double validPixels = 0;
    double inlierShare() const { return validPixels > 0 ? inliers / validPixels : 0.0; }
    double rmse = 0;                        // inliers' point-to-plane RMSE (metres)
    double conditioning = 0;
    double milliseconds = 0;                // wall time of track()
    double gpuMilliseconds = 0;             // GPU time of the tracking passes (timestamps)
    bool modelDrawn = false;                // the mesh was drawn for this frame (not the last maps reused)
    std::vector<std::pair<std::string, double>> gpuStageMilliseconds;   // ... per stage (CameraTracker)
};

// A tracked frame and, when it was fused, what fusing it did.
struct TrackedFusion {
    TrackingReport tracking;
    std::optional<FrameReport> fused;   // empty: the frame was lost (not fused)
    bool oneSubmission = false;         // tracked and fused in one submission (options.solveOnGpu): then
                                        // tracking.milliseconds is the whole frame's wall time, fusion included
    double fuseMilliseconds = 0;        // wall time of the fusion (one submission: the same as tracking's)
};

// The loss policy (TrackerOptions' bounds), and the CPU reference of the GPU's (track_decide.comp): why a frame
// whose ICP ended with `system` (level 0's last, before its step) at `motion` from the last tracked pose is lost,
// TRACK_TRACKED if it is not. `solved`: that system could be solved; `conditioning`: its smallest over largest
// eigenvalue; `recent`: the recent tracked frames' means (RecentFrames, camera_tracker.h; 0: none yet).
uint32_t trackingLoss(const IcpSystem& system, bool solved, double conditioning, const Pose& motion, const RecentFrames& recent,
                      const TrackerOptions& options);
// The reason in words, with the numbers behind it.
std::string lossText(uint32_t reason, const IcpSystem& system, double conditioning, const Pose& motion, const RecentFrames& recent,
                     const TrackerOptions& options);

// Halves a depth image: each pixel averages the 2 x 2 measured samples within `band` metres of the first
// (track_downsample_depth's rule: no averaging across a depth edge); 0 where none is measured. How downsampled
// tracking (TrackerOptions::downsample) and the loop closer's registration shrink a frame.
DepthImage halveTrackingDepth(const DepthImage& in, float band);

class PoseTracker {
public:
    PoseTracker(const vk::Context& context, const TrackerOptions& options = {});
    ~PoseTracker();

    // The first frame's pose (the dataset's, or identity): the frame is not tracked, the caller fuses it.
    TrackingReport start(const Pose& cameraToWorld);
    bool started() const { return started_; }
    // Tracks a frame against `model` (the mesh fused so far: a volume, or MeshBuffers). The
    // colour image (registered to the depth, or null) feeds the photometric term when options.colorWeight > 0.
    TrackingReport track(const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model,
                         const ColorImage* color = nullptr);
    // Tracks a frame against `volume`'s mesh (the triangles in view) and fuses it there when it is tracked.
    // `trackingColor` feeds the photometric term, `fusedColor` is fused (either may be null). With
    // options.solveOnGpu one submission does both (one host wait per frame; docs/TRACKING.md, "One submission"),
    // else track() and then volume.integrate().
    TrackedFusion trackAndFuse(GpuVolume& volume, const DepthImage& depth, const Intrinsics& intrinsics, const ColorImage* trackingColor,
                               const ColorImage* fusedColor, const vk::SubmitSync& sync = {});
    // Relocalisation (docs/LOOP_CLOSURE.md): track() of a frame from `start` (a keyframe's pose) instead of the
    // prediction, with every loss check measured from there (the jump bound from `start`, not from the last tracked
    // pose). Nothing is fused and the tracker's state stays as it was: the result is a hypothesis for the caller to
    // verify, and to go on from with resumeAt(). `bounds` (optional): the loss checks' bounds instead of the options'
    // (a registration against part of the map: the Mapper's older map).
    TrackingReport trackFrom(const Pose& start, const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model,
                             const ColorImage* color = nullptr, const TrackerOptions* bounds = nullptr);
    // The frame of the last track()/trackFrom() against that call's model maps at `cameraToWorld` instead (one ICP
    // iteration's system at the finest level, nothing solved): how well that model fits the frame there.
    IcpSystem fitAt(const Pose& cameraToWorld);
    // Tracking goes on from `pose` (an accepted relocalisation) with `motion` (none: the next frame is predicted
    // at `pose`).
    void resumeAt(const Pose& pose, const Pose& motion = Pose::Identity());
    // What the prediction and the loss checks are made of: kept before frames that may turn out wrong (tracked
    // from a tentative relocalisation) and put back if they do.
    struct State {
        Pose lastTracked, velocity;
        std::deque<double> recentRmse, recentShare;
    };
    State state() const { return {lastTracked_, velocity_, recentRmse_, recentShare_}; }
    void restore(const State& state);
    // The mean inlier RMSE (metres) and inlier share of the last tracked frames (0 before any): what "the error
    // rose" and "the share fell" are measured against.
    double recentRmse() const { return recent().rmse; }
    RecentFrames recent() const;
    // The last tracked frame's pose was corrected (a loop closed): the next frame is predicted from `corrected`
    // with the same motion, and the mesh is drawn anew (maps drawn at the old pose are stale).
    void correctLastPose(const Pose& corrected);
    // The pose the next frame will be predicted at (constant velocity from the last two tracked frames).
    Pose prediction() const { return lastTracked_ * velocity_; }
    const TrackerOptions& options() const { return options_; }

private:
    // The frame as the tracker sees it: downsampled by options.downsample (as given when 1).
    struct TrackingInput {
        const DepthImage* depth;
        const ColorImage* color;
        Intrinsics intrinsics;
    };
    TrackingInput trackingInput(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics);
    CameraTracker& trackerFor(const DepthImage& depth);
    // Whether the frame predicted at `predicted` reuses the last model maps (TrackerOptions::modelReuse*); tells
    // the tracker so.
    bool reuseModelMaps(CameraTracker& tracker, const Pose& predicted);
    // track() with the loss checks' `bounds` (the options', or trackFrom's).
    TrackingReport track(const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model, const ColorImage* color,
                         const TrackerOptions& bounds);
    // The report of a frame whose ICP found `icp` (its verdict `reason` under `bounds`), and the prediction state moved on.
    TrackingReport conclude(const IcpResult& icp, uint32_t reason, double conditioning, const Pose& estimate, const Pose& predicted,
                            const TrackerOptions& bounds);
    const vk::Context& context_;
    TrackerOptions options_;
    std::unique_ptr<CameraTracker> tracker_;   // created at the first tracked frame's image size
    bool started_ = false;
    Pose lastTracked_ = Pose::Identity();
    Pose velocity_ = Pose::Identity();         // last tracked motion, in the camera's frame
    std::deque<double> recentRmse_;            // of the last tracked frames (the "error rose" check)
    std::deque<double> recentShare_;           //  and their inlier shares (the "share fell" check)
    int modelReuses_ = 0;                      // frames in a row that reused the model maps
    bool modelFresh_ = false;                  // the maps were drawn since start() and no frame was lost since
    DepthImage smallDepth_;                    // the frame downsampled (options.downsample > 1)
    ColorImage smallColor_;
};

}  // namespace vkmesh::gpu
