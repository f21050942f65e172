#version 460
// One invocation after the allocation (commit_allocation): if the frame overflowed a capacity (a key found
// no hash slot, a block got no pool memory, the touched list was too short) and VolumeParamsGpu::
// deferOnOverflow is set, the frame is deferred: fusion and dirty marking get empty dispatches, and so do the
// whole-volume passes (plan_block_list) and the delta passes (plan_deltas). What the allocation did is kept
// (keys inserted, blocks handed out: free blocks are all zero, so a block fused later without its FRESH flag
// starts from nothing just the same). The host grows what overflowed and runs the frame again under a new
// frame number (hash stamps of this attempt would hide its blocks from the touched list).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"

layout(local_size_x = 1) in;

void main() {
    // Both flags are per-frame counters, cleared at the start of every frame.
    bool overflow = counters.poolExhausted != 0u || counters.hashFull != 0u || counters.touchedCount > params.touchedCapacity;
    if (params.deferOnOverflow == 0u || !overflow) return;
    counters.frameDeferred = 1u;
    counters.blockDispatch[0] = 0u;    // fuse_depth
    counters.touchedListDispatch[0] = 0u;   // mark_dirty (assign_blocks already ran)
}
