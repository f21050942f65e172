#version 460
// Incremental mesh, pass 1 (paper §V.C): every cube of the retype list computes its new (refined) MC type, lists the
// cube with it for mesh_triangulate where it changed (setChangedCube), and, for each edge the type needs, makes sure
// the edge's owner slot holds a vertex.
//  - Lock-based (default, PARITY_CLASS = 4): the slot is claimed with one atomicCompSwap(EMPTY -> CLAIMED);
//    the winner takes a vertex from the heap's free stack and stores its index; losers do not wait:
//    triangles read the slot in the next pass.
//  - Lock-free (PARITY_CLASS = 0..3, one dispatch each): only cubes whose global parity (x&1, y&1, z&1)
//    is in the class {p, 7 - p} run; no two of them share an edge, so a plain read and write suffice.
// Every new vertex is a GC candidate (freed after triangulation if no triangle ended up using it), and sets
// its slot's bit in the owner block's owned-slot mask (one atomicOr: cubes of a block share the mask words).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"
#include "structure/mc_tables.glsl"
#include "structure/cube_access.glsl"

layout(local_size_x = WG_LIST) in;
layout(constant_id = 0) const uint PARITY_CLASS = 4u;


// Vertex `v` popped for `slot` (the caller owns the slot and stores v in it), a GC candidate at `candidate`.
void initVertex(uint v, uint slot, uint candidate) {
    vertices[v].refcount = 0u;
    vertices[v].createdFrame = frame.frameNumber;
    vertices[v].color = 0u;                                    // until the vertex update gives it one
    vertexOwner[v] = slot;
    markSlotOwned(slot);
    if (candidate < params.vertexCapacity) setGcCandidate(candidate, v);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(counters.retypeCount, params.retypeCapacity)) return;
    uint id = retypeList[i];
    if (id == NO_BLOCK) return;
    CubeRef r = cubeRef(id / VOXELS_PER_BLOCK, id % VOXELS_PER_BLOCK);
    if (PARITY_CLASS < 4u) {
        uint p = (r.cube.x & 1u) | ((r.cube.y & 1u) << 1) | ((r.cube.z & 1u) << 2);   // block origins are even
        if (min(p, 7u - p) != PARITY_CLASS) return;
    }
    uint type = listedCubeType(r);
    uint state = cubeState[id];
    // Classified once: triangulate builds this type, for the cubes listed here only (each entry is in one parity
    // class). A cube keeping its type has its triangles, and vertices on all its edges: nothing to claim.
    bool changed = type != (state & CUBE_TYPE_MASK) || (state & CUBE_INCOMPLETE) != 0u;
    uint k = reserveChangedCubes(changed ? 1u : 0u);   // < retypeCount <= retypeCapacity
    if (!changed) return;
    setChangedCube(k, id, type);
    // First the slots this cube must fill (bit e: edge e's slot was empty and is this invocation's now), then one
    // reservation of vertices and GC candidates per subgroup for all of them (two contended atomics per subgroup
    // instead of two per vertex), then the vertices. commit_vertices shrinks the free stack by the requests.
    uint mask = edgeMaskOf(type), won = 0u;
    for (uint n = 0u; n < 12u && mask != 0u; ++n) {   // over the set bits only
        uint e = findLSB(mask);
        mask &= mask - 1u;
        uint slot = edgeSlot(r, e);
        if (slot == NO_BLOCK || edgeLoad(slot) != EMPTY_SLOT) continue;
        if (PARITY_CLASS < 4u || edgeCompSwap(slot, EMPTY_SLOT, CLAIMED_SLOT) == EMPTY_SLOT) won |= 1u << e;
    }
    uint wanted = bitCount(won), rank, candidate;
    RESERVE_COUNTER(vertexAllocRequests, wanted, rank);   // this invocation's ranks: rank .. rank + wanted - 1
    uint top = counters.vertexFreeTop;
    uint granted = rank >= top ? 0u : min(wanted, top - rank);   // the rest: the heap is exhausted (commit_vertices counts them)
    RESERVE_COUNTER(candidateCount, granted, candidate);
    for (uint n = 0u; n < 12u && won != 0u; ++n) {
        uint e = findLSB(won);
        won &= won - 1u;
        uint slot = edgeSlot(r, e);
        uint v = EMPTY_SLOT;
        if (rank < top) {
            v = vertexFree[top - 1u - rank];
            initVertex(v, slot, candidate++);
        }
        ++rank;
        if (PARITY_CLASS < 4u) edgeStore(slot, v);
        else edgeStoreAtomic(slot, v);
    }
}
