#version 460
// Incremental mesh, pass 2 (paper §V.B): every cube of a dirty block (one invocation per cube) moves the
// vertices on its owned edges, whose corners may have new values. The work is proportional to the
// frame's dirty blocks, not to the size of the map. (Vertices created this frame whose owner block is
// not dirty are moved by update_new_vertices.)
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"
#include "structure/cube_access.glsl"
#include "update_vertices/vertex_update.glsl"

layout(local_size_x = WG_BLOCK) in;


void main() {
    const uint groupsPerBlock = VOXELS_PER_BLOCK / WG_BLOCK;
    uint block = dirtyList[gl_WorkGroupID.x / groupsPerBlock];
    uint local = (gl_WorkGroupID.x % groupsPerBlock) * WG_BLOCK + gl_LocalInvocationIndex;
    uint cube = block * VOXELS_PER_BLOCK + local;
    uint vx = edgeVertexX[cube], vy = edgeVertexY[cube], vz = edgeVertexZ[cube];
    if (vx >= CLAIMED_SLOT && vy >= CLAIMED_SLOT && vz >= CLAIMED_SLOT) return;   // owns no vertex
    CubeRef r = cubeRef(block, local);
    float d[8];
    bool present[8];
    bool observed;
    loadCube(r, d, present, observed);
    if (vx < CLAIMED_SLOT) moveVertex(vx, r, 0u, d, present);
    if (vy < CLAIMED_SLOT) moveVertex(vy, r, 1u, d, present);
    if (vz < CLAIMED_SLOT) moveVertex(vz, r, 2u, d, present);
}
