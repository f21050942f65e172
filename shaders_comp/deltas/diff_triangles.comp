#version 460
// Mesh deltas, triangles: every triangle slot of every chunk ever used is compared with its shadow. A
// slot holds a triangle when its first index is not INVALID (mesh_triangulate keeps released chunks and
// unused slots INVALID). New content in a slot is ADDED (it replaces what a viewer held under that id);
// a slot that emptied is REMOVED. Same overflow rule as diff_vertices.
#extension GL_GOOGLE_include_directive : require
#include "delta_common.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint slot = gl_GlobalInvocationID.x;
    if (slot >= deltaState.triangleScan) return;
    uint base = (slot / TRIANGLES_PER_CHUNK) * CHUNK_WORDS + 3u * (slot % TRIANGLES_PER_CHUNK);
    uvec3 now = uvec3(chunkTriangles[base], chunkTriangles[base + 1u], chunkTriangles[base + 2u]);
    uvec3 before = uvec3(prevChunkTriangles[base], prevChunkTriangles[base + 1u], prevChunkTriangles[base + 2u]);
    bool has = now.x != INVALID_INDEX, had = before.x != INVALID_INDEX;
    uint kind = DELTA_NONE;
    if (has && (!had || any(notEqual(now, before)))) kind = DELTA_ADDED;
    else if (!has && had) kind = DELTA_REMOVED;
    if (kind == DELTA_NONE) return;
    uint at = atomicAdd(deltaState.triangleRecords, 1u);
    if (at >= deltaState.triangleRecordCapacity) return;
    DeltaTriangleRecord r;
    r.idKind = slot | (kind << DELTA_KIND_SHIFT);
    r.v0 = now.x; r.v1 = now.y; r.v2 = now.z;
    triangleRecords[at] = r;
    prevChunkTriangles[base] = now.x;
    prevChunkTriangles[base + 1u] = now.y;
    prevChunkTriangles[base + 2u] = now.z;
}
