// Moving a vertex to the current zero crossing of its edge (paper §V.B): the position interpolated along
// the edge (edgeCrossing: kept off the edge's ends in a refined volume), the normal from the owner cube's TSDF
// gradient, the colour interpolated between the edge's corners (voxel_color.glsl) when colour is fused.
// Includes cube_access.glsl.
#ifndef VKMESH_VERTEX_UPDATE_GLSL
#define VKMESH_VERTEX_UPDATE_GLSL
#include "structure/cube_access.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/voxel_color.glsl"

// r: the owner cube with its corners loaded into d/present; axis: which of its 3 edges.
void moveVertex(uint v, CubeRef r, uint axis, float d[8], bool present[8]) {
    uint hi = 1u << axis;
    // The far corner by selects, not d[hi]: a dynamically indexed local array is slow on llvmpipe (blockHolding).
    float dHi = axis == 0u ? d[1] : (axis == 1u ? d[2] : d[4]);
    bool presentHi = axis == 0u ? present[1] : (axis == 1u ? present[2] : present[4]);
    // Also edges whose corners share a sign: refinement may use them (the vertex then sits next to the flipped
    // corner, edgeCrossing). Every vertex gets a position, so a new one never keeps a stale one.
    if (!present[0] || !presentHi) return;
    float s = edgeCrossing(d[0], dHi, volumeRefines());
    vec3 p = edgeVertexPosition(r, 0u, axis, s);
    bvec3 along = equal(uvec3(axis), uvec3(0u, 1u, 2u));
    vec3 n = mix(vec3(0.0), vec3(dHi - d[0] >= 0.0 ? 1.0 : -1.0), along);   // fallback: along the edge, toward free space
    bool all8 = true;
    [[unroll]] for (uint c = 0u; c < 8u; ++c) all8 = all8 && present[c];
    if (all8) {
        vec3 g = vec3(0.0);
        [[unroll]] for (uint c = 0u; c < 8u; ++c) g += mix(vec3(-d[c]), vec3(d[c]), bvec3(cornerOffset(c)));
        if (dot(g, g) > 0.0) n = normalize(g);
    }
    vertices[v].px = p.x;
    vertices[v].py = p.y;
    vertices[v].pz = p.z;
    vertices[v].nx = n.x;
    vertices[v].ny = n.y;
    vertices[v].nz = n.z;
    if (volumeKeepsColor()) {
        uvec3 local;
        uint hiBlock = blockHolding(r, r.cube + cornerOffset(hi), local);
        uint lo = voxelColor[voxelIndex(r.nb[0], r.cube)], high = voxelColor[voxelIndex(hiBlock, local)];
        vertices[v].color = vertexColorOnEdge(lo, high, s);
    }
}
#endif
