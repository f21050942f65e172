#version 460
// Incremental mesh, pass 2 (paper §V.B), the variant for small maps: every live vertex whose owner block
// is dirty this frame, or that was created this frame, is moved (vertex_update.glsl). One invocation per
// heap entry below the high water (the heap is popped lowest index first, so every live vertex is there).
// commit_vertices runs this or update_vertices + update_new_vertices, whichever visits fewer entries.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"
#include "structure/cube_access.glsl"
#include "update_vertices/vertex_update.glsl"

layout(local_size_x = WG_LIST) in;


void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= counters.vertexHighWater || vertices[v].refcount == DEAD_REFCOUNT) return;
    uint owner = vertexOwner[v];
    uint block = owner / (VOXELS_PER_BLOCK * 3u);
    if (meshStamps[block] != frame.frameNumber && vertices[v].createdFrame != frame.frameNumber) return;
    CubeRef r = cubeRef(block, (owner / 3u) % VOXELS_PER_BLOCK);
    float d[8];
    bool present[8];
    bool observed;
    loadCube(r, d, present, observed);
    moveVertex(v, r, owner % 3u, d, present);
}
