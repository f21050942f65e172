#version 460
// One invocation before the export: its two dispatches cover only the used parts of the heaps (vertices
// and triangle slots below their high-water marks; a free stack hands out low indices first, so no index
// at or above the high water was ever used), not their capacities.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    uint vertices = min(counters.vertexHighWater, params.vertexCapacity);
    uint slots = min(counters.chunkHighWater, params.chunkCapacity) * TRIANGLES_PER_CHUNK;
    counters.exportDispatch[0] = (vertices + WG_LIST - 1u) / WG_LIST;
    counters.exportDispatch[1] = 1u;
    counters.exportDispatch[2] = 1u;
    counters.exportTriangleDispatch[0] = (slots + WG_LIST - 1u) / WG_LIST;
    counters.exportTriangleDispatch[1] = 1u;
    counters.exportTriangleDispatch[2] = 1u;
}
