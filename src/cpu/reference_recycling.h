// The CPU reference of bounded maps (docs/MESH.md, "Recycling blocks"; shaders_comp/recycle_*.comp): blocks
// whose centre is farther than keepRadius from the camera are not allocated and the existing ones have their
// weights zeroed (retired); blocks not touched for starveAfterFrames frames lose starveWeight per corner per
// frame (starved); either kind is freed once all its weights are 0.
#pragma once

#include <cstdint>
#include <map>

#include "cpu/reference_block.h"

namespace vkmesh::cpu {

struct RecyclingRule {
    float keepRadius = 0.0f;         // metres; 0 = no radius
    uint32_t starveAfterFrames = 0;  // 0 = no starvation
    float starveWeight = 0.0f;
    bool enabled() const { return keepRadius > 0.0f || starveAfterFrames > 0; }
};

// blockOutsideKeepRadius of structure/frame.glsl, the same float operations in the same order: whether the block's
// centre lies farther than keepRadius (> 0) from the camera position (the last column of cameraToWorld rows).
bool blockOutsideKeepRadius(const BlockCoord& c, float voxelSize, float keepRadius, const float cameraToWorld[3][4]);

struct RecyclingStats {
    uint32_t blocksStarved = 0;  // idle blocks whose weights decayed
    uint32_t blocksRetired = 0;  // blocks beyond the radius whose weights were zeroed
    uint32_t blocksFreed = 0;    // blocks removed (all weights 0)
};

// One frame's recycling after fusion (recycle_retire.comp, then recycle_free.comp): `lastTouchedFrame` is the
// GPU's hash stamp per block (the caller records the frame's touched blocks first; a block without one counts
// as last touched in frame 0), `frame` the current frame number. Freed blocks leave both maps. Unlike the GPU,
// which defers freeing a block that still owns mesh state, a block is freed as soon as its weights are 0.
// A starved corner keeps its distance (starvedSum, core/tsdf_corner.h; metresPerStep: tsdfFixedPoint's).
RecyclingStats recycleBlocks(std::map<BlockCoord, ReferenceBlock>& blocks, std::map<BlockCoord, uint32_t>& lastTouchedFrame,
                             uint32_t frame, const RecyclingRule& rule, float voxelSize, float metresPerStep,
                             const float cameraToWorld[3][4]);

}  // namespace vkmesh::cpu
