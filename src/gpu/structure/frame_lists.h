// Component: the per-frame lists, what one pass hands the next within a frame (GLSL:
// shaders_comp/structure/frame_lists.glsl; their lengths are in Counters):
//   touched      the blocks the frame's depth touched (allocate -> fuse, mark_dirty);
//   block list   every live block (collect_blocks -> recycling, hash rebuild, whole-volume passes);
//   dirty list   the blocks to re-mesh, deduplicated with per-block mesh stamps (mark_dirty -> retype);
//   retype masks one bit per cube that may change type; persistent: bits left over (deferred or
//                INCOMPLETE cubes) wait for the next pass (fuse, recycling -> collect_retype);
//   retype list  the cubes of this pass (collect_retype -> claim, triangulate);
//   garbage      GC candidate vertices and released chunks (claim, triangulate -> mesh_gc);
//   moved        the edge slots of the vertices whose corners may have changed (list_moved_vertices -> move_vertices);
//   neighbours   each dirty block's 26 neighbour blocks (cache_neighbors -> the mesh passes' cubeRef);
//   corner flips one bit per corner whose sign or observed state fusion flipped (fuse -> decide_mesh_signs,
//                which marks the cubes around them and clears the words);
//   mesh signs   with refinement, one bit per corner: inside for meshing (decide_mesh_signs -> claim,
//                triangulate), persistent and derived from the TSDF alone (docs/REFINEMENT.md); and the masks of
//                the TSDF it is decided from: raw sign, near, observed (fuse, recycling, map load -> decide_mesh_signs).
#pragma once

#include "core/map_format.h"
#include "gpu/structure/component.h"
#include "gpu/layout.h"

namespace vkmesh::gpu {

struct FrameListCapacities {
    uint32_t blocks = 0;     // the block pool: block list, dirty list, stamps, masks
    uint32_t touched = 0;    // blocks one frame may touch
    uint32_t retype = 0;     // cubes one mesh pass may retype
    uint32_t vertices = 0;   // the vertex heap (GC candidates, moved vertices)
    uint32_t chunks = 0;     // the chunk heap (released chunks)
};

class FrameLists {
public:
    FrameLists(const vk::Context& context, const vk::BindingTable& table, const FrameListCapacities& capacities);

    const FrameListCapacities& capacities() const { return capacities_; }
    const vk::Buffer& retypeMasks() const { return retypeMask_; }
    const vk::Buffer& meshSigns() const { return meshSigns_; }
    // Clears the stamps and retype masks (a new or reset mesh; the mesh signs and TSDF masks are kept).
    void recordReset(VkCommandBuffer cmd) const;
    // Between frames: lists for larger capacities (never smaller). The persistent parts (mesh stamps,
    // retype masks, mesh signs) keep their contents; the rest only ever holds the current frame's entries.
    void grow(const FrameListCapacities& capacities);
    // Map files: the live blocks' retype masks (the only persistent list besides the mesh stamps, which
    // only ever compare equal to the current frame number and so need not be kept).
    void saveRetypeMasks(map::MapData& map, const std::vector<uint32_t>& blocks) const;
    void loadRetypeMasks(const map::MapData& map, const std::vector<uint32_t>& blocks);
    // The live block list (blockList), as collect_blocks would write it: what the hash re-insertion reads.
    void uploadBlockList(const std::vector<uint32_t>& blocks);
    void pools(std::vector<PoolInfo>& out) const {
        listPools(out, {&touched_, &blockList_, &meshStamps_, &dirtyList_, &retypeMask_, &retypeList_, &garbage_, &moved_, &neighbors_, &meshSigns_,
                        &cornerFlips_});
    }

private:
    const vk::Context& context_;
    const vk::BindingTable& table_;
    FrameListCapacities capacities_;
    vk::Buffer touched_, blockList_, meshStamps_, dirtyList_, retypeMask_, retypeList_, garbage_, moved_, neighbors_, meshSigns_,
        cornerFlips_;
};

}  // namespace vkmesh::gpu
