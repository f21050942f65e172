#version 460
// After the mesh passes of a frame that de-integrates (framePose.deintegrate; docs/CORRECTION.md): one workgroup
// per touched block. A block the de-integration left with no observation is freed with the mesh state the
// passes released (free_block.glsl); commit_recycle follows, as after recycle_free.
#extension GL_GOOGLE_include_directive : require
#include "recycle/free_block.glsl"

layout(local_size_x = WG_BLOCK) in;

void main() {
    uint entry = touched[gl_WorkGroupID.x];   // the same for the whole workgroup
    if (entry == NO_BLOCK || framePose.deintegrate == 0u) return;
    freeBlockIfEmpty(entry & INDEX_MASK);
}
