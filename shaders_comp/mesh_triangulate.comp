#version 460
// Incremental mesh, pass 2 (paper §V.B, §V.D, §V.E): every cube of a dirty block
//  - moves the vertices on its 3 owned edges to the current zero crossing (normal from the TSDF gradient);
//  - keeps its triangles if its MC type did not change (temporal consistency);
//  - otherwise releases them (refcount - 1 on their vertices; a vertex reaching 0 becomes a GC candidate)
//    and builds the new type's triangles from the edge slots claimed in the previous pass (+1 each).
// Triangles live in a chunk of 5 per cube; a cube gaining triangles pops a chunk (committed next pass), a
// cube losing all of them lists its chunk for release (pushed back two passes later).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = WG_BLOCK) in;

#include "cube_access.glsl"

uint created = 0u, released = 0u, invalid = 0u, retyped = 0u;

void listCandidate(uint v) {
    uint c = atomicAdd(counters.candidateCount, 1u);
    if (c < params.vertexCapacity) gcCandidates[c] = v;
}

// Position and normal of the vertex on the owned edge along `axis` (docs/MESH.md, "Update").
void updateOwnedVertex(uvec3 cube, uint axis, float d[8], bool present[8]) {
    uint local = (cube.z * BLOCK_SIDE + cube.y) * BLOCK_SIDE + cube.x;
    uint v = edgeVertex[(neighbour[0] * VOXELS_PER_BLOCK + local) * 3u + axis];
    if (v >= CLAIMED_SLOT) return;
    uint hi = 1u << axis;
    if (!present[0] || !present[hi] || (d[0] < 0.0) == (d[hi] < 0.0)) return;
    vec3 p = edgeVertexPosition(cube, 0u, axis, d[0], d[hi]);
    vec3 fallback = vec3(0.0);
    fallback[axis] = d[hi] - d[0] >= 0.0 ? 1.0 : -1.0;
    vec3 n = fallback;
    bool all8 = true;
    for (uint c = 0u; c < 8u; ++c) all8 = all8 && present[c];
    if (all8) {
        vec3 g = vec3(0.0);
        for (uint c = 0u; c < 8u; ++c) {
            uvec3 o = cornerOffset(c);
            g += mix(vec3(-d[c]), vec3(d[c]), bvec3(o));
        }
        if (dot(g, g) > 0.0) n = normalize(g);
    }
    vertices[v].px = p.x;
    vertices[v].py = p.y;
    vertices[v].pz = p.z;
    vertices[v].nx = n.x;
    vertices[v].ny = n.y;
    vertices[v].nz = n.z;
}

void main() {
    uint block = dirtyList[gl_WorkGroupID.x];
    loadNeighbours(block);
    for (uint k = 0u; k < VOXELS_PER_INVOCATION; ++k) {
        uint local = gl_LocalInvocationIndex + k * WG_BLOCK;
        uvec3 cube = cubeOfLocal(local);
        float d[8];
        bool present[8];
        bool observed;
        uint type = loadCube(cube, d, present, observed);
        for (uint axis = 0u; axis < 3u; ++axis) updateOwnedVertex(cube, axis, d, present);

        uint cubeIndex = block * VOXELS_PER_BLOCK + local;
        uint state = cubeState[cubeIndex];
        uint oldType = state & CUBE_TYPE_MASK;
        if (type == oldType && (state & CUBE_INCOMPLETE) == 0u) continue;
        ++retyped;
        uint chunk = state >> CUBE_CHUNK_SHIFT;   // chunk index + 1, 0 = none

        // Release the old triangles.
        if (chunk != 0u) {
            uint base = (chunk - 1u) * CHUNK_WORDS;
            for (uint t = 0u; t < triangleCountOf(oldType); ++t) {
                if (chunkTriangles[base + 3u * t] == INVALID_INDEX) continue;
                for (uint j = 0u; j < 3u; ++j) {
                    uint v = chunkTriangles[base + 3u * t + j];
                    if (atomicAdd(vertices[v].refcount, 0xFFFFFFFFu) == 1u) listCandidate(v);
                }
                ++released;
            }
        }

        // Build the new ones.
        bool incomplete = false;
        uint count = triangleCountOf(type);
        if (count == 0u) {
            if (chunk != 0u) {
                uint r = atomicAdd(counters.releaseCount, 1u);
                if (r < params.chunkCapacity) chunkRelease[r] = chunk - 1u;
                chunk = 0u;
            }
        } else {
            if (chunk == 0u) {
                uint rank = atomicAdd(counters.chunkAllocRequests, 1u);
                if (rank < counters.chunkFreeTop) chunk = chunkFree[counters.chunkFreeTop - 1u - rank] + 1u;
            }
            if (chunk == 0u) {
                incomplete = true;       // no chunk: counted by commit_chunks, retried when next dirty
                invalid += count;
            } else {
                uint base = (chunk - 1u) * CHUNK_WORDS;
                for (uint t = 0u; t < count; ++t) {
                    uint tri[3];
                    bool ok = true;
                    for (uint j = 0u; j < 3u; ++j) {
                        uint slot = edgeSlot(cube, triangleEdge(type, 3u * t + j));
                        tri[j] = slot == NO_BLOCK ? EMPTY_SLOT : edgeVertex[slot];
                        ok = ok && tri[j] < CLAIMED_SLOT;
                    }
                    if (!ok) {
                        chunkTriangles[base + 3u * t] = INVALID_INDEX;
                        incomplete = true;
                        ++invalid;
                        continue;
                    }
                    for (uint j = 0u; j < 3u; ++j) {
                        chunkTriangles[base + 3u * t + j] = tri[j];
                        atomicAdd(vertices[tri[j]].refcount, 1u);
                    }
                    ++created;
                }
            }
        }
        cubeState[cubeIndex] = type | (incomplete ? CUBE_INCOMPLETE : 0u) | (chunk << CUBE_CHUNK_SHIFT);
    }
    ADD_COUNTER(trianglesCreated, created);
    ADD_COUNTER(trianglesReleased, released);
    ADD_COUNTER(trianglesInvalid, invalid);
    ADD_COUNTER(cubesRetyped, retyped);
}
