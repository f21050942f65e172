// The CPU reference of vkmesh's GPU stages up to the TSDF: one frame = block allocation along truncation
// bands (reference_allocation.h), TSDF fusion and the corners it flips (reference_fusion.h), then bounded-map
// recycling (reference_recycling.h); and the baseline marching-cubes mesh (reference_baseline.h). Each stage
// is written serially and plainly in its own file, with the same float operations in the same order as its
// shaders (shaders_comp/*.comp), so tests can compare GPU and CPU results value for value. The block hash
// has its own reference (reference_hash.h); this volume keeps its blocks in an ordered map.
#pragma once

#include <Eigen/Core>

#include <array>
#include <map>
#include <vector>

#include "core/types.h"
#include "cpu/reference_block.h"
#include "cpu/reference_fusion.h"
#include "cpu/reference_recycling.h"
#include "shared_layout.h"

namespace vkmesh::cpu {

// What one frame did; the fields mean the same as the GPU's Counters of the same names.
struct ReferenceFrameStats {
    uint32_t validPixels = 0;
    uint32_t blockRequests = 0;
    uint32_t blocksInserted = 0;
    uint32_t touchedCount = 0;
    uint32_t updatedVoxels = 0;
    uint32_t rayTruncated = 0;
    uint32_t outOfRange = 0;       // block visits beyond the block key range
    uint32_t outsideRadius = 0;    // recycling (setRecycling): block visits beyond the keep radius
    uint32_t blocksStarved = 0;
    uint32_t blocksRetired = 0;
    uint32_t blocksFreed = 0;
    uint32_t observationsDropped = 0;  // corner updates not applied (fuseBlock's FusionCount::dropped)
    uint32_t blocksMissing = 0;        // deintegrate(): blocks of the frame's bands the volume does not hold (no longer)
};

class ReferenceVolume {
public:
    // minMeshWeight: a corner is "observed" (meshable) from this weight on. (Mesh refinement is the mesher's
    // alone: ReferenceMesher re-decides every corner of its dirty blocks.)
    explicit ReferenceVolume(const VolumeParams& params, float minMeshWeight = 1.0f);

    float minMeshWeight() const { return minMeshWeight_; }
    const VolumeParams& params() const { return params_; }

    // Bounded maps, the rules of the GPU's recycling passes (shaders_comp/recycle_*.comp, docs/MESH.md): blocks
    // whose centre is farther than keepRadius metres from the camera (> 0) are not allocated, and existing ones
    // have their weights zeroed; blocks not touched for starveAfterFrames frames (> 0) lose starveWeight per
    // corner per frame; either kind is removed once all its weights are 0. Applied at the end of integrate().
    // (lastFlipped() and retypeCubes() do not include the corners recycling changes.)
    void setRecycling(float keepRadius, uint32_t starveAfterFrames, float starveWeight);

    // color: the frame's colour registered to depth (or nullptr), folded in as params.colorFusion says.
    ReferenceFrameStats integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                  const ColorImage* color = nullptr);

    // Takes a frame fused at `cameraToWorld` out again (the GPU's frame with FramePoseGpu::deintegrate): the same
    // blocks, the same steps subtracted; blocks left with weight 0 at every corner are removed. Fusing a frame
    // and de-integrating it at the same pose restores every corner's sum and weight, whatever came between.
    ReferenceFrameStats deintegrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                    const ColorImage* color = nullptr);

    // Blocks in coordinate order.
    const std::map<BlockCoord, ReferenceBlock>& blocks() const { return blocks_; }
    // Places a block as given, replacing any there (tests of single stages: the baseline and the mesher read
    // the volume's blocks). Changes nothing of lastTouched(), lastFlipped() or retypeCubes().
    void setBlock(const BlockCoord& c, const ReferenceBlock& block) { blocks_[c] = block; }

    // Blocks whose truncation band a pixel of the image crosses (the allocation stage alone).
    std::vector<BlockCoord> blocksTouchedBy(const DepthImage& depth, const Intrinsics& intrinsics,
                                            const Pose& cameraToWorld, ReferenceFrameStats* stats = nullptr) const;

    // Baseline mesh: every cube's triangles with 3 vertices of their own (a triangle soup).
    std::vector<Eigen::Vector3f> extractBaselineMesh() const;

    // The blocks touched by the last integrate() call (allocation order), what the incremental mesh marks dirty.
    const std::vector<BlockCoord>& lastTouched() const { return lastTouched_; }

    // The corners (voxels, global coordinates block * 8 + local) that "flipped" in the last integrate() call,
    // in fusion order: the rule of shaders_comp/fuse/fuse_depth.comp. With o/n the old/new weight and sdf,
    // observed = weight >= minMeshWeight, a corner flips when
    //   observed(o) != observed(n), or observed(n) and (sdf_o < 0) != (sdf_n < 0).
    // (A block allocated this frame starts at sdf 0, weight 0.)
    const std::vector<std::array<int, 3>>& lastFlipped() const { return lastFlipped_; }

    // The cubes whose MC type may have changed in the last integrate() call: for every flipped
    // corner, the 8 cubes around it (corner - o, o in {0,1}^3), in whatever block they lie, for the blocks that
    // exist after that call. Every such block is a dirty block of the frame (touched, or touched - o).
    const std::map<BlockCoord, CubeMask>& retypeCubes() const { return retypeCubes_; }
    // The same for the corners whose observed state flipped: what fusion marks when the mesh is refined (a cube's
    // refined type follows its corners' meshing signs, whose changes the mesher finds itself).
    const std::map<BlockCoord, CubeMask>& observedRetypeCubes() const { return observedRetypeCubes_; }
    // Whether the last call may have taken observations away: a deintegrate(), or an integrate() with recycling
    // (starving and retiring lower weights). Otherwise it only added weight: no corner stopped being observed.
    bool lastMayLoseObservations() const { return lastDeintegrated_ || recycling_.enabled(); }
    // The corners (global grid positions) whose observed state the last call flipped.
    const std::vector<std::array<int, 3>>& lastObservedFlipped() const { return lastObservedFlipped_; }
    // Number of cubes in retypeCubes().
    size_t retypeCubeCount() const;

private:
    FusionRule fusionRule() const;

    VolumeParams params_;
    float minMeshWeight_;
    std::map<BlockCoord, ReferenceBlock> blocks_;
    RecyclingRule recycling_;
    uint32_t frame_ = 0;                             // integrate() calls so far (the GPU's frame number)
    std::map<BlockCoord, uint32_t> lastTouchedFrame_;   // the GPU's hash stamp of each block
    std::vector<BlockCoord> lastTouched_;
    std::vector<std::array<int, 3>> lastFlipped_, lastObservedFlipped_;
    std::map<BlockCoord, CubeMask> retypeCubes_, observedRetypeCubes_;
    bool lastDeintegrated_ = false;
};

}  // namespace vkmesh::cpu
