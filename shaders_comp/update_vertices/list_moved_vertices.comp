#version 460
// Incremental mesh, pass 2a (paper §V.B): lists the vertices to move for move_vertices, visiting only what
// exists. The owned-slot masks (cube_mesh.glsl: one bit per edge slot that holds a vertex) of the dirty blocks
// whose vertices move (blockMovesVertices: fused this frame, all of them; blockReadsMovedCorners: a block below a
// fused one, only the cubes on its upper faces, which read a neighbour's corners; the blocks dirty only
// because refinement reaches one block further list nothing), WORDS_PER_INVOCATION words of one axis per
// invocation (6 invocations per dirty block): it reserves room for their set bits (one atomic per subgroup) and
// lists each of those slots. Then one invocation per vertex created this frame (the GC candidates so far): a cube
// can claim an edge owned by a block whose vertices do not move, whose mask is not visited, so such a vertex's
// slot is listed here (one in a moving block already was). The cost follows the frame (the moving blocks' mask
// words and set bits, the new vertices), not the map. What is listed is the edge slot, not the vertex:
// move_vertices reads the vertex there, and the loop over the bits loads nothing (measured on lavapipe, a load per
// bit inside this divergent loop cost more than the scan of the whole heap it replaces on a small map). 8 words per invocation rather than 1: the
// per-invocation part (dirty list, reservation) is paid 8 times less (listing -25 % on the soak's first lap).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

const uint WORDS_PER_INVOCATION = OWNED_WORDS_PER_INVOCATION;   // of one axis (MASK_WORDS = 16 per axis): 256 cubes
const uint GROUPS_PER_BLOCK = OWNED_SLOT_WORDS / WORDS_PER_INVOCATION;

// The cubes of a mask word (of one axis: z = word / 2, y = 4 (word % 2) + bit / 8, x = bit % 8) whose vertices move
// in a block stamped MESH_STAMP_READS_MOVED: those on its upper faces (x, y or z = 7), the only cubes that read a
// neighbour's corners, a third of the block. Which neighbours moved is not looked up: on lavapipe the lookups (7 per
// invocation) cost about what moving the few more vertices costs.
uint upperFaceCubes(uint word) {
    return word >= MASK_WORDS - 2u ? ~0u : 0x80808080u | ((word & 1u) != 0u ? 0xFF000000u : 0u);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint groups = counters.dirtyCount * GROUPS_PER_BLOCK;
    uint created = min(counters.candidateCount, params.vertexCapacity);
    uint count = 0u, base = 0u, cubes = 0u, axis = 0u, firstWord = 0u, single = EMPTY_SLOT;
    bool movesAll = false, movesFaces = false;
    if (i < groups) {
        uint block = dirtyList[i / GROUPS_PER_BLOCK], first = (i % GROUPS_PER_BLOCK) * WORDS_PER_INVOCATION;
        base = block * OWNED_SLOT_WORDS + first;
        axis = first / MASK_WORDS;
        firstWord = first % MASK_WORDS;
        movesAll = blockMovesVertices(block);
        movesFaces = blockReadsMovedCorners(block);
        if (movesAll || movesFaces)
            for (uint w = 0u; w < WORDS_PER_INVOCATION; ++w)
                count += bitCount(ownedSlots[base + w] & (movesAll ? ~0u : upperFaceCubes(firstWord + w)));
        cubes = block * VOXELS_PER_BLOCK + firstWord * 32u;   // the cube of bit 0 of the first word
    } else if (i - groups < created) {
        // Listed here unless the scan of its block's mask lists it (the same test, so never twice).
        uint slot = vertexOwner[gcCandidate(i - groups)];
        uint block = slot / (VOXELS_PER_BLOCK * 3u), cube = (slot / 3u) % VOXELS_PER_BLOCK;
        bool scanned = blockMovesVertices(block) ||
                       (blockReadsMovedCorners(block) && (upperFaceCubes(cube / 32u) & (1u << (cube % 32u))) != 0u);
        if (!scanned) single = slot;
    }
    uint at = reserveMovedVertices(single != EMPTY_SLOT ? 1u : count);   // uniform control flow; sizes move_vertices
    if (single != EMPTY_SLOT) listMovedVertex(at, single);
    for (uint w = 0u; w < WORDS_PER_INVOCATION && count != 0u; ++w) {
        uint b = ownedSlots[base + w] & (movesAll ? ~0u : upperFaceCubes(firstWord + w));
        for (uint n = 0u; n < 32u && b != 0u; ++n) {   // over the set bits only: the slot, not its vertex (no load)
            listMovedVertex(at++, (cubes + 32u * w + uint(findLSB(b))) * 3u + axis);
            b &= b - 1u;
        }
    }
}
