// Component: the per-frame lists (src/gpu/frame_lists.h), what one pass hands the next: the blocks a frame
// touched, the live-block list of whole-volume passes, the dirty blocks (deduplicated with per-block mesh
// stamps), the retype masks and list of cubes to re-mesh, the vertices that may have lost their last
// triangle (GC candidates) and the chunks released this frame, the vertices to move this mesh pass (their edge slots), and
// the dirty blocks' neighbour blocks, and with refinement each corner's sign for meshing. Their lengths are in
// Counters.
#ifndef VKMESH_FRAME_LISTS_GLSL
#define VKMESH_FRAME_LISTS_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_TOUCHED) buffer Touched { uint touched[]; };
layout(std430, set = 0, binding = BINDING_BLOCK_LIST) buffer BlockList { uint blockList[]; };
layout(std430, set = 0, binding = BINDING_MESH_STAMPS) coherent buffer MeshStamps { uint meshStamps[]; };
layout(std430, set = 0, binding = BINDING_DIRTY_LIST) buffer DirtyList { uint dirtyList[]; };
layout(std430, set = 0, binding = BINDING_RETYPE_MASK) coherent buffer RetypeMask { uint retypeMask[]; };
layout(std430, set = 0, binding = BINDING_RETYPE_LIST) buffer RetypeList { uint retypeList[]; };
layout(std430, set = 0, binding = BINDING_GARBAGE) buffer Garbage { uint garbage[]; };
layout(std430, set = 0, binding = BINDING_MOVED_VERTICES) buffer MovedVertices { uint movedVertices[]; };
// Per block, NEIGHBORS_PER_BLOCK entries: the block index at each offset in {-1, 0, 1}^3 from it (NO_BLOCK when
// not allocated), written by cache_neighbors for every dirty block, and so valid for a block whose mesh stamp
// is this frame's number (the hash does not change during the mesh passes). The mesh passes read a cube's
// neighbour blocks here instead of probing the hash up to 7 times per cube (26 with refinement; cubeRef,
// cube_access.glsl), and their pipelines need no hash buffers.
layout(std430, set = 0, binding = BINDING_BLOCK_NEIGHBORS) buffer BlockNeighbors { uint blockNeighbors[]; };

// With refinement (docs/REFINEMENT.md), per block MESH_SIGN_WORDS words. The first MASK_WORDS: bit `local` set
// when the corner is inside for meshing; decide_mesh_signs keeps them (for the corners whose sign may have
// changed, before the retype list is collected), claim and triangulate type a cube from its 8 corners' bits.
// Persistent: a corner's bit only changes when the TSDF within one corner of it does. The next MASK_WORDS: the
// corners whose |d| < epsilon changed in fusion (so their sign may have changed), which list_sign_corners
// lists and clears.
layout(std430, set = 0, binding = BINDING_MESH_SIGNS) coherent buffer MeshSigns { uint meshSigns[]; };

uint meshSignWord(uint block, uint local) { return block * MESH_SIGN_WORDS + local / 32u; }
uint nearChangeWord(uint block, uint local) { return block * MESH_SIGN_WORDS + MASK_WORDS + local / 32u; }

bool meshSignInside(uint block, uint local) { return ((meshSigns[meshSignWord(block, local)] >> (local % 32u)) & 1u) != 0u; }

uint neighborIndex(ivec3 offset) { return uint((offset.x + 1) + 3 * (offset.y + 1) + 9 * (offset.z + 1)); }
uint cachedNeighbor(uint block, ivec3 offset) { return blockNeighbors[block * NEIGHBORS_PER_BLOCK + neighborIndex(offset)]; }

// The two garbage lists (shared_layout.h, BINDING_GARBAGE).
uint gcCandidate(uint i) { return garbage[i]; }
void setGcCandidate(uint i, uint v) { garbage[i] = v; }
uint releasedChunk(uint i) { return garbage[params.vertexCapacity + i]; }
void setReleasedChunk(uint i, uint chunk) { garbage[params.vertexCapacity + i] = chunk; }

// Reserves `count` entries of the moved-vertex list for this invocation, one atomic per subgroup; returns
// the first. Called by every invocation of the subgroup (uniform control flow), with a count or 0. Entries
// at or past params.vertexCapacity do not exist (never more: each vertex is listed once).
uint reserveMovedVertices(uint count) {
    uint offset = subgroupExclusiveAdd(count);
    uint total = subgroupAdd(count);
    uint base = 0u;
    if (subgroupElect() && total != 0u) base = atomicAdd(counters.movedCount, total);
    return subgroupBroadcastFirst(base) + offset;
}

// `slot`: the edge slot holding the vertex (move_vertices reads the vertex there).
void listMovedVertex(uint at, uint slot) {
    if (at < params.vertexCapacity) movedVertices[at] = slot;
}
#endif
