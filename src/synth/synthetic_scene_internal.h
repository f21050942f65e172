// Internal to synthetic_scene.h's implementation (src/synth/shapes.cpp, scenes.cpp, sensor_model.cpp,
// ground_truth.cpp): the angle helpers those files share and the sphere tracer the renderer casts rays with.
#pragma once

#include "synth/synthetic_scene.h"

#include <Eigen/Core>

#include <numbers>
#include <optional>

namespace vkmesh::synth::detail {

inline constexpr double kPi = std::numbers::pi;

inline double degrees(double value) { return value * kPi / 180.0; }

// Where the ray o + t d (d unit length) first meets the surface, t in (0, maxT]; nothing when it does not,
// or when the ray starts inside matter (then nothing in front of it is visible). In shapes.cpp.
std::optional<double> intersectRay(const SyntheticScene& scene, const Eigen::Vector3d& origin,
                                   const Eigen::Vector3d& direction, double maxT);

}  // namespace vkmesh::synth::detail
