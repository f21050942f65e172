// Component: loop closure and relocalisation (docs/LOOP_CLOSURE.md) over a tracked sequence.
//   keyframes  a fused frame becomes a keyframe once the camera moved keyframeMetres or turned keyframeDegrees
//              from the last one: its pose (a node of the pose graph), its random-fern code (slam/random_ferns.h)
//              and its depth at registration size (slam/frame_registration.h). Every fused frame moves with the
//              keyframe it follows (its pose relative to that keyframe is kept).
//   loops      a new keyframe's code is compared with the older keyframes' (at least minKeyframeGap keyframes and
//              minFrameGap frames back); the most alike are verified by the tracker's ICP against their depth,
//              from the current pose and, failing that, from theirs; a verified registration that moves the
//              camera no further than the drift the path since then allows becomes a loop edge; the graph is
//              optimised (Ceres) and every frame's new pose handed back for the map's correction.
//   relocalise a lost frame's code ranks the keyframes; the caller tracks the frame from the most alike ones'
//              poses with the tracker's own checks (PoseTracker::relocalise).
// Everything is deterministic: the same frames give the same keyframes, loops and poses (fixed fern seed, ties
// broken by keyframe order, Ceres on one thread).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "api/loop_closure.h"
#include "gpu/tracking/camera_tracker.h"
#include "slam/frame_registration.h"
#include "slam/pose_graph.h"
#include "slam/random_ferns.h"

namespace vkmesh::slam {

struct LoopClosureOptions {
    FernOptions ferns;
    gpu::TrackerOptions tracker;        // the registration's pyramid, gates and stopping rule (the tracker's own)
    int registrationWidth = 160;        // frames halved until at most this wide for verification
    double keyframeMetres = 0.10;       // a new keyframe once the camera moved this far from the last one,
    double keyframeDegrees = 10.0;      // or turned this far
    // Loop candidates: keyframes at least this many keyframes and frames older than the new one, whose codes
    // differ from its code in at most this share of the ferns; the most alike `candidates` are verified.
    int minKeyframeGap = 10;
    uint32_t minFrameGap = 30;
    double loopDissimilarity = 0.30;
    int candidates = 3;
    // Verification (on top of the tracker's own loss checks): the registration's inliers cover at least this
    // share of the frame's valid pixels, and their RMSE is below maxRmse metres.
    double minInlierShare = 0.30;
    double maxRmse = 0.015;
    // Plausibility: a loop may move the camera by at most driftBaseMetres + driftPerMetre x the path travelled
    // since the old keyframe (and driftBaseDegrees + driftDegreesPerMetre x that path): tracking does not drift
    // further, and two look-alike places further apart are a false loop.
    double driftBaseMetres = 0.10, driftPerMetre = 0.05;
    double driftBaseDegrees = 5.0, driftDegreesPerMetre = 2.0;
    // A verified loop that moves the camera less than this and turns it less than this agrees with the trajectory
    // (counted as consistent): no edge, no solve. Below it a registration at registration size is not more precise
    // than tracking, and re-solving for its noise made TUM fr1/rpy's ATE worse (docs/RESULTS.md, "Loop closure").
    double minLoopCorrectionMetres = 0.03, minLoopCorrectionDegrees = 2.0;
    // odometryCheck: an odometry edge takes the keyframes' registered motion instead of the tracked one where the
    // two differ by more than this (tracking snapped onto a surface mapped long before; loop_closer.cpp says why).
    // Off by default: on the gallery sequence it made the final trajectory worse (the corrected poses and the
    // tracker, which follows the old map, pulled against each other; docs/LOOP_CLOSURE.md).
    bool odometryCheck = false;
    double odometryCheckMetres = 0.01, odometryCheckDegrees = 0.5;
    // The pose graph: odometry edges' standard deviation grows with the motion between the keyframes (a
    // tracker's drift), loop edges are as precise as a registration; loops take a Huber loss at this many
    // standard deviations. After the solve, a loop still off by more than maxLoopError deviations is rejected.
    double odometrySigmaMetres = 0.005, odometrySigmaPerMetre = 0.02;
    double odometrySigmaDegrees = 0.3, odometrySigmaPerDegree = 0.02;
    double loopSigmaMetres = 0.01, loopSigmaDegrees = 0.5;
    double huber = 3.0;
    double maxLoopError = 5.0;
    // A frame the graph moved less than this (and turned less) is not handed back for re-fusion: re-fusing costs
    // two frames' fusion, and a move well below a voxel does not change the map.
    double minCorrectionMetres = 0.002, minCorrectionDegrees = 0.1;
    // Relocalisation: at most this many keyframes tried, each differing in at most this share of the ferns.
    double relocaliseDissimilarity = 0.40;
    int relocaliseCandidates = 3;
};

// What the loop closer did (--stats "loop_closure", Python's stats()).
struct LoopClosureStats {
    uint32_t keyframes = 0;
    uint32_t loopsDetected = 0;        // candidates the ferns found (verified or not)
    uint32_t loopsAccepted = 0;
    uint32_t loopsRejected = 0;
    uint32_t loopsConsistent = 0;      // verified, but the trajectory already agrees: nothing to correct
    uint32_t odometryRegistered = 0;   // odometry edges that took the registered motion (tracking snapped)
    std::map<std::string, uint32_t> rejectedBy;   // "registration", "implausible", "graph"
    uint32_t lostFrames = 0, relocalisations = 0, relocalisationCandidatesTried = 0;
    uint32_t framesCorrected = 0;      // poses handed back (a frame counts once per loop that moved it)
    uint32_t graphSolves = 0;
    // Milliseconds per stage (sum and count): encode (shrink + code), keyframe (registration image), search,
    // verify (registration), solve (the graph), per frameFused call in all ("frame").
    std::map<std::string, std::pair<double, uint32_t>> milliseconds;
    struct Loop {
        uint32_t frame = 0, keyframeFrame = 0;   // the new keyframe's frame and the old one's
        double dissimilarity = 0;
        bool accepted = false;                   // verified (and plausible)
        std::string reason;                      // why rejected; "consistent" when verified but nothing to correct
        double correctionMetres = 0, correctionDegrees = 0;   // how far the loop moved the camera
    };
    std::vector<Loop> loops;
};

class LoopCloser final : public LoopClosure {
public:
    explicit LoopCloser(const LoopClosureOptions& options = {});
    PoseCorrections frameFused(const LoopClosureFrame& frame) override;
    std::vector<Pose> relocalisationCandidates(const LoopClosureFrame& frame) override;
    void relocalisationResult(uint32_t frame, bool relocalised, int candidatesTried) override;
    bool latestPose(uint32_t frame, Pose& pose) const override;
    const LoopClosureStats& stats() const { return stats_; }
    const LoopClosureOptions& options() const { return options_; }
    const PoseGraph& graph() const { return graph_; }

private:
    struct Keyframe {
        uint32_t frame = 0;
        int node = 0;
        FernCode code;
        DepthImage depth;          // at registration size
        Intrinsics intrinsics;     // of that depth
        double pathMetres = 0;     // path length travelled when it was made
    };
    struct FusedFrame {
        int keyframe = -1;                     // the keyframe it follows
        Pose relative = Pose::Identity();      // inverse(keyframe pose) * its pose, when fused
        Pose handed = Pose::Identity();        // the pose it was fused at or last handed out with for correction
    };
    // Verifies and, if accepted, closes a loop from the newest keyframe to `candidate`.
    enum class LoopOutcome { Rejected, Consistent, Closed };
    LoopOutcome tryLoop(const Keyframe& current, const RegistrationFrame& currentFrame, int candidate, double dissimilarity);
    void time(const std::string& stage, double ms);
    // Why registration `r` (from `initial`) does not verify: the tracker's loss checks, the inlier share, the RMSE; "" when it does.
    std::string verified(const Registration& r, const Pose& initial) const;
    // Every fused frame the graph moved by minCorrection* or more from the pose it was fused at or last handed
    // out with; they are handed out with their new poses now.
    PoseCorrections corrections();

    LoopClosureOptions options_;
    RandomFerns ferns_;
    PoseGraph graph_;
    std::vector<Keyframe> keyframes_;
    std::map<uint32_t, FusedFrame> frames_;
    double pathMetres_ = 0;
    std::optional<Pose> lastPose_;
    // A relocalisation succeeded: the next fused frame becomes a keyframe tied to this keyframe.
    std::optional<int> relocalisedFrom_;
    std::vector<int> lastCandidates_;
    // The newest keyframe's registration pyramid (its odometry check, its loops) and the one before (the check).
    RegistrationFrame currentRegistration_, previousRegistration_;   // relocalisationCandidates' keyframes, in the order returned
    LoopClosureStats stats_;
};

}  // namespace vkmesh::slam
