#version 460
// Incremental mesh, pass 2b: one invocation per listed edge slot (list_moved_vertices) moves its vertex to the zero
// crossing of its edge (vertex_update.glsl). Listing first and moving second keeps every SIMD lane of this,
// the expensive part, busy.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"
#include "structure/cube_access.glsl"
#include "update_vertices/vertex_update.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(counters.movedCount, params.vertexCapacity)) return;
    uint owner = movedVertices[i];   // the vertex's edge slot (list_moved_vertices)
    uint v = edgeLoad(owner);
    CubeRef r = cubeRefAnyBlock(owner / (VOXELS_PER_BLOCK * 3u), (owner / 3u) % VOXELS_PER_BLOCK);
    float d[8];
    bool present[8];
    bool observed;
    loadCube(r, d, present, observed);
    moveVertex(v, r, owner % 3u, d, present);
}
