#version 460
// One invocation after export_triangles: the compacted mesh's VkDrawIndexedIndirectCommand, so that a
// renderer can draw it without the host reading a count. Nothing is drawn when an export buffer was too
// small (the host then grows it and re-runs the export before it hands the buffers out).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "export/export_buffers.glsl"

layout(local_size_x = 1) in;

void main() {
    bool fits = counters.exportVertices <= params.exportVertexCapacity &&
                counters.exportTriangles <= params.exportTriangleCapacity;
    counters.drawIndexed[0] = fits ? 3u * counters.exportTriangles : 0u;   // indexCount
    counters.drawIndexed[1] = 1u;                                         // instanceCount
    counters.drawIndexed[2] = 0u;                                         // firstIndex
    counters.drawIndexed[3] = 0u;                                         // vertexOffset
    counters.drawIndexed[4] = 0u;                                         // firstInstance
}
