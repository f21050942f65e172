// What a loop closer does for a tracked sequence (docs/LOOP_CLOSURE.md), as the Reconstructor and the CLI see it:
// after every fused frame it may find that the camera is back at a place it has seen, and answer with new poses
// for frames already fused (the map's correction re-fuses them); for a frame tracking lost it names poses to try.
// The implementation (keyframes, random ferns, geometric verification, a Ceres pose graph) is slam::LoopCloser in
// the vkmesh_slam library: the GPU core declares only this interface, so that an embedding application that does
// not close loops does not link Ceres.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/types.h"

namespace vkmesh {

// A tracked frame registered against the older map before it was fused (Mapper; docs/LOOP_CLOSURE.md, "Loops against
// the older map"): the tracker's ICP from the tracked pose against only the surface made before the recent frames,
// with tracking's own loss checks. Where the camera is in the map the recent frames' drift has not reached.
struct OlderMapRegistration {
    bool tracked = false;                    // the checks passed
    Pose cameraToWorld = Pose::Identity();   // tracked: the estimate
    // The older map's fit to the frame (inlier point-to-plane RMSE, metres) at cameraToWorld and at the tracked
    // pose: a drift the older map measures fits it better than the tracked pose does.
    double rmse = 0, rmseAtTracked = 0;
    double milliseconds = 0;                 // wall time of the registration
};

// One frame as the loop closer sees it: the images as fused (or as tracking lost them) and where it was.
struct LoopClosureFrame {
    uint32_t index = 0;                  // the frame's number in the sequence (as the map's correction numbers it)
    const DepthImage* depth = nullptr;   // metres, 0 = none
    const ColorImage* color = nullptr;   // registered to the depth, or null / empty
    Intrinsics intrinsics;
    Pose cameraToWorld = Pose::Identity();   // fused at (frameFused), or the tracker's prediction (lost frames)
    const OlderMapRegistration* olderMap = nullptr;   // frameFused: the frame against the older map, when wantsOlderMap asked for it
};

// A pose to track a lost frame from (LoopClosure::relocalisationCandidates).
struct RelocalisationCandidate {
    Pose cameraToWorld = Pose::Identity();
    // Where the frame's own features, matched to a keyframe's, put the camera (slam/feature_relocaliser.h), rather
    // than a look-alike keyframe's pose to start from: tracking that lands here has two independent cues agreeing
    // (MapperOptions::Relocalisation::placed*).
    bool placed = false;
};

// New camera-to-world poses for frames already fused (an accepted loop moved them), in ascending frame order.
struct PoseCorrections {
    std::vector<uint32_t> frames;
    std::vector<Pose> poses;
    bool empty() const { return frames.empty(); }
};

// The loop closer's (slam::LoopClosureOptions::proximityCandidates) default, here so that the settings
// (api/settings.cpp) state it without depending on the loop closer.
inline constexpr int kDefaultLoopPlaceCandidates = 2;

// What a loop closer did (--stats "loop_closure", Python's stats(): RunStats carries it).
struct LoopClosureStats {
    uint32_t keyframes = 0;
    uint32_t loopsDetected = 0;        // candidates the ferns found (verified or not)
    uint32_t loopsAccepted = 0;
    uint32_t loopsRejected = 0;
    uint32_t loopsConsistent = 0;      // verified, but the trajectory already agrees: nothing to correct
    std::map<std::string, uint32_t> rejectedBy;   // "registration", "implausible", "graph"
    uint32_t lostFrames = 0, relocalisations = 0, relocalisationCandidatesTried = 0;
    // Poses the keyframes' ORB features proposed for lost frames, and the confirmed relocalisations among them.
    uint32_t featureCandidates = 0, relocalisationsByFeatures = 0;
    uint32_t framesCorrected = 0;      // poses handed back (a frame counts once per loop that moved it)
    uint32_t olderMapChecks = 0;       // frames registered against the older map (wantsOlderMap), and those that matched it
    uint32_t olderMapMatches = 0;
    uint32_t graphSolves = 0;
    // Milliseconds per stage (sum and count): encode (shrink + code), features (a keyframe's ORB features), keyframe
    // (registration image), search, verify (registration), solve (the graph), per frameFused call in all ("frame");
    // for lost frames relocalise_features (ORB, matching, PnP) and relocalise_search (the ferns).
    std::map<std::string, std::pair<double, uint32_t>> milliseconds;
    struct Loop {
        uint32_t frame = 0, keyframeFrame = 0;   // the new keyframe's frame and the old one's
        double dissimilarity = 0;
        // "ferns" (the codes look alike), "proximity" (the graph puts them close) or "older map" (the frame matched
        // the surface made before the recent frames, and it showed drift)
        std::string proposedBy;
        bool accepted = false;                   // verified (and plausible)
        std::string reason;                      // why rejected; "consistent" when verified but nothing to correct
        double correctionMetres = 0, correctionDegrees = 0;   // how far the loop moved the camera
    };
    std::vector<Loop> loops;
};

class LoopClosure {
public:
    virtual ~LoopClosure() = default;
    // A frame was fused at frame.cameraToWorld (the first frame, a tracked or a relocalised one). Returns the poses
    // an accepted loop moved (this frame's among them), or nothing.
    virtual PoseCorrections frameFused(const LoopClosureFrame& frame) = 0;
    // Whether a tracked frame about to be fused at about `cameraToWorld` should first be registered against the older
    // map (handed to frameFused in LoopClosureFrame::olderMap). Never by default.
    virtual bool wantsOlderMap(uint32_t /*frame*/, const Pose& /*cameraToWorld*/) const { return false; }
    // A frame tracking lost: camera poses to track it from, most likely first (none: no keyframe looks alike).
    virtual std::vector<RelocalisationCandidate> relocalisationCandidates(const LoopClosureFrame& frame) = 0;
    // How trying them ended (counted; a success also restarts the pose graph's chain at that frame, whose
    // frameFused follows).
    virtual void relocalisationResult(uint32_t frame, bool relocalised, int candidatesTried) = 0;
    // Where the frame's own features place it against the keyframes (candidates with `placed` set), to check a pose
    // tracking found. Unlike relocalisationCandidates it starts no relocalisation: the candidates relocalisationResult
    // refers to stay those of the last relocalisationCandidates call, and no lost frame is counted. None by default.
    virtual std::vector<RelocalisationCandidate> placements(const LoopClosureFrame&) { return {}; }
    // The latest pose of every frame fused so far (the loops' corrections applied), by frame number.
    virtual bool latestPose(uint32_t frame, Pose& pose) const = 0;
    // Kept with a saved map (beside it: loopClosurePathOf), tied to it by the map's save id: a run continued from
    // the map recognises the places it saw. load() throws Error naming the file for a file of another map, a
    // newer version, a truncated or corrupt file; it replaces what the loop closer held.
    virtual void save(const std::filesystem::path& path, uint64_t mapId) const = 0;
    virtual void load(const std::filesystem::path& path, uint64_t mapId) = 0;
    // What it did so far (counts, per-stage times, the loops it tried).
    virtual const LoopClosureStats& stats() const = 0;
};

// Where a map's loop-closure state is kept: beside the map, with the extension .vkloops.
inline std::filesystem::path loopClosurePathOf(const std::filesystem::path& mapPath) {
    std::filesystem::path p = mapPath;
    return p.replace_extension(".vkloops");
}

}  // namespace vkmesh
