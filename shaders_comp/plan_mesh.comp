#version 460
// One invocation: one workgroup per dirty block for the meshing passes.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = 1) in;

void main() {
    counters.dirtyDispatch[0] = counters.dirtyCount;
    counters.dirtyDispatch[1] = 1u;
    counters.dirtyDispatch[2] = 1u;
}
