#version 460
// One invocation, between allocate_blocks and assign_blocks: sizes the indirect dispatches over the
// touched list, whose length only the GPU knows.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    uint n = min(counters.touchedCount, params.touchedCapacity);
    counters.touchedListDispatch[0] = (n + WG_LIST - 1u) / WG_LIST;
    counters.touchedListDispatch[1] = 1u;
    counters.touchedListDispatch[2] = 1u;
    counters.blockDispatch[0] = n;
    counters.blockDispatch[1] = 1u;
    counters.blockDispatch[2] = 1u;
}
