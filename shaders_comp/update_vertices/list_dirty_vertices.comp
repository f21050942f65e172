#version 460
// Incremental mesh, pass 2a (paper §V.B), the variant for large maps: every cube of a dirty block (one
// invocation per cube) lists the vertices on its owned edges, whose corners may have new values, for
// move_vertices. The work is proportional to the frame's dirty blocks, not to the size of the map.
// (Vertices created this frame whose owner block is not dirty are listed by list_new_vertices.)
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_BLOCK) in;

void main() {
    const uint groupsPerBlock = VOXELS_PER_BLOCK / WG_BLOCK;
    uint block = dirtyList[gl_WorkGroupID.x / groupsPerBlock];
    uint local = (gl_WorkGroupID.x % groupsPerBlock) * WG_BLOCK + gl_LocalInvocationIndex;
    uint cube = block * VOXELS_PER_BLOCK + local;
    uint vx = edgeVertexX[cube], vy = edgeVertexY[cube], vz = edgeVertexZ[cube];
    listMovedVertex(vx, vx < CLAIMED_SLOT);
    listMovedVertex(vy, vy < CLAIMED_SLOT);
    listMovedVertex(vz, vz < CLAIMED_SLOT);
}
