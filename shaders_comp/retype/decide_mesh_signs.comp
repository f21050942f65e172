#version 460
// Incremental mesh with refinement (docs/REFINEMENT.md): re-decides the meshing sign of every corner that
// list_sign_corners listed, before the retype list is collected (decideMeshSign, mesh_signs.glsl). One
// invocation per listed corner, so that the corners near the surface, which read 27 corners each, keep every
// SIMD lane busy.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "retype/mesh_signs.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(counters.signCornerCount, params.retypeCapacity)) return;
    uint id = retypeList[i];
    decideMeshSign(id / VOXELS_PER_BLOCK, id % VOXELS_PER_BLOCK);
}
