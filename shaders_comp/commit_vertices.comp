#version 460
// One invocation after mesh_claim: pops the vertices handed out from the heap's free stack, and sizes
// update_vertices over the part of the heap ever used (indices below the high water).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = 1) in;

void main() {
    uint granted = min(counters.vertexAllocRequests, counters.vertexFreeTop);
    counters.vertexExhausted = counters.vertexAllocRequests - granted;
    counters.vertexFreeTop -= granted;
    counters.verticesInUse += granted;
    counters.vertexHighWater = max(counters.vertexHighWater, counters.verticesInUse);
    counters.vertexDispatch[0] = (counters.vertexHighWater + WG_LIST - 1u) / WG_LIST;
    counters.vertexDispatch[1] = 1u;
    counters.vertexDispatch[2] = 1u;
}
