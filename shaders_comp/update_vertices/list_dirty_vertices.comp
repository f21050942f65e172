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
    bool hasX = vx < CLAIMED_SLOT, hasY = vy < CLAIMED_SLOT, hasZ = vz < CLAIMED_SLOT;
    uint at = reserveMovedVertices(uint(hasX) + uint(hasY) + uint(hasZ));   // one reservation for the cube's 3 edges
    if (hasX) listMovedVertex(at++, vx);
    if (hasY) listMovedVertex(at++, vy);
    if (hasZ) listMovedVertex(at, vz);
}
