#version 460
// Hash rebuild, pass 2, on the cleared table: one invocation per live block inserts its key with one
// atomicCompSwap per probed slot (keys are unique, so a CAS either wins an EMPTY slot or meets another
// key and probes on; nobody waits), then stores the block index and the saved stamp, and points the
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
        uint64_t key = packBlockKey(c.xyz);
        uint slot = hashSlot(c.xyz);
        lost = 1u;
        for (uint probe = 0u; probe < HASH_MAX_PROBES; ++probe) {
            if (atomicCompSwap(hashKeys[slot], KEY_EMPTY, key) == KEY_EMPTY) {
                hashValues[slot] = block;
                hashStamps[slot] = uint(c.w);
                blockCoords[block].w = int(slot);
                lost = 0u;
                break;
            }
            slot = (slot + 1u) & (params.hashCapacity - 1u);
        }
    }
    ADD_COUNTER(rehashLost, lost);
}
