// Mesh refinement (paper §V.F, docs/REFINEMENT.md): a cube whose MC type is a few corners away from one of the
// six "regular" types (a plane parallel to a cube face splitting the cube in two halves) takes that regular
// type instead, when every corner it would flip lies within epsilon of the surface. Shared by the CPU
// reference (src/cpu/reference_mesh_dirty.cpp); shaders_comp/structure/cube_access.glsl computes the same function.
#pragma once

#include <array>
#include <cstdint>

namespace vkmesh {

// The six regular types in vkmesh's corner numbering (corner i at (i&1, i>>1&1, i>>2&1)), in the order that
// breaks ties: inside half z = 0, z = 1, y = 0, y = 1, x = 0, x = 1.
inline constexpr std::array<uint8_t, 6> kRegularTypes{0x0F, 0xF0, 0x33, 0xCC, 0x55, 0xAA};

// The default refinement epsilon, metres: half a voxel (docs/REFINEMENT.md; GpuVolumeConfig::refineEpsilonVoxels).
inline float defaultRefineEpsilon(float voxelSize) { return 0.5f * voxelSize; }

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
