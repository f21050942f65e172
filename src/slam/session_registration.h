// Two sessions of one place put in one world frame (docs/SCALING.md, "Sessions of one place"): the transform that
// takes the second session's world into the first's, found from the frames both maps keep (their frame stores).
//
// Each session's keyframes are its stored frames spaced as the loop closer spaces them (10 cm or 10 degrees). Each
// of (at most maxSecondKeyframes of) the second session's keyframes is recognised among the first's by its random-fern
// code (slam/random_ferns.h): the `candidates` most alike are tried, each by the tracker's ICP of the second
// keyframe's depth against the first keyframe's, started at the first keyframe's pose, and verified as a loop is
// (slam/frame_registration.h: the tracker's loss checks, inliers, RMSE, both ways). Each verified pair gives a
// transform. One pair can be a look-alike, so the answer is what several pairs agree on: the largest set of
// transforms within agreeMetres and agreeDegrees of one of them, at least minAgreeing, averaged. When a second set
// that large agrees on a different transform, the place is ambiguous and nothing is returned. Both are Errors
// naming what was tried: joining two maps wrongly is worse than not joining them.
//
// Deterministic: the same stores give the same transform (fixed fern seed, keyframes in frame order, ties by order).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/frame_store.h"
#include "core/types.h"
#include "gpu/tracking/camera_tracker.h"
#include "slam/frame_registration.h"
#include "slam/random_ferns.h"

namespace vkmesh::slam {

struct SessionRegistrationOptions {
    FernOptions ferns;
    gpu::TrackerOptions tracker;      // the registration's pyramid, gates and stopping rule (the tracker's own)
    int registrationWidth = 320;      // frames halved until at most this wide (as the loop closer)
    double keyframeMetres = 0.10;     // a stored frame is a keyframe once the camera moved this far from the last one
    double keyframeDegrees = 10.0;    // or turned this far
    int maxSecondKeyframes = 24;      // the second session's keyframes tried, spread evenly over it
    int candidates = 4;               // the first session's keyframes most alike each one, tried in that order
    double maxDissimilarity = 0.60;   // ... among those whose fern codes differ in at most this share
    VerificationGates gates;
    double agreeMetres = 0.05, agreeDegrees = 3.0;   // two verified pairs agree on the transform within this
    int minAgreeing = 3;                             // verified pairs that must agree
};

// One pair of keyframes tried.
struct SessionMatch {
    uint32_t secondFrame = 0, firstFrame = 0;   // frame indices in the two stores
    double dissimilarity = 0;                   // of their fern codes
    bool verified = false;
    bool agrees = false;                        // one of the pairs the transform is the mean of
    std::string failure;                        // why it did not verify
    Pose secondToFirst = Pose::Identity();      // the transform this pair gives (when verified)
    double rmse = 0;                            // of its registration, metres
};

struct SessionRegistration {
    Pose secondToFirst = Pose::Identity();      // the second session's world -> the first's
    size_t firstKeyframes = 0, secondKeyframes = 0;   // keyframes made; of the second's, those tried
    size_t secondKeyframesTried = 0;
    size_t registrations = 0, verified = 0, agreeing = 0;
    double spreadMetres = 0, spreadDegrees = 0;   // the furthest an agreeing pair's transform is from the mean
    std::vector<SessionMatch> matches;            // every pair tried, in order
    double milliseconds = 0;
};

// Throws Error when a store holds no frame, or when the transform is not sure (too few verified pairs agree, or
// two sets of pairs agree on different transforms), saying how many pairs were tried, verified and agreed, and
// why the most common rejections happened.
SessionRegistration registerSessions(const FrameStore& first, const FrameStore& second, const SessionRegistrationOptions& options = {});

// The stored frames that are keyframes: the first, then each that moved keyframeMetres or turned keyframeDegrees
// from the last keyframe (ascending indices).
std::vector<uint32_t> storedKeyframes(const FrameStore& store, double keyframeMetres, double keyframeDegrees);

}  // namespace vkmesh::slam
