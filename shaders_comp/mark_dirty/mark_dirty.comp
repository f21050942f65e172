#version 460
// Incremental mesh, pass 0 (docs/MESH.md): the dirty blocks of this frame are the touched blocks and the
// existing blocks at T - o, o in {0,1}^3, whose border cubes read corners of T: T moves all its vertices, the
// others those of the border cubes (markBlockDirty, dirtyMarkAt). One invocation per touched entry; the first to
// stamp a block with this frame's number lists it. With refinement the 26 blocks it looks up are all of T's
// neighbours, which it writes to T's neighbour cache (frame_lists.glsl) on the way: cache_neighbors then skips T
// (neighborCacheFilled).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(counters.touchedCount, params.touchedCapacity)) return;
    uint entry = touched[i];
    if (entry == NO_BLOCK) return;
    uint block = entry & INDEX_MASK;
    ivec3 coord = blockCoords[block].xyz;
    // With refinement a corner's meshing sign reads the corners around it, so the corners whose sign may change
    // lie up to one block ahead too: then the dirty blocks are T + o, o in {-1, 0, 1}^3, and decide_mesh_signs
    // re-decides all their corners; the blocks ahead only retype (their vertices read no corner of T).
    uint n = volumeRefines() ? 27u : 8u;
    for (uint o = 0u; o < n; ++o) {
        ivec3 offset = volumeRefines() ? ivec3(int(o % 3u), int((o / 3u) % 3u), int(o / 9u)) - 1
                                           : ivec3(o & 1u, (o >> 1) & 1u, (o >> 2) & 1u);
        uint b = offset == ivec3(0) ? block : findBlock(coord - offset);
        if (volumeRefines()) blockNeighbors[block * NEIGHBORS_PER_BLOCK + (NEIGHBORS_PER_BLOCK - 1u - o)] = b;   // at -offset
        if (b == NO_BLOCK) continue;
        markBlockDirty(b, dirtyMarkAt(offset));
    }
}
