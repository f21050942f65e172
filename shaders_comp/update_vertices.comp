#version 460
// Incremental mesh, pass 2 (paper §V.B): every live vertex whose owner block is dirty this frame (its
// edge's corners may have new values), or that was created this frame (its owner block may lie outside
// the dirty set), moves to the current zero crossing of its edge (extrapolated, within limits, on an edge
// that only a refined type uses); its normal is the owner cube's TSDF gradient.
// The heap is popped lowest index first, so every live vertex lies below the high water.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = WG_LIST) in;

#include "cube_access.glsl"

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= counters.vertexHighWater || vertices[v].refcount == DEAD_REFCOUNT) return;
    uint owner = vertexOwner[v];
    uint block = owner / (VOXELS_PER_BLOCK * 3u);
    if (meshStamps[block] != frame.frameNumber && vertices[v].createdFrame != frame.frameNumber) return;
    uint axis = owner % 3u;
    CubeRef r = cubeRef(block, (owner / 3u) % VOXELS_PER_BLOCK);
    float d[8];
    bool present[8];
    bool observed;
    loadCube(r, d, present, observed);
    uint hi = 1u << axis;
    // Also edges whose corners share a sign: refinement may use them (the position is then extrapolated).
    if (!present[0] || !present[hi] || d[0] == d[hi]) return;
    vec3 p = edgeVertexPosition(r, 0u, axis, d[0], d[hi]);
    vec3 n = vec3(0.0);
    n[axis] = d[hi] - d[0] >= 0.0 ? 1.0 : -1.0;   // fallback: along the edge, toward free space
    bool all8 = true;
    for (uint c = 0u; c < 8u; ++c) all8 = all8 && present[c];
    if (all8) {
        vec3 g = vec3(0.0);
        for (uint c = 0u; c < 8u; ++c) g += mix(vec3(-d[c]), vec3(d[c]), bvec3(cornerOffset(c)));
        if (dot(g, g) > 0.0) n = normalize(g);
    }
    vertices[v].px = p.x;
    vertices[v].py = p.y;
    vertices[v].pz = p.z;
    vertices[v].nx = n.x;
    vertices[v].ny = n.y;
    vertices[v].nz = n.z;
}
