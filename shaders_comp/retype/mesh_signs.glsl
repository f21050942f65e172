// Refinement (docs/REFINEMENT.md): re-deciding one corner's meshing sign (cornerMeshInside, cube_access.glsl).
// Where it differs from the stored sign it is stored, and the 8 cubes around the corner are marked for
// retyping: their type changes with it. Used by decide_mesh_signs, and by list_sign_corners for corners that
// do not fit in its list.
#ifndef VKMESH_MESH_SIGNS_GLSL
#define VKMESH_MESH_SIGNS_GLSL
#include "structure/cube_access.glsl"
#include "structure/frame_lists.glsl"

void decideMeshSign(uint block, uint local) {
    bool inside = cornerMeshInside(block, local);
    if (inside == meshSignInside(block, local)) return;
    // Only this invocation decides this corner this pass (each corner is listed once), so a toggle is exact.
    atomicXor(meshSigns[meshSignWord(block, local)], 1u << (local % 32u));
    // The cubes corner - o, o in {0,1}^3: in this block, or on the axes where the corner is at 0, in the
    // blocks behind (from the neighbour cache).
    uvec3 l = cubeOfLocal(local);
    for (uint o = 0u; o < 8u; ++o) {
        uvec3 off = cornerOffset(o);
        ivec3 under = ivec3(lessThan(l, off));
        uint b = under == ivec3(0) ? block : cachedNeighbor(block, -under);
        if (b == NO_BLOCK) continue;
        uint cube = localOfCube((l + uvec3(BLOCK_SIDE) - off) % BLOCK_SIDE);
        atomicOr(retypeMask[b * MASK_WORDS + cube / 32u], 1u << (cube % 32u));
    }
}
#endif
