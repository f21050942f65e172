#version 460
// One invocation after mesh_claim: pops the vertices handed out from the heap's free stack, sizes mesh_triangulate's
// dispatch to the cubes mesh_claim listed as changed (retypeDispatch: claim has used it), and sizes
// list_moved_vertices' dispatch: 6 invocations per dirty block (8 owned-slot mask words each), then one per vertex
// created so far (the GC candidates), so its cost follows the frame, never the size of the map. move_vertices'
// dispatch starts at 0 for the listing to raise.
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
    uint items = counters.dirtyCount * (OWNED_SLOT_WORDS / OWNED_WORDS_PER_INVOCATION) + created;
    counters.movedCount = 0u;
    counters.vertexDispatch[0] = 0u;   // move_vertices': list_moved_vertices raises it as it lists
    counters.vertexDispatch[1] = counters.vertexDispatch[2] = 1u;
    counters.retypeDispatch[0] = (counters.cubesChanged + WG_LIST - 1u) / WG_LIST;
    counters.ownedDispatch[0] = (items + WG_LIST - 1u) / WG_LIST;
    counters.ownedDispatch[1] = counters.ownedDispatch[2] = 1u;
}
