#version 460
// Incremental mesh: caches each dirty block's 26 neighbour blocks (blockNeighbors, frame_lists.glsl) for the
// passes that follow, so that they read a neighbour instead of probing the hash. MASK_WORDS invocations per
// dirty block (the dispatch of collect_retype), each writing entries n, n + MASK_WORDS. With refinement mark_dirty has
// already filled the touched blocks' caches (most of the dirty blocks: 2 in 3 on the synthetic room), which are
// skipped here.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/frame_lists.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"

layout(local_size_x = WG_LIST) in;

// Whether mark_dirty wrote the cache of the block at hash slot `slot` this frame: with refinement it writes that of
// every touched block it visits, and it visits them all when the touched list held them all (a block touched past
// its capacity is stamped but not listed). A completion pass (no allocation: touchedCount 0) has no such blocks.
bool neighborCacheFilled(uint slot) {
    return volumeRefines() && counters.touchedCount != 0u && counters.touchedCount <= params.touchedCapacity &&
           hashStamps[slot] == frame.frameNumber;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counters.dirtyCount * MASK_WORDS) return;
    uint block = dirtyList[i / MASK_WORDS];
    ivec4 coord = blockCoords[block];
    if (neighborCacheFilled(uint(coord.w))) return;
    for (uint n = i % MASK_WORDS; n < NEIGHBORS_PER_BLOCK; n += MASK_WORDS) {
        ivec3 offset = ivec3(int(n % 3u), int((n / 3u) % 3u), int(n / 9u)) - 1;
        blockNeighbors[block * NEIGHBORS_PER_BLOCK + n] = offset == ivec3(0) ? block : findBlock(coord.xyz + offset);
    }
}
