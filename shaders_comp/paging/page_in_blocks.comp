#version 460
// Paging in, between frames: one workgroup per block of the block list (blockList[0, liveBlockCount): free blocks
// the host popped off the free list). Writes each block's record into its per-block arrays, its coordinate with
// w = the saved hash stamp (rehash_insert, dispatched next, inserts the key, restores the stamp and points w at the
// slot), and points the owner of every vertex on its edges at the block's new place in the pool ((block * 512 +
// cube) * 3 + axis): the mesh GC clears a vertex's edge slot through its owner.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_store.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"
#include "paging/paging.glsl"

layout(local_size_x = WG_BLOCK) in;

void restoreEdge(uint axis, uint block, uint k, uint slot) {
    if (slot != EMPTY_SLOT) vertexOwner[slot] = (block * VOXELS_PER_BLOCK + k) * 3u + axis;
}

void main() {
    uint i = gl_WorkGroupID.x;
    if (i >= counters.liveBlockCount) return;   // the whole workgroup
    uint block = blockList[i];
    uint r = i * PAGE_RECORD_WORDS;
    uint t = gl_LocalInvocationIndex;
    bool color = volumeKeepsColor();
    for (uint k = t; k < VOXELS_PER_BLOCK; k += WG_BLOCK) {
        uint v = block * VOXELS_PER_BLOCK + k;
        voxelSdfSum[v] = int(pageRecords[r + PAGE_RECORD_SDF + k]);
        voxelWeight[v] = uintBitsToFloat(pageRecords[r + PAGE_RECORD_WEIGHT + k]);
        if (color) voxelColor[v] = pageRecords[r + PAGE_RECORD_COLOR + k];
        uint x = pageRecords[r + PAGE_RECORD_EDGES + k];
        uint y = pageRecords[r + PAGE_RECORD_EDGES + VOXELS_PER_BLOCK + k];
        uint z = pageRecords[r + PAGE_RECORD_EDGES + 2u * VOXELS_PER_BLOCK + k];
        edgeVertexX[v] = x;
        edgeVertexY[v] = y;
        edgeVertexZ[v] = z;
        restoreEdge(0u, block, k, x);
        restoreEdge(1u, block, k, y);
        restoreEdge(2u, block, k, z);
        cubeState[v] = pageRecords[r + PAGE_RECORD_CUBE_STATE + k];
    }
    if (t < OWNED_SLOT_WORDS) ownedSlots[block * OWNED_SLOT_WORDS + t] = pageRecords[r + PAGE_RECORD_OWNED + t];
    if (t < MASK_WORDS) retypeMask[block * MASK_WORDS + t] = pageRecords[r + PAGE_RECORD_RETYPE + t];
    if (t < MESH_SIGN_WORDS) meshSigns[block * MESH_SIGN_WORDS + t] = pageRecords[r + PAGE_RECORD_SIGNS + t];
    if (t == 0u)
        blockCoords[block] = ivec4(int(pageRecords[r]), int(pageRecords[r + 1u]), int(pageRecords[r + 2u]), int(pageRecords[r + 3u]));
}
