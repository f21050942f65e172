// The CPU reference of TSDF fusion (shaders_comp/fuse_depth.comp): the projective running-average update of
// a touched block's corners, the rule that says which corners "flipped" (what the incremental mesh must
// re-evaluate), and the cubes around the flipped corners (structure/retype_marks.glsl markCornerRetype), with the shader's
// float operations in the shader's order.
#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include "core/types.h"
#include "cpu/reference_block.h"

namespace vkmesh::cpu {

// What fusion needs besides the image: the volume's parameters and the mesh's notion of an observed corner.
struct FusionRule {
    float voxelSize = 0.0f, truncation = 0.0f, maxWeight = 0.0f;
    float minMeshWeight = 1.0f;   // a corner is observed (meshable) from this weight on
    ColorFusion colorFusion = ColorFusion::Average;
    float colorRecency = 0.2f;
};

// With o/n the old/new weight and sdf, observed = weight >= minMeshWeight, a corner flips when
// observed(o) != observed(n), or observed(n) and (sdf_o < 0) != (sdf_n < 0). (With refinement the mesher
// finds the corners whose meshing sign changed itself: docs/REFINEMENT.md.)
bool cornerFlipped(float oldSdf, float oldWeight, float newSdf, float newWeight, const FusionRule& rule);

// Fuses the frame (push: its camera and depth range) into one block at `coord`: every corner that projects
// into the image onto a valid depth d with sdf = d - z >= -truncation gets sdf' = (sdf w + min(sdf, trunc)) /
// (w + 1), w' = min(w + 1, maxWeight), and, when `color` is given and colour fusion is on, its colour at the
// same pixel folded into the corner's (foldVoxelColor, core/voxel_color.h).
// Appends the corners that flipped (global voxel coordinates) to `flipped` in corner order; returns the
// number of corners updated.
uint32_t fuseBlock(ReferenceBlock& block, const BlockCoord& coord, const DepthImage& depth, const gpu::FramePush& push,
                   const FusionRule& rule, std::vector<std::array<int, 3>>* flipped, const ColorImage* color = nullptr);

// For every flipped corner (global voxel coordinates), the 8 cubes around it (corner - o, o in {0,1}^3) in
// whatever block they lie, for the blocks in `blocks`: the cubes whose MC type may have changed.
std::map<BlockCoord, CubeMask> cubesAroundCorners(const std::vector<std::array<int, 3>>& flipped,
                                                  const std::map<BlockCoord, ReferenceBlock>& blocks);

}  // namespace vkmesh::cpu
