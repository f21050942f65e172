#version 460
// Recycling, phase 2 (after the mesh passes and their garbage collection): one workgroup per live block. A
// retiring or starving block whose weights are all 0 is freed (free_block.glsl), else tried again next frame.
#extension GL_GOOGLE_include_directive : require
#include "recycle/recycle.glsl"
#include "recycle/free_block.glsl"

layout(local_size_x = WG_BLOCK) in;

void main() {
    uint block = blockList[gl_WorkGroupID.x];   // the same for the whole workgroup
    if (!blockRetires(block) && !blockStarves(block)) return;   // uniform over the workgroup
    freeBlockIfEmpty(block);
}
