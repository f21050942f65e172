// A TSDF corner as vkmesh stores it (shared_layout.h, "A TSDF corner"; docs/ARCHITECTURE.md, "Exact fusion"):
// the sum of the observations' truncated distances in whole steps of truncation / SDF_STEPS_PER_TRUNCATION,
// and their count. The CPU twin of the functions in shaders_comp/structure/block_store.glsl and
// recycle/recycle.glsl: same float operations in the same order (built with -ffp-contract=off), so the CPU
// reference and the GPU agree bit for bit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "shared_layout.h"

namespace vkmesh {

// The two scale factors, computed once on the host for the GPU's parameters and the CPU reference alike.
struct TsdfFixedPoint {
    float stepsPerMetre = 0.0f;   // SDF_STEPS_PER_TRUNCATION / truncation
    float metresPerStep = 0.0f;   // truncation / SDF_STEPS_PER_TRUNCATION (a power-of-two division: exact)
};
inline TsdfFixedPoint tsdfFixedPoint(float truncation) {
    const float steps = float(gpu::SDF_STEPS_PER_TRUNCATION);
    return {steps / truncation, truncation / steps};
}

// The corner's distance in metres: the mean of its steps, 0 without observations.
inline float tsdfMean(int32_t sum, float weight, float metresPerStep) {
    if (weight <= 0.0f) return 0.0f;
    const float steps = float(sum) / weight;
    return steps * metresPerStep;
}

// One observation's truncated distance (metres, in [-truncation, truncation]) in whole steps.
inline int32_t tsdfSteps(float tsdf, float stepsPerMetre) {
    const float scaled = tsdf * stepsPerMetre + 0.5f;
    const float limit = float(gpu::SDF_STEPS_PER_TRUNCATION);
    return int32_t(std::clamp(std::floor(scaled), -limit, limit));
}

// Recycling's starvation lowers a corner's weight and keeps its distance: the sum scales with the weight,
// rounded, never across zero (a starved map forgets, so it is not exact anyway; docs/MESH.md "Recycling").
inline int32_t starvedSum(int32_t sum, float oldWeight, float newWeight) {
    if (newWeight <= 0.0f) return 0;
    const float scaled = float(sum) / oldWeight * newWeight + 0.5f;
    const int32_t s = int32_t(std::floor(scaled));
    return sum < 0 ? std::min(s, -1) : (sum > 0 ? std::max(s, 1) : 0);
}

}  // namespace vkmesh
