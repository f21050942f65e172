#version 460
// One invocation after the listing (list_moved_vertices): sizes move_vertices' dispatch to the vertices listed,
// in Counters::vertexDispatch.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    uint listed = min(counters.movedCount, params.vertexCapacity);
    counters.vertexDispatch[0] = (listed + WG_LIST - 1u) / WG_LIST;
    counters.vertexDispatch[1] = 1u;
    counters.vertexDispatch[2] = 1u;
}
