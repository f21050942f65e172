#version 460
// Hash rebuild or growth, pass 2, on the cleared (possibly larger) table: one invocation per live block
// inserts its key (structure/block_hash.glsl: keys are unique, so each claim either wins an EMPTY slot or
// meets another key and probes on; nobody waits), then stores the block index and the saved stamp, and points the
// block's w back at its new slot. A block finding no slot within HASH_MAX_PROBES is counted (rehashLost).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint lost = 0u;
    if (i < counters.liveBlockCount) {
        uint block = blockList[i];
        ivec4 c = blockCoords[block];
        bool inserted;
        uint slot = hashInsertKey(c.xyz, inserted);
        if (slot != NO_BLOCK) {
            hashValues[slot] = block;
            hashStamps[slot] = uint(c.w);
            blockCoords[block].w = int(slot);
        } else {
            lost = 1u;
        }
    }
    ADD_COUNTER(rehashLost, lost);
}
