#version 460
// One invocation after mesh_triangulate: pops the triangle chunks handed out, keeps the live-triangle count,
// and sizes the garbage-collection dispatches.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    uint granted = min(counters.chunkAllocRequests, counters.chunkFreeTop);
    counters.chunkExhausted = counters.chunkAllocRequests - granted;
    counters.chunkFreeTop -= granted;
    counters.chunksInUse += granted;
    counters.chunkHighWater = max(counters.chunkHighWater, counters.chunksInUse);
    counters.liveTriangles += counters.trianglesCreated - counters.trianglesReleased;
    uint candidates = min(counters.candidateCount, params.vertexCapacity);
    counters.candidateDispatch[0] = (candidates + WG_LIST - 1u) / WG_LIST;
    counters.candidateDispatch[1] = 1u;
    counters.candidateDispatch[2] = 1u;
    uint releases = min(counters.releaseCount, params.chunkCapacity);
    counters.releaseDispatch[0] = (releases + WG_LIST - 1u) / WG_LIST;
    counters.releaseDispatch[1] = 1u;
    counters.releaseDispatch[2] = 1u;
}
