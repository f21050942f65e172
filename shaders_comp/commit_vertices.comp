#version 460
// One invocation after mesh_claim: pops the vertices handed out from the heap's free stack.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = 1) in;

void main() {
    uint granted = min(counters.vertexAllocRequests, counters.vertexFreeTop);
    counters.vertexExhausted = counters.vertexAllocRequests - granted;
    counters.vertexFreeTop -= granted;
    counters.verticesInUse += granted;
    counters.vertexHighWater = max(counters.vertexHighWater, counters.verticesInUse);
}
