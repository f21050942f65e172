#version 460
// Export, pass 2: every live triangle, with its vertices' dense indices, into one index buffer. One
// invocation per triangle slot of the chunks below their high water: a slot holds a triangle when its
// first index is valid (mesh_triangulate keeps released chunks and unused slots empty), so neither the
// cubes nor the hash need to be visited.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "export/export_buffers.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint slot = gl_GlobalInvocationID.x;
    bool live = false;
    uint base = 0u;
    if (slot < min(counters.chunkHighWater, params.chunkCapacity) * TRIANGLES_PER_CHUNK) {
        base = (slot / TRIANGLES_PER_CHUNK) * CHUNK_WORDS + 3u * (slot % TRIANGLES_PER_CHUNK);
        live = chunkTriangles[base] != INVALID_INDEX;
    }
    uint offset = subgroupExclusiveAdd(live ? 1u : 0u);
    uint total = subgroupAdd(live ? 1u : 0u);
    uint first = 0u;
    if (subgroupElect() && total != 0u) first = atomicAdd(counters.exportTriangles, total);
    uint at = subgroupBroadcastFirst(first) + offset;
    // Counted either way: the host grows the buffer and re-runs when exportTriangles > capacity.
    if (live && at < params.exportTriangleCapacity)
        for (uint j = 0u; j < 3u; ++j) exportIndices[3u * at + j] = vertexRemap[chunkTriangles[base + j]];
}
