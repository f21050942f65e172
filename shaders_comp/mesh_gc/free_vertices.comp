#version 460
// Incremental mesh, pass 3 (paper §V.E, garbage collection), in its own dispatch so that no free stack is
// popped and pushed at once: every GC candidate still without triangles is freed: refcount 0 -> DEAD with
// one compare-and-swap (a vertex listed twice is freed once), its edge slot emptied and the slot's bit of the
// owned-slot mask cleared (one atomicAnd), its index pushed above the committed top of the free stack.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(counters.candidateCount, params.vertexCapacity)) return;
    uint v = gcCandidate(i);
    bool freed = atomicCompSwap(vertices[v].refcount, 0u, DEAD_REFCOUNT) == 0u;
    uint pushed;
    RESERVE_COUNTER(vertexPushes, freed ? 1u : 0u, pushed);   // one atomic per subgroup
    if (!freed) return;
    uint slot = vertexOwner[v];
    edgeStore(slot, EMPTY_SLOT);
    markSlotEmpty(slot);
    vertexFree[counters.vertexFreeTop + pushed] = v;
}
