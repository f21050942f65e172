#version 460
// Mesh deltas, vertices: every heap entry is compared with its shadow (the vertex as last reported).
// A vertex is alive while triangles use it (refcount > 0, not DEAD), the same test the export makes.
//   dead -> alive, or alive with another creation frame (freed and reused): ADDED
//   alive -> alive, position or normal bits differ: CHANGED;  alive -> dead: REMOVED.
// The shadow is updated only for listed entries, so a record that did not fit is found again when the
// host re-runs the pass with a larger list: nothing is lost.
#extension GL_GOOGLE_include_directive : require
#include "delta_common.glsl"

layout(local_size_x = WG_LIST) in;

bool alive(Vertex v) { return v.refcount != DEAD_REFCOUNT && v.refcount != 0u; }

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= deltaState.vertexScan) return;
    Vertex now = vertices[v];
    Vertex before = prevVertices[v];
    bool isAlive = alive(now), wasAlive = alive(before);
    uint kind = DELTA_NONE;
    if (isAlive && (!wasAlive || now.createdFrame != before.createdFrame)) {
        kind = DELTA_ADDED;
    } else if (!isAlive && wasAlive) {
        kind = DELTA_REMOVED;
    } else if (isAlive) {
        uvec3 p0 = floatBitsToUint(vec3(now.px, now.py, now.pz)), p1 = floatBitsToUint(vec3(before.px, before.py, before.pz));
        uvec3 n0 = floatBitsToUint(vec3(now.nx, now.ny, now.nz)), n1 = floatBitsToUint(vec3(before.nx, before.ny, before.nz));
        if (any(notEqual(p0, p1)) || any(notEqual(n0, n1)) || now.color != before.color) kind = DELTA_CHANGED;
    }
    if (kind == DELTA_NONE) return;
    uint at = atomicAdd(deltaState.vertexRecords, 1u);
    if (at >= deltaState.vertexRecordCapacity) return;
    DeltaVertexRecord r;
    r.idKind = v | (kind << DELTA_KIND_SHIFT);
    r.px = now.px; r.py = now.py; r.pz = now.pz;
    r.nx = now.nx; r.ny = now.ny; r.nz = now.nz;
    r.createdFrame = now.createdFrame;
    r.color = now.color;
    vertexRecords[at] = r;
    prevVertices[v] = now;
}
