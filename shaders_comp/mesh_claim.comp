#version 460
// Incremental mesh, pass 1 (paper §V.C, "lock-based" without a lock): every cube of the retype list
// computes its new MC type and, for each edge the type needs, claims the edge's owner slot with one
// atomicCompSwap(EMPTY -> CLAIMED). The winner takes a vertex from the heap's free stack and stores its
// index; losers do not wait: triangles read the slot in the next pass. Every new vertex is a GC candidate
// (freed after triangulation if no triangle ended up using it).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = WG_LIST) in;

#include "cube_access.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(counters.retypeCount, params.retypeCapacity)) return;
    uint id = retypeList[i];
    if (id == NO_BLOCK) return;
    CubeRef r = cubeRef(id / VOXELS_PER_BLOCK, id % VOXELS_PER_BLOCK);
    float d[8];
    bool present[8];
    bool observed;
    uint mask = edgeMaskOf(loadCube(r, d, present, observed));
    for (uint n = 0u; n < 12u && mask != 0u; ++n) {   // over the set bits only
        uint e = findLSB(mask);
        mask &= mask - 1u;
        uint slot = edgeSlot(r, e);
        if (slot == NO_BLOCK || edgeVertex[slot] != EMPTY_SLOT) continue;
        if (atomicCompSwap(edgeVertex[slot], EMPTY_SLOT, CLAIMED_SLOT) != EMPTY_SLOT) continue;
        // Won the claim: pop a vertex. commit_vertices shrinks the stack in the next dispatch.
        uint rank = atomicAdd(counters.vertexAllocRequests, 1u);
        if (rank < counters.vertexFreeTop) {
            uint v = vertexFree[counters.vertexFreeTop - 1u - rank];
            vertices[v].refcount = 0u;
            vertices[v].createdFrame = frame.frameNumber;
            vertexOwner[v] = slot;
            atomicExchange(edgeVertex[slot], v);
            uint c = atomicAdd(counters.candidateCount, 1u);
            if (c < params.vertexCapacity) gcCandidates[c] = v;
        } else {
            atomicExchange(edgeVertex[slot], EMPTY_SLOT);   // heap exhausted: counted by commit_vertices
        }
    }
}
