#version 460
// Stage 2: every touched hash slot that holds no block yet takes one from the pool's free list.
// Each slot is in the touched list once, so no two invocations assign the same slot. The free list is
// only read here; commit_allocation shrinks it in the next dispatch (allocating and freeing never
// share a dispatch). Rewrites each touched entry from "hash slot" to "block index | FRESH_BLOCK".
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint requested = 0u;
    if (i < min(counters.touchedCount, params.touchedCapacity)) {
        uint slot = touched[i];
        uint block = hashValues[slot];
        if (block != NO_BLOCK) {
            touched[i] = block;
        } else {
            requested = 1u;
            uint rank = atomicAdd(counters.allocRequests, 1u);
            if (rank < counters.freeTop) {
                block = freeList[counters.freeTop - 1u - rank];
                hashValues[slot] = block;
                blockCoords[block] = ivec4(hashSlotCoord(slot), int(slot));
                touched[i] = block | FRESH_BLOCK;
            } else {
                // Pool exhausted: the key stays in the table without a block and asks again the next
                // time a frame touches it. Counted by commit_allocation (allocRequests > freeTop).
                touched[i] = NO_BLOCK;
            }
        }
    }
}
