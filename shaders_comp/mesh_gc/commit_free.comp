#version 460
// One invocation after the frees: the pushed entries join the free stacks.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    counters.vertexFreeTop += counters.vertexPushes;
    counters.verticesInUse -= counters.vertexPushes;
    counters.chunkFreeTop += counters.chunkPushes;
    counters.chunksInUse -= counters.chunkPushes;
}
