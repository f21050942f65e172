// Component: the cube mesh (src/gpu/cube_mesh.h), the paper's persistent shared-vertex mesh (docs/MESH.md):
// per cube its MC type and triangle chunk, per cube and axis the vertex on the edge it owns; the vertex heap
// with owners and a free stack; the triangle chunks (5 triangles each) with a free stack; per block, a bit
// mask of the edge slots that hold a vertex (the owned-slot mask).
#ifndef VKMESH_CUBE_MESH_GLSL
#define VKMESH_CUBE_MESH_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_CUBE_STATE) buffer CubeState { uint cubeState[]; };
layout(std430, set = 0, binding = BINDING_EDGE_VERTEX_X) coherent buffer EdgeVertexX { uint edgeVertexX[]; };
layout(std430, set = 0, binding = BINDING_EDGE_VERTEX_Y) coherent buffer EdgeVertexY { uint edgeVertexY[]; };
layout(std430, set = 0, binding = BINDING_EDGE_VERTEX_Z) coherent buffer EdgeVertexZ { uint edgeVertexZ[]; };
layout(std430, set = 0, binding = BINDING_VERTICES) coherent buffer Vertices { Vertex vertices[]; };
layout(std430, set = 0, binding = BINDING_VERTEX_OWNER) buffer VertexOwner { uint vertexOwner[]; };
layout(std430, set = 0, binding = BINDING_VERTEX_FREE) buffer VertexFree { uint vertexFree[]; };
layout(std430, set = 0, binding = BINDING_CHUNK_TRIANGLES) buffer ChunkTriangles { uint chunkTriangles[]; };
layout(std430, set = 0, binding = BINDING_CHUNK_FREE) buffer ChunkFree { uint chunkFree[]; };
// Per block OWNED_SLOT_WORDS words, MASK_WORDS per axis: bit `cube % 32` of word `axis * MASK_WORDS + cube / 32`
// is set iff the cube's slot along `axis` holds a vertex (not EMPTY). Claim sets the bit when it stores a
// vertex in an empty slot, GC clears it when it empties the slot; a reset, a growth or a map load rebuilds it
// from the slots (src/gpu/structure/cube_mesh.cpp). list_moved_vertices visits only the set bits.
layout(std430, set = 0, binding = BINDING_OWNED_SLOTS) coherent buffer OwnedSlots { uint ownedSlots[]; };

// ---- edge-vertex slots ---------------------------------------------------------------------------
// A slot is (block * 512 + cube) * 3 + axis (the owner cube's edge along that axis); the three axes live in
// three arrays.
uint edgeLoad(uint slot) {
    uint c = slot / 3u, a = slot % 3u;
    return a == 0u ? edgeVertexX[c] : (a == 1u ? edgeVertexY[c] : edgeVertexZ[c]);
}
void edgeStore(uint slot, uint v) {
    uint c = slot / 3u, a = slot % 3u;
    if (a == 0u) edgeVertexX[c] = v; else if (a == 1u) edgeVertexY[c] = v; else edgeVertexZ[c] = v;
}
void edgeStoreAtomic(uint slot, uint v) {
    uint c = slot / 3u, a = slot % 3u;
    if (a == 0u) atomicExchange(edgeVertexX[c], v); else if (a == 1u) atomicExchange(edgeVertexY[c], v); else atomicExchange(edgeVertexZ[c], v);
}
uint edgeCompSwap(uint slot, uint expected, uint v) {
    uint c = slot / 3u, a = slot % 3u;
    if (a == 0u) return atomicCompSwap(edgeVertexX[c], expected, v);
    if (a == 1u) return atomicCompSwap(edgeVertexY[c], expected, v);
    return atomicCompSwap(edgeVertexZ[c], expected, v);
}

// ---- owned-slot masks -------------------------------------------------------------------------------
uint ownedSlotWord(uint slot) {
    uint c = slot / 3u, a = slot % 3u;
    return (c / VOXELS_PER_BLOCK) * OWNED_SLOT_WORDS + a * MASK_WORDS + (c % VOXELS_PER_BLOCK) / 32u;
}
uint ownedSlotBit(uint slot) { return 1u << ((slot / 3u) % 32u); }   // block * 512 is a multiple of 32
void markSlotOwned(uint slot) { atomicOr(ownedSlots[ownedSlotWord(slot)], ownedSlotBit(slot)); }
void markSlotEmpty(uint slot) { atomicAnd(ownedSlots[ownedSlotWord(slot)], ~ownedSlotBit(slot)); }
#endif
