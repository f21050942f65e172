#version 460
// Paging out, pass 2 of 2: one invocation per block of the block list. A block page_out_blocks copied (its record's
// stamp word not PAGE_RECORD_KEPT) gets its coordinate and hash stamp in the record's first words, its hash key
// turned into a tombstone and its index pushed on the free list above counters.freeTop; counters.blocksFreed counts
// them (the host zeroes it before and moves the top after).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"
#include "paging/paging.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counters.liveBlockCount) return;
    uint r = i * PAGE_RECORD_WORDS;
    if (pageRecords[r + 3u] == PAGE_RECORD_KEPT) return;
    uint block = blockList[i];
    ivec4 c = blockCoords[block];
    uint slot = uint(c.w);
    pageRecords[r] = uint(c.x);
    pageRecords[r + 1u] = uint(c.y);
    pageRecords[r + 2u] = uint(c.z);
    pageRecords[r + 3u] = hashStamps[slot];
    hashRemoveKey(slot);
    freeList[counters.freeTop + atomicAdd(counters.blocksFreed, 1u)] = block;
}
