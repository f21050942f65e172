#version 460
// One invocation after the frees: the pushed entries join the free stacks. With deferOnOverflow, a pass that
// left cubes for later (a heap or the retype list ran out) marks the mesh pending: the host grows what ran
// out and re-meshes those cubes before the frame's deltas are taken (plan_deltas waits for it).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    counters.vertexFreeTop += counters.vertexPushes;
    counters.verticesInUse -= counters.vertexPushes;
    counters.chunkFreeTop += counters.chunkPushes;
    counters.chunksInUse -= counters.chunkPushes;
    bool leftOver = counters.vertexExhausted != 0u || counters.chunkExhausted != 0u || counters.retypeDeferred != 0u;
    counters.meshPending = params.deferOnOverflow != 0u && leftOver ? 1u : 0u;
}
