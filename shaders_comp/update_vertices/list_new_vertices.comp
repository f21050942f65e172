#version 460
// Incremental mesh, pass 2b: a cube of a dirty block can claim an edge whose owner cube lies in a block
// that is not dirty; list_dirty_vertices does not visit that owner, so the vertices created this frame (the
// GC candidates so far) are listed here unless their owner block is dirty.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/cube_mesh.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    bool listed = false;
    uint v = 0u;
    if (i < min(counters.candidateCount, params.vertexCapacity)) {
        v = gcCandidate(i);
        listed = meshStamps[vertexOwner[v] / (VOXELS_PER_BLOCK * 3u)] != frame.frameNumber;   // else list_dirty_vertices has it
    }
    uint at = reserveMovedVertices(listed ? 1u : 0u);
    if (listed) listMovedVertex(at, v);
}
