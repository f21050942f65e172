#version 460
// Incremental mesh, pass 3 (paper §V.D, §V.E): every cube of the retype list whose MC type changed, as mesh_claim
// listed it with its new type (setChangedCube: the cube's mask words and neighbours are not read again; a cube that
// keeps its type keeps its triangles, temporal consistency, and is not listed),
//  - releases its triangles (refcount - 1 on their vertices; a vertex reaching 0 becomes a GC candidate)
//    and builds the new type's triangles from the edge slots claimed in pass 1 (+1 each).
// Triangles live in a chunk of 5 per cube; a cube gaining triangles pops a chunk (committed next pass), a
// cube losing all of them lists its chunk for release (pushed back two passes later). A cube left
// INCOMPLETE (a heap was exhausted) sets its retype bit again: it is rebuilt when its block is next dirty.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"
#include "structure/mc_tables.glsl"
#include "structure/cube_access.glsl"

layout(local_size_x = WG_LIST) in;


uint created = 0u, released = 0u, invalid = 0u, retyped = 0u;

// Cube `id`, whose type is now `type` (mesh_claim's classification: nothing it reads changes in between).
void retype(uint id, uint type) {
    uint state = cubeState[id];
    uint oldType = state & CUBE_TYPE_MASK;
    CubeRef r = cubeRef(id / VOXELS_PER_BLOCK, id % VOXELS_PER_BLOCK);   // the edges' blocks, for a cube that changes
    ++retyped;
    uint chunk = state >> CUBE_CHUNK_SHIFT;   // chunk index + 1, 0 = none
    uint count = triangleCountOf(type);
    // A chunk popped for a cube that gains triangles, or released by one that loses all of them: reserved per
    // subgroup (RESERVE_COUNTER).
    uint chunkRank, releaseAt;
    RESERVE_COUNTER(chunkAllocRequests, count != 0u && chunk == 0u ? 1u : 0u, chunkRank);
    RESERVE_COUNTER(releaseCount, count == 0u && chunk != 0u ? 1u : 0u, releaseAt);

    // Release the old triangles. A vertex that loses its last triangle becomes a GC candidate: the chunk words of
    // those (bit 3 t + j: corner j of triangle t) are listed after the loop, with one reservation per subgroup.
    uint lastUses = 0u;
    if (chunk != 0u) {
        uint base = (chunk - 1u) * CHUNK_WORDS;
        for (uint t = 0u; t < triangleCountOf(oldType); ++t) {
            if (chunkTriangles[base + 3u * t] == INVALID_INDEX) continue;
            [[unroll]] for (uint j = 0u; j < 3u; ++j) {
                uint v = chunkTriangles[base + 3u * t + j];
                if (atomicAdd(vertices[v].refcount, 0xFFFFFFFFu) == 1u) lastUses |= 1u << (3u * t + j);
            }
            ++released;
        }
    }
    uint candidate;
    RESERVE_COUNTER(candidateCount, bitCount(lastUses), candidate);
    for (uint n = 0u; n < 3u * TRIANGLES_PER_CHUNK && lastUses != 0u; ++n) {
        uint word = uint(findLSB(lastUses));
        lastUses &= lastUses - 1u;
        if (candidate < params.vertexCapacity) setGcCandidate(candidate, chunkTriangles[(chunk - 1u) * CHUNK_WORDS + word]);
        ++candidate;
    }

    // Build the new ones.
    bool incomplete = false;
    if (count == 0u) {
        if (chunk != 0u) {
            // Released chunks go back holding no triangle, so a chunk's words alone say which of its
            // triangles exist (the delta passes read them without the cube state).
            uint base = (chunk - 1u) * CHUNK_WORDS;
            for (uint t = 0u; t < TRIANGLES_PER_CHUNK; ++t) chunkTriangles[base + 3u * t] = INVALID_INDEX;
            if (releaseAt < params.chunkCapacity) setReleasedChunk(releaseAt, chunk - 1u);
            chunk = 0u;
        }
    } else {
        if (chunk == 0u) {
            if (chunkRank < counters.chunkFreeTop) chunk = chunkFree[counters.chunkFreeTop - 1u - chunkRank] + 1u;
        }
        if (chunk == 0u) {
            incomplete = true;       // no chunk: counted by commit_chunks
            invalid += count;
        } else {
            uint base = (chunk - 1u) * CHUNK_WORDS;
            for (uint t = 0u; t < count; ++t) {
                uint tri[3];
                bool ok = true;
                [[unroll]] for (uint j = 0u; j < 3u; ++j) {
                    uint slot = edgeSlot(r, triangleEdge(type, 3u * t + j));
                    tri[j] = slot == NO_BLOCK ? EMPTY_SLOT : edgeLoad(slot);
                    ok = ok && tri[j] < CLAIMED_SLOT;
                }
                if (!ok) {
                    chunkTriangles[base + 3u * t] = INVALID_INDEX;
                    incomplete = true;
                    ++invalid;
                    continue;
                }
                [[unroll]] for (uint j = 0u; j < 3u; ++j) {
                    chunkTriangles[base + 3u * t + j] = tri[j];
                    atomicAdd(vertices[tri[j]].refcount, 1u);
                }
                ++created;
            }
            for (uint t = count; t < TRIANGLES_PER_CHUNK; ++t) chunkTriangles[base + 3u * t] = INVALID_INDEX;
        }
    }
    cubeState[id] = type | (incomplete ? CUBE_INCOMPLETE : 0u) | (chunk << CUBE_CHUNK_SHIFT);
    if (incomplete) atomicOr(retypeMask[id / 32u], 1u << (id % 32u));
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < counters.cubesChanged) {
        uvec2 cube = changedCube(i);
        retype(cube.x, cube.y);
    }
    ADD_COUNTER(trianglesCreated, created);
    ADD_COUNTER(trianglesReleased, released);
    ADD_COUNTER(trianglesInvalid, invalid);
    ADD_COUNTER(cubesRetyped, retyped);
}
