// Component: the frame's deferral (docs/MESH.md, "Deferral"). Called by the last allocation pass
// (commit_allocation, one invocation, after it has counted what the pool could not serve; it was a pass of its own
// until 2026-12-05, whose dispatch and barrier cost more than its few loads): if the frame overflowed a capacity (a
// key found no hash slot, a block got no pool memory, the touched list was too short) and
// VolumeParamsGpu::deferOnOverflow is set, the frame is deferred: fusion and dirty marking get empty dispatches, and
// so do the whole-volume passes (plan_block_list) and the delta passes (plan_deltas). What the allocation did is
// kept (keys inserted, blocks handed out: free blocks are all zero, so a block fused later without its FRESH flag
// starts from nothing just the same). The host grows what overflowed and runs the frame again under a new frame
// number (hash stamps of this attempt would hide its blocks from the touched list).
#ifndef VKMESH_DEFER_FRAME_GLSL
#define VKMESH_DEFER_FRAME_GLSL
#include "structure/frame.glsl"

void deferFrameOnOverflow() {
    // Both flags are per-frame counters, cleared at the start of every frame.
    bool overflow = counters.poolExhausted != 0u || counters.hashFull != 0u || counters.touchedCount > params.touchedCapacity;
    if (params.deferOnOverflow == 0u || !overflow) return;
    counters.frameDeferred = 1u;
    counters.blockDispatch[0] = 0u;    // fuse_depth
    counters.touchedListDispatch[0] = 0u;   // mark_dirty (assign_blocks already ran)
}
#endif
