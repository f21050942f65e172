// Relocalisation by local features (issue 54; docs/LOOP_CLOSURE.md, "Relocalisation"): the ferns compare whole tiny
// images, so a real view turned more than about 20 degrees from every keyframe (TUM fr1/rpy's 119-degree landing)
// looks like no keyframe to them (docs/RESULTS.md, "Place recognition on real pairs"). ORB features (OpenCV's
// features2d) survive that turn: each keyframe keeps its features that have a depth, as points in its camera; a lost
// frame's features are matched against every keyframe's (Lowe's ratio test), and the matches of the keyframes with
// the most are solved for the camera by PnP in RANSAC (OpenCV's calib3d). A keyframe with enough inliers gives a pose to track the frame from:
// the caller's tracking and its checks decide, as for the ferns' candidates.
//
// Deterministic: OpenCV's ORB and brute-force matcher are, and the RANSAC is seeded (cv::theRNG) before each solve.
// Frames without colour have no features (the ferns alone then propose).
#pragma once

#include <cstdint>
#include <vector>

#include "core/types.h"

namespace vkmesh::slam {

struct FeatureOptions {
    bool enabled = true;
    int features = 500;              // ORB keypoints per image (ORB-SLAM's count at VGA is 1000; 500 keep matching cheap)
    double ratio = 0.8;              // Lowe's ratio test: best match closer than this times the second best
    int maxDistance = 64;            // and at most this many of the 256 bits apart (ORB-SLAM's bound for a match)
    int minMatches = 20;             // a keyframe with fewer ratio-test matches is not solved for
    int minInliers = 20;             // PnP inliers a pose needs
    double minInlierShare = 0.30;    // and as a share of the matches
    double reprojectionPixels = 3.0; // RANSAC's inlier threshold at the image's resolution
    int ransacIterations = 200;
    int solveKeyframes = 5;          // PnP for at most this many keyframes, those with the most matches
    int candidates = 2;              // at most this many poses, most inliers first (one per keyframe)
    // Keyframes a lost frame's features are matched against: matching costs about 2 ms a keyframe (OpenCV's
    // brute-force Hamming matcher, 500 x 500 features, this 2-core machine), so a lost frame in a map of more
    // keyframes is matched against the newest quarter of this count and a window of the rest that moves on with
    // each lost frame (slam::LoopCloser): a camera lost for a few frames is matched against every keyframe.
    int matchKeyframes = 64;
    float minDepth = 0.3f, maxDepth = 6.0f;   // a keyframe's feature needs a depth in this range (metres)
};

// One keyframe's features with a depth: descriptors (32 bytes each, ORB) and points in its camera (metres).
struct KeyframeFeatures {
    std::vector<uint8_t> descriptors;    // 32 x count
    std::vector<float> points;           // 3 x count: x, y, z in the keyframe's camera
    size_t count() const { return points.size() / 3; }
};

// A pose proposed for a lost frame.
struct FeatureCandidate {
    int keyframe = -1;                   // index into the keyframes given to propose()
    Pose keyframeToCamera = Pose::Identity();   // the lost frame's camera from the keyframe's: camera = inverse(this)
    int matches = 0, inliers = 0;
};

class FeatureRelocaliser {
public:
    explicit FeatureRelocaliser(const FeatureOptions& options = {});
    // The features of a keyframe: detected on its colour image (grey), kept where its depth (same pixel grid) is
    // measured. Empty without colour. Throws Error when the images' sizes disagree.
    KeyframeFeatures describe(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics) const;
    // Poses for a lost frame (its colour image; its intrinsics), from the keyframes' features: those with enough PnP
    // inliers, most inliers first, at most options().candidates. Empty without colour.
    std::vector<FeatureCandidate> propose(const ColorImage* color, const Intrinsics& intrinsics,
                                          const std::vector<const KeyframeFeatures*>& keyframes) const;
    const FeatureOptions& options() const { return options_; }

private:
    FeatureOptions options_;
};

}  // namespace vkmesh::slam
