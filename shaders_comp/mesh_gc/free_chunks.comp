#version 460
// Pushes the triangle chunks released by mesh_triangulate back on their free stack.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(counters.releaseCount, params.chunkCapacity)) return;
    chunkFree[counters.chunkFreeTop + atomicAdd(counters.chunkPushes, 1u)] = releasedChunk(i);
}
