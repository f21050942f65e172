// Camera tracking over a sequence (docs/TRACKING.md): the prediction, the ICP against the mesh (CameraTracker)
// and the decision whether a frame is tracked or lost. Used the same way by the CLI (`vkmesh fuse --track`),
// Reconstructor::integrate without a pose and the Python module:
//   PoseTracker tracker(context, options);
//   tracker.start(firstPose);                            // the first frame is fused at this pose
//   for every later frame:
//       TrackingReport r = tracker.track(depth, intrinsics, volume.meshBuffers());
//       if (r.tracked) volume.integrate(depth, intrinsics, r.cameraToWorld);   // else: not fused
// A lost frame (too few inliers, an ill-conditioned system, a jump past a bound, an error that rises, or no
// valid depth) gets the predicted pose and is not fused: the map stays bit-identical. The next frame is
// predicted from the last tracked pose and tracks again as soon as it matches.
#pragma once

#include <deque>
#include <memory>
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
    double rmse = 0;                        // inliers' point-to-plane RMSE (metres)
    double conditioning = 0;
    double milliseconds = 0;                // wall time of track()
    double gpuMilliseconds = 0;             // GPU time of the tracking passes (timestamps)
    std::vector<std::pair<std::string, double>> gpuStageMilliseconds;   // ... per stage (CameraTracker)
};

class PoseTracker {
public:
    PoseTracker(const vk::Context& context, const TrackerOptions& options = {});
    ~PoseTracker();

    // The first frame's pose (the dataset's, or identity): the frame is not tracked, the caller fuses it.
    TrackingReport start(const Pose& cameraToWorld);
    bool started() const { return started_; }
    // Tracks a frame against `mesh` (the mesh fused so far: MeshBuffers of a volume with publishMesh). The
    // colour image (registered to the depth, or null) feeds the photometric term when options.colorWeight > 0.
    TrackingReport track(const DepthImage& depth, const Intrinsics& intrinsics, const MeshBuffers& mesh,
                         const ColorImage* color = nullptr);
    // The pose the next frame will be predicted at (constant velocity from the last two tracked frames).
    Pose prediction() const { return lastTracked_ * velocity_; }
    const TrackerOptions& options() const { return options_; }

private:
    const vk::Context& context_;
    TrackerOptions options_;
    std::unique_ptr<CameraTracker> tracker_;   // created at the first tracked frame's image size
    bool started_ = false;
    Pose lastTracked_ = Pose::Identity();
    Pose velocity_ = Pose::Identity();         // last tracked motion, in the camera's frame
    std::deque<double> recentRmse_;            // of the last tracked frames (the "error rises" check)
};

}  // namespace vkmesh::gpu
