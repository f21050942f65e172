// Geometric verification of a loop or a relocalisation: a frame registered to a keyframe's depth by the
// tracker's own point-to-plane ICP (the CPU reference of its passes, cpu/reference_tracking.h: the same pyramid,
// association gates, Huber weights and 6x6 solve), coarse to fine at a small resolution, independent of the mesh.
// The keyframe's camera-space points become world-space "model maps" at its pose, exactly what the mesh drawn
// there would give for a surface the keyframe saw alone.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/icp_solve.h"
#include "core/types.h"
#include "cpu/reference_tracking.h"
#include "gpu/tracking/camera_tracker.h"

namespace vkmesh::slam {

// A frame prepared for registration: its depth halved until it is at most maxWidth pixels wide, and the
// tracking pyramid of that (points and normals per level).
struct RegistrationFrame {
    std::vector<cpu::TrackingLevel> levels;
    bool empty() const { return levels.empty(); }
};
RegistrationFrame registrationFrame(const DepthImage& depth, const Intrinsics& intrinsics, const gpu::TrackerOptions& tracker,
                                    int maxWidth = 160);

struct Registration {
    Pose cameraToWorld = Pose::Identity();   // the frame's pose found
    IcpSystem system;                        // level 0's last system (before its step)
    bool solved = false;
    double conditioning = 0;
    int iterations = 0;
    double inlierShare() const { return system.validPixels > 0 ? system.inliers / system.validPixels : 0.0; }
};

// ICP of `frame` against `keyframe` (seen from keyframePose) starting from `initial` (the frame's camera-to-world
// guess): iterations per level coarse to fine (finest first in the array), each level stopping at a tiny step.
Registration registerFrame(const RegistrationFrame& frame, const RegistrationFrame& keyframe, const Pose& keyframePose,
                           const Pose& initial, const gpu::TrackerOptions& tracker, const std::array<int, 3>& iterations = {10, 5, 4});

// What a registration must pass to be trusted as a loop, or as the tie between two sessions of one place, on top of
// the tracker's own loss checks (its jump gates off: the caller bounds how far a match may move the camera).
struct VerificationGates {
    double minInlierShare = 0.50;   // the inliers cover at least this share of the frame's valid pixels
    double maxRmse = 0.015;         // metres
    // Both ways: the keyframe registered back to the frame (placed where the match says) lands within this of where
    // it is. A registration that slid along a weakly constrained direction does not come back.
    double symmetricMetres = 0.01, symmetricDegrees = 0.5;
};
// Why `r` (started from `initial`) does not verify; "" when it does.
std::string registrationFailure(const Registration& r, const Pose& initial, const gpu::TrackerOptions& tracker, const VerificationGates& gates);

struct VerifiedRegistration {
    std::optional<Registration> match;   // the frame's registration, verified both ways
    std::string failure;                 // why not, when there is no match
};
// `frame` registered to `keyframe` (seen from keyframePose) from each of `initials` in turn until one verifies, then
// checked both ways.
VerifiedRegistration verifyRegistration(const RegistrationFrame& frame, const RegistrationFrame& keyframe, const Pose& keyframePose,
                                        const std::vector<Pose>& initials, const gpu::TrackerOptions& tracker, const VerificationGates& gates);

}  // namespace vkmesh::slam
