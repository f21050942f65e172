// Mesh refinement (paper §V.F, docs/REFINEMENT.md): noisy corners within epsilon of the surface are snapped so
// that cubes take the six "regular" types (a plane parallel to a cube face splitting the cube in two halves).
// refinedCubeType() is what the meshers use (src/cpu/reference_mesh_dirty.cpp; shaders_comp/structure/
// cube_access.glsl computes the same function): flips are decided per corner, so the mesh has no cracks.
// refineType() is the paper's rule as written, per cube (it cracks the mesh); kept as the specification the
// per-corner rule is measured against (docs/REFINEMENT.md) and unit-tested, not used by the meshers.
#pragma once

#include <array>
#include <cstdint>

#include "shared_layout.h"

namespace vkmesh {

// The six regular types in vkmesh's corner numbering (corner i at (i&1, i>>1&1, i>>2&1)), in the order that
// breaks ties: inside half z = 0, z = 1, y = 0, y = 1, x = 0, x = 1.
inline constexpr std::array<uint8_t, 6> kRegularTypes{0x0F, 0xF0, 0x33, 0xCC, 0x55, 0xAA};

// The default refinement epsilon, metres: half a voxel (docs/REFINEMENT.md; GpuVolumeConfig::refineEpsilonVoxels).
inline float defaultRefineEpsilon(float voxelSize) { return 0.5f * voxelSize; }

// Where the vertex of an edge sits along it, s from the low corner: the zero crossing d_lo / (d_lo - d_hi) in
// [0, 1] (the midpoint when the values are equal, which only an edge meshed across a flipped corner has).
// No vertex sits on a corner, so that no two vertices coincide: s stays 1/REFINED_EDGE_MARGIN_INVERSE off the
// ends (a corner's distance is exactly 0 whenever its integer step sum is, shared_layout.h "A TSDF corner",
// and the crossing would then be the corner itself, shared by every edge leaving it), and in a refined mesh it
// stops 1/FLIPPED_EDGE_MARGIN_INVERSE before a flipped corner on an edge whose corners share a raw sign
// (docs/REFINEMENT.md, "Vertices"). The float operations of edgeCrossing in shaders_comp/structure/cube_access.glsl.
inline float edgeCrossing(float dLo, float dHi, bool refined) {
    if (dLo == dHi) return 0.5f;
    const uint32_t inverse = refined && (dLo < 0.0f) == (dHi < 0.0f) ? gpu::FLIPPED_EDGE_MARGIN_INVERSE : gpu::REFINED_EDGE_MARGIN_INVERSE;
    const float margin = 1.0f / float(inverse);
    const float s = dLo / (dLo - dHi);
    return s < margin ? margin : (s > 1.0f - margin ? 1.0f - margin : s);
}

// True when t (0..255) is one of kRegularTypes.
bool isRegularType(int t);

// The type MC uses for a cube with refinement on (docs/REFINEMENT.md):
//   prev = the cube's stored type (the type its current triangles were built from), t = the type of its 8
//   corners now (0 when unobserved), d = the corner values (metres), epsilon = refineEpsilon (metres).
// 1. t is 0, 255 or regular, or popcount(prev ^ t) > 3: t.
// 2. Candidates: every regular r with popcount(r ^ t) <= 3 whose flipped corners (bits of r ^ t) all have
//    |d[i]| < epsilon.
// 3. No candidate: t; otherwise the candidate with the smallest float sum of |d[i]| over its flipped corners
//    (summed in increasing i), ties to the earlier one in kRegularTypes.
int refineType(int prev, int t, const float d[8], float epsilon);

}  // namespace vkmesh

namespace vkmesh {

// ---- Crack-free refinement: flips decided per corner (docs/REFINEMENT.md) ------------------------------------
// The meshing sign of a corner is a pure function of the TSDF in the 3x3x3 corners around it, so every cube
// sharing the corner sees the same sign and neighbouring cubes always meet on their shared face.

// Hamming distance from type t to the nearest "good" type: 0, 255 or one of kRegularTypes (0 for those).
int regularDistance(int t);

// The sign of a corner for meshing, with refinement on (epsilon in metres), from the 3x3x3 corners around it:
// index cornerWindowIndex(x, y, z) with x, y, z in [-1, 1], the corner itself at (0, 0, 0). observed: the
// corner's block exists and its weight is at least minMeshWeight; d: its TSDF value (anything when not
// observed). The corner is inside iff d < 0, except that an observed corner with |d| < epsilon whose 27-corner
// window is all observed (the 8 cubes around it are) flips when that strictly lowers the sum of
// regularDistance() over those 8 cubes, each typed from the raw signs of its corners, and at most 2 of its 6
// edge neighbours share its raw sign (more would pile clamped vertices onto it). Only signs and the one
// |d| < epsilon test enter: integer arithmetic, exact. The GPU computes it once per corner
// (decide_mesh_signs, from per-block bit masks of the TSDF: refinedSignWord below) and stores it.
inline constexpr int kCornerWindowSize = 27;
constexpr int cornerWindowIndex(int x, int y, int z) { return (x + 1) + 3 * ((y + 1) + 3 * (z + 1)); }
bool refinedCornerInside(const float d[kCornerWindowSize], const bool observed[kCornerWindowSize], float epsilon);

// ---- The GPU's word decision on the host (decide_mesh_signs; shaders_comp/retype/sign_window.h) ----------------
// The masks of the TSDF of one block as fusion keeps them on the GPU (shared_layout.h, MESH_SIGN_RAW, _NEAR,
// _OBSERVED): bit local % 32 of word local / 32 (local = x + 8 (y + 8 z)); raw: d < 0, near: observed and
// |d| < epsilon, observed: weight >= minMeshWeight.
struct TsdfMasks {
    std::array<uint32_t, 16> raw{}, near{}, observed{};
};
TsdfMasks tsdfMasks(const float sdf[512], const float weight[512], float minMeshWeight, float epsilon);
// The meshing signs of the 32 corners of word `word` of the block at the centre of `blocks` (the 3x3x3 blocks
// around it, index cornerWindowIndex(x, y, z) of the block offset; nullptr: not allocated), computed by the very
// code the GPU runs (sign_window.h). Bit i equals refinedCornerInside() of corner 32 word + i (tested).
// `evaluated`: how many corners were decided from their window bit by bit.
uint32_t refinedSignWord(const std::array<const TsdfMasks*, 27>& blocks, uint32_t word, uint32_t* evaluated = nullptr);

// A 4x4x4 window of corners around a cube: offsets -1..2 on each axis from the cube's corner 0, index
// windowIndex(x, y, z) with x, y, z in [-1, 2].
inline constexpr int kWindowSide = 4, kWindowSize = 64;
constexpr int windowIndex(int x, int y, int z) { return (x + 1) + kWindowSide * ((y + 1) + kWindowSide * (z + 1)); }

// The type MC builds for the cube at window offset (0, 0, 0), with refinement on: 0 unless its 8 corners are
// observed; bit i set iff refinedCornerInside() of corner i (whose 3x3x3 window lies in the cube's 4x4x4).
int refinedCubeType(const float d[kWindowSize], const bool observed[kWindowSize], float epsilon);

}  // namespace vkmesh
