#version 460
// Hash rebuild, pass 1 (docs/MESH.md, "Recycling blocks"): one invocation per live block (collect_blocks).
// The block's hash stamp (the last frame that touched it, which starvation reads) is kept in its
// coordinate's w, which held the slot: the table is cleared next and the block gets a new slot.
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counters.liveBlockCount) return;
    uint block = blockList[i];
    blockCoords[block].w = int(hashStamps[uint(blockCoords[block].w)]);
}
