// Freeing a block that holds no observation any more (recycle_free: blocks recycling emptied; free_emptied:
// blocks a de-integration emptied): one workgroup per candidate block, called in uniform control flow. A block
// whose 512 weights are all 0 is freed, but only if it owns no mesh state any more: every cube has no type,
// chunk or INCOMPLETE flag and every edge slot is EMPTY (the mesh passes released the triangles reading its
// corners and GC freed the vertices on its edges). Otherwise it is counted (recycleDeferred). Freeing: the hash
// key becomes a tombstone, the block index is pushed above the committed top of the free list (commit_recycle
// moves the top), and its retype mask is cleared, so a block handed out again starts like a never-used one (its
// TSDF is zeroed here; cube state and edge slots were verified empty).
#ifndef VKMESH_FREE_BLOCK_GLSL
#define VKMESH_FREE_BLOCK_GLSL
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"

shared uint weightLeft, meshLeft;

void freeBlockIfEmpty(uint block) {
    if (gl_LocalInvocationIndex == 0u) { weightLeft = 0u; meshLeft = 0u; }
    barrier();
    bool weight = false, mesh = false;
    [[unroll]] for (uint k = 0u; k < VOXELS_PER_INVOCATION; ++k) {
        uint v = block * VOXELS_PER_BLOCK + gl_LocalInvocationIndex + k * WG_BLOCK;
        weight = weight || voxelWeight[v] != 0.0;
        mesh = mesh || cubeState[v] != 0u || edgeVertexX[v] != EMPTY_SLOT || edgeVertexY[v] != EMPTY_SLOT ||
               edgeVertexZ[v] != EMPTY_SLOT;
    }
    // One shared-memory atomic per subgroup, not per invocation.
    if (subgroupOr(uint(weight)) != 0u && subgroupElect()) atomicOr(weightLeft, 1u);
    if (subgroupOr(uint(mesh)) != 0u && subgroupElect()) atomicOr(meshLeft, 1u);
    barrier();
    if (weightLeft != 0u) return;   // still starving (uniform: shared memory after the barrier)
    if (meshLeft != 0u) {
        if (gl_LocalInvocationIndex == 0u) atomicAdd(counters.recycleDeferred, 1u);
        return;
    }
    // A free block is all zero (its weights already are): a block handed out again, or fused without the
    // FRESH flag after a deferred frame (docs/MESH.md, "Capacities"), starts like a never-used one.
    [[unroll]] for (uint k = 0u; k < VOXELS_PER_INVOCATION; ++k) voxelSdfSum[block * VOXELS_PER_BLOCK + gl_LocalInvocationIndex + k * WG_BLOCK] = 0;
    if (gl_LocalInvocationIndex < MASK_WORDS) retypeMask[block * MASK_WORDS + gl_LocalInvocationIndex] = 0u;
    // Meshing signs and TSDF masks: all corners unobserved and d = 0, so outside, not near, not observed.
    if (gl_LocalInvocationIndex < MESH_SIGN_WORDS) meshSigns[block * MESH_SIGN_WORDS + gl_LocalInvocationIndex] = 0u;
    if (gl_LocalInvocationIndex == 0u) {
        uint slot = uint(blockCoords[block].w);
        hashRemoveKey(slot);
        freeList[counters.freeTop + atomicAdd(counters.blocksFreed, 1u)] = block;
    }
}
#endif
