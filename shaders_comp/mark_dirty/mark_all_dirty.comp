#version 460
// Marks every live block dirty (a from-scratch extraction, or the first frame after loading). Runs over
// the live block list written by collect_blocks.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counters.liveBlockCount) return;
    uint b = blockList[i];
    meshStamps[b] = 4u * frame.frameNumber + MESH_STAMP_MOVES;   // (markBlockDirty)
    listDirtyBlock(b);
}
