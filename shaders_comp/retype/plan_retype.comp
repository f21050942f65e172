#version 460
// One invocation after collect_retype: one invocation per listed cube for claim and triangulate.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    uint n = min(counters.retypeCount, params.retypeCapacity);
    counters.retypeDispatch[0] = (n + WG_LIST - 1u) / WG_LIST;
    counters.retypeDispatch[1] = 1u;
    counters.retypeDispatch[2] = 1u;
}
