#version 460
// Incremental mesh, after mark_dirty, only in the frame after a heap growth (GpuVolume::growMeshHeaps), and
// in the next ones while that retry overflows the retype list: every live block (collect_blocks) that still
// has retype bits set (INCOMPLETE cubes waiting for heap room, or cubes deferred by a full retype list)
// becomes dirty, so those cubes are rebuilt now instead of whenever the camera next touches their block.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counters.liveBlockCount || frameSkipped()) return;
    uint b = blockList[i];
    uint pending = 0u;
    for (uint w = 0u; w < MASK_WORDS; ++w) pending |= retypeMask[b * MASK_WORDS + w];
    if (pending == 0u) return;
    markBlockDirty(b, MESH_STAMP_DIRTY);   // its corners did not change: only the waiting cubes are rebuilt
}
