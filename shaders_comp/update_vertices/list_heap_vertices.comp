#version 460
// Incremental mesh, pass 2 (paper §V.B), the variant for small maps: every live vertex whose owner block
// is dirty this frame, or that was created this frame, is listed for move_vertices. One invocation per
// heap entry below the high water (the heap is popped lowest index first, so every live vertex is there).
// commit_vertices runs this or list_dirty_vertices + list_new_vertices, whichever visits fewer entries.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint v = gl_GlobalInvocationID.x;
    bool listed = false;
    if (v < counters.vertexHighWater && vertices[v].refcount != DEAD_REFCOUNT) {
        uint block = vertexOwner[v] / (VOXELS_PER_BLOCK * 3u);
        listed = meshStamps[block] == frame.frameNumber || vertices[v].createdFrame == frame.frameNumber;
    }
    uint at = reserveMovedVertices(listed ? 1u : 0u);
    if (listed) listMovedVertex(at, v);
}
