#version 460
// Export, pass 1: compaction of the vertex heap. Every vertex with triangles gets a dense index (one
// atomic per subgroup), is copied to the export buffer and remembers its new index for pass 2.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "export/export_buffers.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint v = gl_GlobalInvocationID.x;
    bool live = false, unreferenced = false;
    if (v < min(counters.vertexHighWater, params.vertexCapacity)) {
        uint refs = vertices[v].refcount;
        live = refs != DEAD_REFCOUNT && refs > 0u;
        unreferenced = refs == 0u;
    }
    uint offset = subgroupExclusiveAdd(live ? 1u : 0u);
    uint total = subgroupAdd(live ? 1u : 0u);
    uint base = 0u;
    if (subgroupElect() && total != 0u) base = atomicAdd(counters.exportVertices, total);
    base = subgroupBroadcastFirst(base) + offset;
    if (live) {
        vertexRemap[v] = base;
        // Counted either way: the host grows the buffer and re-runs when exportVertices > capacity.
        if (base < params.exportVertexCapacity) exportVertices[base] = vertices[v];
    }
    ADD_COUNTER(exportUnreferenced, unreferenced ? 1u : 0u);
}
