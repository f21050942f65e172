// Component: loop closure and relocalisation (docs/LOOP_CLOSURE.md) over a tracked sequence.
//   keyframes  a fused frame becomes a keyframe once the camera moved keyframeMetres or turned keyframeDegrees
//              from the last one: its pose (a node of the pose graph), its random-fern code (slam/random_ferns.h)
//              and its depth at registration size (slam/frame_registration.h). Every fused frame moves with the
//              keyframe it follows (its pose relative to that keyframe is kept).
//   loops      a new keyframe's code is compared with the older keyframes' (at least minKeyframeGap keyframes and
//              minFrameGap frames back), and the older keyframes the graph puts near it are found (the ferns miss
//              real views turned 10-20 degrees); the most alike and the nearest are verified by the tracker's ICP
//              against their depth, from the current pose and, failing that, from theirs; a verified registration
//              that moves the camera no further than the drift the path since then allows becomes a loop edge; the
//              graph is optimised (Ceres) and every frame's new pose handed back for the map's correction.
//   relocalise a lost frame's ORB features are matched against every keyframe's and solved by PnP
//              (slam/feature_relocaliser.h: views turned too far for the ferns), and its code ranks the keyframes;
//              the caller tracks the frame from those poses and the most alike keyframes' poses with the
//              tracker's own checks and confirms the result over the next frames (Mapper::relocalise,
//              PoseTracker::trackFrom).
// Everything is deterministic: the same frames give the same keyframes, loops and poses (fixed fern seed, ties
// broken by keyframe order, Ceres on one thread).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "api/loop_closure.h"
#include "gpu/tracking/camera_tracker.h"
#include "slam/feature_relocaliser.h"
#include "slam/frame_registration.h"
#include "slam/pose_graph.h"
#include "slam/random_ferns.h"

namespace vkmesh::slam {

struct LoopClosureOptions {
    FernOptions ferns;
    FeatureOptions features;            // relocalisation by ORB features and PnP (features.enabled: on)
    gpu::TrackerOptions tracker;        // the registration's pyramid, gates and stopping rule (the tracker's own)
    int registrationWidth = 320;        // frames halved until at most this wide for verification (VGA: 320 x 240,
                                        // as tracking; at 160 the loops' errors made TUM fr1/rpy's ATE worse)
    double keyframeMetres = 0.10;       // a new keyframe once the camera moved this far from the last one,
    double keyframeDegrees = 10.0;      // or turned this far
    // Loop candidates: keyframes at least this many keyframes and frames older than the new one, whose codes
    // differ from its code in at most this share of the ferns; the most alike `candidates` are verified.
    int minKeyframeGap = 10;
    uint32_t minFrameGap = 30;
    double loopDissimilarity = 0.30;
    int candidates = 3;
    // Loop candidates by place, besides the ferns (which miss real views 10-20 degrees apart: docs/RESULTS.md,
    // "Place recognition"): old enough keyframes that the graph puts within the drift the path since them allows
    // (the plausibility bound below) and whose optical axis is within proximityDegrees of the camera's; the
    // nearest `proximityCandidates` are verified as the ferns' are, unless a loop was verified at one of the last
    // proximitySpacing keyframes (a place already tied to the map needs no second check).
    int proximityCandidates = kDefaultLoopPlaceCandidates;   // --loop-place-candidates
    double proximityDegrees = 20.0;
    int proximitySpacing = 3;
    // A loop proposed by place corrects the trajectory only when it moves the camera at least this far or turns
    // it this much (below, it counts as consistent): registrations of real views that far apart can be off by
    // 6 cm and 6 degrees and still verify (TUM fr1/rpy), and closing such loops made its ATE worse (docs/RESULTS.md).
    double proximityMinCorrectionMetres = 0.10, proximityMinCorrectionDegrees = 8.0;
    // Verification (on top of the tracker's own loss checks): the registration's inliers cover at least this
    // share of the frame's valid pixels, and their RMSE is below maxRmse metres.
    double minInlierShare = 0.50;
    double maxRmse = 0.015;
    // Plausibility: a loop may move the camera by at most driftBaseMetres + driftPerMetre x the path travelled
    // since the old keyframe (and driftBaseDegrees + driftDegreesPerMetre x that path): tracking does not drift
    // further, and two look-alike places further apart are a false loop.
    double driftBaseMetres = 0.10, driftPerMetre = 0.05;
    double driftBaseDegrees = 5.0, driftDegreesPerMetre = 2.0;
    // A verified loop that moves the camera less than this and turns it less than this agrees with the trajectory
    // (counted as consistent): no edge, no solve. Below it a single frame's registration is not more precise than
    // frame-to-model tracking: at 2 cm / 1 degree TUM fr1/rpy's ATE went 2.28 -> 2.57 cm, at 3 cm / 2 degrees to
    // 2.31 cm, at 5 cm / 3 degrees it stays 2.28 (docs/RESULTS.md, "Loop closure").
    double minLoopCorrectionMetres = 0.05, minLoopCorrectionDegrees = 3.0;
    // Verification both ways: the old keyframe registered back to the current frame (placed where the match says)
    // must land within this of where it is: a registration that slid along a weakly constrained direction does
    // not come back.
    double symmetricMetres = 0.01, symmetricDegrees = 0.5;
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
    // Loops against the older map (docs/LOOP_CLOSURE.md): at each would-be keyframe (with keyframes old enough for a
    // loop) that may see what an old enough keyframe saw (its view direction within olderMapDegrees, its position
    // within olderMapReachMetres and the drift the path since allows), the frame is registered against the map made
    // before the recent frames before it is fused (the Mapper does it: MapperOptions::olderMapRecentFrames), unless a
    // loop verified or the older map matched at one of the last proximitySpacing keyframes.
    // A match that shows drift is a loop to the old keyframe nearest its pose (within olderMapDegrees of its view
    // direction): the fused model is far less noisy than one keyframe's depth, so this loop measures drift before
    // frame-to-model tracking snaps back onto the old surface and hides it (the gallery: "Limits"). It shows drift
    // when it moves the camera at least olderMapMinCorrection* and the older map fits the frame there with at most
    // olderMapFitGain times the RMSE it has at the tracked pose (a registration that slid along a wall fits no better:
    // ICL-NUIM office 0, 1.2 mm at both poses 3.8 cm apart; the gallery's drift 22.1 -> 5.0 mm; TUM fr1/rpy's
    // matches 0.91-1.02 times); its edge is as precise as olderMapSigma*.
    bool olderMap = true;
    double olderMapDegrees = 45.0;
    double olderMapReachMetres = 1.5;   // cameras looking the same way this far apart see the same walls 2-4 m away
    double olderMapMinCorrectionMetres = 0.01, olderMapMinCorrectionDegrees = 0.5;
    double olderMapFitGain = 0.5;
    double olderMapSigmaMetres = 0.005, olderMapSigmaDegrees = 0.3;
    // Relocalisation: the features' poses (at most features.candidates), then at most relocaliseCandidates
    // keyframes, each differing in at most this share of the ferns (a keyframe the features already proposed is
    // not proposed again).
    double relocaliseDissimilarity = 0.40;
    int relocaliseCandidates = 3;
};

// What the loop closer did: LoopClosureStats (api/loop_closure.h).
using LoopClosureStats = vkmesh::LoopClosureStats;

class LoopCloser final : public LoopClosure {
public:
    explicit LoopCloser(const LoopClosureOptions& options = {});
    PoseCorrections frameFused(const LoopClosureFrame& frame) override;
    std::vector<RelocalisationCandidate> relocalisationCandidates(const LoopClosureFrame& frame) override;
    std::vector<RelocalisationCandidate> placements(const LoopClosureFrame& frame) override;
    bool wantsOlderMap(uint32_t frame, const Pose& cameraToWorld) const override;
    void relocalisationResult(uint32_t frame, bool relocalised, int candidatesTried) override;
    bool latestPose(uint32_t frame, Pose& pose) const override;
    // File layout (little-endian): "VKLOOPS" and a 0 byte, u32 version (2), u64 map id, u64 payload bytes, u32
    // CRC-32 (map::crc32) of the payload, then the payload: zstd of the state (the path length, the last pose,
    // every keyframe with its code, registration depth and (version 2) ORB features, the graph's nodes and edges,
    // every fused frame's keyframe and poses; f64 poses row-major). Version 1 files load, their keyframes without
    // features. Counters (stats()) start again at 0.
    void save(const std::filesystem::path& path, uint64_t mapId) const override;
    void load(const std::filesystem::path& path, uint64_t mapId) override;
    const LoopClosureStats& stats() const override { return stats_; }
    const LoopClosureOptions& options() const { return options_; }
    const PoseGraph& graph() const { return graph_; }

private:
    struct Keyframe {
        uint32_t frame = 0;
        int node = 0;
        FernCode code;
        KeyframeFeatures features; // ORB features with a depth (none without colour)
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
    LoopOutcome tryLoop(const Keyframe& current, const RegistrationFrame& currentFrame, int candidate, double dissimilarity, const char* proposedBy);
    // Counts a rejected loop and why (the reason's words before ':' are its kind in stats' rejectedBy).
    LoopOutcome rejectLoop(LoopClosureStats::Loop loop, const std::string& reason);
    // The same for the newest keyframe registered against the older map (LoopClosureFrame::olderMap, tracked).
    LoopOutcome tryOlderMapLoop(const Keyframe& current, const OlderMapRegistration& registration);
    // The plausibility bound, the correction's threshold and the solve of a verified loop from keyframe `old` to
    // `current` that puts the current camera at `matched` (tryLoop, tryOlderMapLoop); `loop` is recorded.
    LoopOutcome acceptLoop(const Keyframe& current, const Keyframe& old, const Pose& matched, double minMetres, double minDegrees,
                           double sigmaMetres, double sigmaDegrees, LoopClosureStats::Loop loop);
    // Whether a frame at `cameraToWorld` becomes a keyframe (moved or turned far enough from the last one).
    bool farFromLastKeyframe(const Pose& cameraToWorld) const;
    // Whether the keyframe made now (`id`) skips the loop checks by place: a loop verified at one of the last
    // proximitySpacing keyframes tied the place to the map.
    bool placeRecentlyVerified(int id) const { return lastVerifiedKeyframe_ >= 0 && id - lastVerifiedKeyframe_ <= options_.proximitySpacing; }
    // Whether keyframe k is old enough to close a loop with `current` (the newest keyframe): minKeyframeGap
    // keyframes and minFrameGap frames back.
    bool oldEnoughForLoop(int k, const Keyframe& current) const;
    // How far tracking can have drifted over `path` metres (the plausibility bound).
    double maxDriftMetres(double path) const;
    // Old enough keyframes that could be where the camera is now (proximity* options), nearest first, not in `skip`.
    std::vector<int> nearbyKeyframes(const Keyframe& current, const std::vector<int>& skip) const;
    void time(const std::string& stage, double ms);
    // The verification gates of the options (minInlierShare, maxRmse, symmetric*).
    VerificationGates gates() const;
    // Every fused frame the graph moved by minCorrection* or more from the pose it was fused at or last handed
    // out with; they are handed out with their new poses now.
    PoseCorrections corrections();

    LoopClosureOptions options_;
    RandomFerns ferns_;
    FeatureRelocaliser features_;
    PoseGraph graph_;
    std::vector<Keyframe> keyframes_;
    std::map<uint32_t, FusedFrame> frames_;
    double pathMetres_ = 0;
    std::optional<Pose> lastPose_;
    // A relocalisation succeeded: the next fused frame becomes a keyframe tied to this keyframe.
    std::optional<int> relocalisedFrom_;
    std::vector<int> lastCandidates_;   // relocalisationCandidates' keyframes, in the order returned
    std::vector<bool> lastByFeatures_;  // and whether the features proposed each
    // The poses the frame's features place it at, with the keyframe each was matched to (relocalisationCandidates,
    // placements); `stage`: the milliseconds' name.
    std::vector<std::pair<int, RelocalisationCandidate>> placeByFeatures(const LoopClosureFrame& frame, const char* stage);
    size_t featureWindow_ = 0;          // where the next lost frame's window of older keyframes starts (FeatureOptions::matchKeyframes)
    int lastVerifiedKeyframe_ = -1;     // the newest keyframe whose loop verified (closed or consistent)
    int lastOlderMapMatch_ = -1;        // the newest keyframe that matched the older map
    LoopClosureStats stats_;
};

}  // namespace vkmesh::slam
