#version 460
// One invocation after list_sign_corners: one invocation per listed corner for decide_mesh_signs (in
// vertexDispatch, which commit_vertices overwrites for the vertex update later in the pass).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    counters.vertexDispatch[0] = (min(counters.signCornerCount, params.retypeCapacity) + WG_LIST - 1u) / WG_LIST;
    counters.vertexDispatch[1] = 1u;
    counters.vertexDispatch[2] = 1u;
}
