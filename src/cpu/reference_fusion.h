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
    float voxelSize = 0.0f, truncation = 0.0f;
    float minMeshWeight = 1.0f;   // a corner is observed (meshable) from this weight on
    ColorFusion colorFusion = ColorFusion::Average;
    float colorRecency = 0.2f;
};

// With o/n the old/new weight and sdf, observed = weight >= minMeshWeight, a corner flips when
// observed(o) != observed(n), or observed(n) and (sdf_o < 0) != (sdf_n < 0). (With refinement the mesher
// finds the corners whose meshing sign changed itself: docs/REFINEMENT.md.)
bool cornerFlipped(float oldSdf, float oldWeight, float newSdf, float newWeight, const FusionRule& rule);

// What fuseBlock did to a block's corners.
struct FusionCount {
    uint32_t updated = 0;   // corners updated
    uint32_t dropped = 0;   // observations not applied (gpu::Counters::observationsDropped)
};

// Fuses the frame (push: its camera and depth range) into one block at `coord`: every corner that projects
// into the image onto a valid depth d with sdf = d - z >= -truncation gets s = tsdfSteps(min(sdf, trunc))
// added to its sum and 1 to its weight (below SDF_MAX_COUNT; past it the observation is dropped), and, when
// `color` is given and colour fusion is on, its colour at the same pixel folded into the corner's
// (foldVoxelColor, core/voxel_color.h). With `deintegrate` the same s is subtracted and 1 taken from the
// weight (a corner of weight 0 drops it), the colour folded out (unfoldVoxelColor).
// Appends the corners that flipped (global voxel coordinates) to `flipped` in corner order, and those whose
// observed state changed to `observedFlipped` (what fusion marks with refinement, fuse_depth.comp).
FusionCount fuseBlock(ReferenceBlock& block, const BlockCoord& coord, const DepthImage& depth, const gpu::FramePush& push,
                      const FusionRule& rule, std::vector<std::array<int, 3>>* flipped, const ColorImage* color = nullptr,
                      bool deintegrate = false, std::vector<std::array<int, 3>>* observedFlipped = nullptr);

// For every flipped corner (global voxel coordinates), the 8 cubes around it (corner - o, o in {0,1}^3) in
// whatever block they lie, for the blocks in `blocks`: the cubes whose MC type may have changed.
std::map<BlockCoord, CubeMask> cubesAroundCorners(const std::vector<std::array<int, 3>>& flipped,
                                                  const std::map<BlockCoord, ReferenceBlock>& blocks);

}  // namespace vkmesh::cpu
