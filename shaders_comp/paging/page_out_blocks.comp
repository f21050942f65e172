#version 460
// Paging out, between frames, pass 1 of 2: one workgroup per block of the block list (blockList[0, liveBlockCount),
// written by the host: blocks no camera will reach soon). Copies every per-block array into the block's record, then
// leaves the block's arrays as free_block.glsl leaves a freed one's (zero TSDF and colour, empty cubes and edge
// slots, no masks); page_out_keys then frees it (two passes: one would bind more storage buffers than a pipeline
// may). Its
// vertices and triangles stay in the heaps: resident cubes' triangles may use the vertices on its edges, and only a
// cube re-meshed with its corners, so with the block resident again, can release them. A block with cubes waiting to
// be re-meshed (retype bits, INCOMPLETE cubes) stays, its record's stamp PAGE_RECORD_KEPT: a pass over the pending
// cubes would miss it.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_store.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"
#include "paging/paging.glsl"

layout(local_size_x = WG_BLOCK) in;

shared uint pending;

void main() {
    uint i = gl_WorkGroupID.x;
    if (i >= counters.liveBlockCount) return;   // the whole workgroup
    uint block = blockList[i];
    uint r = i * PAGE_RECORD_WORDS;
    uint t = gl_LocalInvocationIndex;
    if (t == 0u) pending = 0u;
    barrier();
    bool waits = t < MASK_WORDS && retypeMask[block * MASK_WORDS + t] != 0u;
    for (uint k = t; k < VOXELS_PER_BLOCK; k += WG_BLOCK) waits = waits || (cubeState[block * VOXELS_PER_BLOCK + k] & CUBE_INCOMPLETE) != 0u;
    if (subgroupOr(uint(waits)) != 0u && subgroupElect()) atomicOr(pending, 1u);
    barrier();
    if (pending != 0u) {   // uniform: shared memory after the barrier
        if (t == 0u) pageRecords[r + 3u] = PAGE_RECORD_KEPT;
        return;
    }
    bool color = volumeKeepsColor();
    for (uint k = t; k < VOXELS_PER_BLOCK; k += WG_BLOCK) {
        uint v = block * VOXELS_PER_BLOCK + k;
        pageRecords[r + PAGE_RECORD_SDF + k] = uint(voxelSdfSum[v]);
        pageRecords[r + PAGE_RECORD_WEIGHT + k] = floatBitsToUint(voxelWeight[v]);
        pageRecords[r + PAGE_RECORD_COLOR + k] = color ? voxelColor[v] : 0u;
        pageRecords[r + PAGE_RECORD_EDGES + k] = edgeVertexX[v];
        pageRecords[r + PAGE_RECORD_EDGES + VOXELS_PER_BLOCK + k] = edgeVertexY[v];
        pageRecords[r + PAGE_RECORD_EDGES + 2u * VOXELS_PER_BLOCK + k] = edgeVertexZ[v];
        pageRecords[r + PAGE_RECORD_CUBE_STATE + k] = cubeState[v];
        voxelSdfSum[v] = 0;
        voxelWeight[v] = 0.0;
        if (color) voxelColor[v] = 0u;
        edgeVertexX[v] = EMPTY_SLOT;
        edgeVertexY[v] = EMPTY_SLOT;
        edgeVertexZ[v] = EMPTY_SLOT;
        cubeState[v] = 0u;
    }
    if (t < OWNED_SLOT_WORDS) {
        pageRecords[r + PAGE_RECORD_OWNED + t] = ownedSlots[block * OWNED_SLOT_WORDS + t];
        ownedSlots[block * OWNED_SLOT_WORDS + t] = 0u;
    }
    if (t < MASK_WORDS) {
        pageRecords[r + PAGE_RECORD_RETYPE + t] = retypeMask[block * MASK_WORDS + t];
        retypeMask[block * MASK_WORDS + t] = 0u;
    }
    if (t < MESH_SIGN_WORDS) {
        pageRecords[r + PAGE_RECORD_SIGNS + t] = meshSigns[block * MESH_SIGN_WORDS + t];
        meshSigns[block * MESH_SIGN_WORDS + t] = 0u;
    }
    if (t == 0u) pageRecords[r + 3u] = 0u;   // paged out (page_out_keys writes the stamp)
}
