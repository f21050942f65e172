#version 460
// Lists every block that holds pool memory, for whole-volume passes (the baseline mesh).
// One invocation per hash slot.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint slot = gl_GlobalInvocationID.x;
    if (slot < params.hashCapacity && hashSlotUsed(slot)) {
        uint block = hashValues[slot];
        if (block != NO_BLOCK) blockList[atomicAdd(counters.liveBlockCount, 1u)] = block;
    }
}
