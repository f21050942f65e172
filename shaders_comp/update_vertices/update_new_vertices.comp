#version 460
// Incremental mesh, pass 2b: a cube of a dirty block can claim an edge whose owner cube lies in a block
// that is not dirty; update_vertices does not visit that owner, so the vertices created this frame (the
// GC candidates so far) are moved here unless their owner block is dirty.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"
#include "structure/cube_access.glsl"
#include "update_vertices/vertex_update.glsl"

layout(local_size_x = WG_LIST) in;


void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(counters.candidateCount, params.vertexCapacity)) return;
    uint v = gcCandidate(i);
    uint owner = vertexOwner[v];
    uint block = owner / (VOXELS_PER_BLOCK * 3u);
    if (meshStamps[block] == frame.frameNumber) return;   // update_vertices moves it
    CubeRef r = cubeRef(block, (owner / 3u) % VOXELS_PER_BLOCK);
    float d[8];
    bool present[8];
    bool observed;
    loadCube(r, d, present, observed);
    moveVertex(v, r, owner % 3u, d, present);
}
