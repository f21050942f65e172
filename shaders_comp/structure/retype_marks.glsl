// When a TSDF corner's sign or observed state (weight >= minMeshWeight) flips, the 8 cubes around it may
// change MC type: their bits are set in their block's retype mask, and the mesh passes retype only those
// cubes (docs/MESH.md). Cubes at -x/-y/-z of the block's low faces belong to the blocks behind, looked up
// here, per corner: few corners flip, and a workgroup-wide table would cost a barrier (expensive on
// lavapipe). Used by block recycling (which zeroes or decays weights). Fusion records its flipped corners instead
// (cornerFlips, frame_lists.glsl) and decide_mesh_signs marks the cubes around them, with those around the corners
// whose meshing sign changed (refinement).
#ifndef VKMESH_RETYPE_MARKS_GLSL
#define VKMESH_RETYPE_MARKS_GLSL
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"

void markCornerRetype(uint block, uint local) {
    uvec3 l = uvec3(local % BLOCK_SIDE, (local / BLOCK_SIDE) % BLOCK_SIDE, local / (BLOCK_SIDE * BLOCK_SIDE));
    for (uint o = 0u; o < 8u; ++o) {
        uvec3 off = uvec3(o & 1u, (o >> 1) & 1u, (o >> 2) & 1u);
        uvec3 under = uvec3(lessThan(l, off));   // 1 on an axis where the cube lies in the block behind
        uint b = any(bvec3(under)) ? findBlock(blockCoords[block].xyz - ivec3(under)) : block;
        if (b == NO_BLOCK) continue;
        uvec3 c = (l + uvec3(BLOCK_SIDE) - off) % BLOCK_SIDE;
        uint cube = (c.z * BLOCK_SIDE + c.y) * BLOCK_SIDE + c.x;
        atomicOr(retypeMask[b * MASK_WORDS + cube / 32u], 1u << (cube % 32u));
    }
}
#endif
