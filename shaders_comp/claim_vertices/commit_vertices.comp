#version 460
// One invocation after mesh_claim: pops the vertices handed out from the heap's free stack, and chooses
// how this frame's vertices to move are listed: a scan of the heap up to its high water (list_heap_vertices,
// cost ~ size of the map) or a pass over the dirty blocks' cubes plus the new vertices (list_dirty_vertices +
// list_new_vertices, cost ~ size of the frame), whichever visits fewer entries; the other dispatches
// are sized 0. move_vertices then moves what was listed. Measured on lavapipe a heap entry costs about twice a cube, hence the factor 2.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    uint granted = min(counters.vertexAllocRequests, counters.vertexFreeTop);
    counters.vertexExhausted = counters.vertexAllocRequests - granted;
    counters.vertexFreeTop -= granted;
    counters.verticesInUse += granted;
    counters.vertexHighWater = max(counters.vertexHighWater, counters.verticesInUse);
    uint created = min(counters.candidateCount, params.vertexCapacity);   // the GC candidates so far
    uint dirtyCubes = counters.dirtyCount * VOXELS_PER_BLOCK;
    bool scanHeap = params.vertexUpdate == VERTEX_UPDATE_AUTO ? 2u * counters.vertexHighWater < dirtyCubes
                                                              : params.vertexUpdate == VERTEX_UPDATE_HEAP;
    counters.movedCount = 0u;
    counters.heapDispatch[0] = scanHeap ? (counters.vertexHighWater + WG_LIST - 1u) / WG_LIST : 0u;
    counters.vertexDispatch[0] = scanHeap ? 0u : counters.dirtyCount * (VOXELS_PER_BLOCK / WG_BLOCK);
    counters.candidateDispatch[0] = scanHeap ? 0u : (created + WG_LIST - 1u) / WG_LIST;
    counters.heapDispatch[1] = counters.heapDispatch[2] = 1u;
    counters.vertexDispatch[1] = counters.vertexDispatch[2] = 1u;
    counters.candidateDispatch[1] = counters.candidateDispatch[2] = 1u;
}
