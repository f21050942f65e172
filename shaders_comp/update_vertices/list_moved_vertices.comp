#version 460
// Incremental mesh, pass 2a (paper §V.B): lists the vertices to move for move_vertices, visiting only what
// exists. One invocation per word of each dirty block's owned-slot mask (cube_mesh.glsl: one bit per edge slot
// that holds a vertex), OWNED_SLOT_WORDS per block: it reserves room for its set bits (one atomic per
// subgroup) and lists the vertex in each of those slots. Then one invocation per vertex created this frame
// (the GC candidates so far): a cube of a dirty block can claim an edge owned by a block that is not dirty,
// whose mask is not visited, so such a vertex is listed here (one whose owner block is dirty already was).
// The cost follows the frame (48 words per dirty block + the new vertices), not the map.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint words = counters.dirtyCount * OWNED_SLOT_WORDS;
    uint created = min(counters.candidateCount, params.vertexCapacity);
    uint bits = 0u, cubes = 0u, axis = 0u, single = NO_BLOCK;
    if (i < words) {
        uint block = dirtyList[i / OWNED_SLOT_WORDS], word = i % OWNED_SLOT_WORDS;
        bits = ownedSlots[block * OWNED_SLOT_WORDS + word];
        axis = word / MASK_WORDS;
        cubes = block * VOXELS_PER_BLOCK + (word % MASK_WORDS) * 32u;   // the cube of bit 0
    } else if (i - words < created) {
        uint v = gcCandidate(i - words);
        if (meshStamps[vertexOwner[v] / (VOXELS_PER_BLOCK * 3u)] != frame.frameNumber) single = v;
    }
    uint at = reserveMovedVertices(single != NO_BLOCK ? 1u : bitCount(bits));   // uniform control flow
    if (single != NO_BLOCK) listMovedVertex(at, single);
    for (uint n = 0u; n < 32u && bits != 0u; ++n) {   // over the set bits only
        uint cube = cubes + uint(findLSB(bits));
        bits &= bits - 1u;
        listMovedVertex(at++, axis == 0u ? edgeVertexX[cube] : (axis == 1u ? edgeVertexY[cube] : edgeVertexZ[cube]));
    }
}
