// What allocate_blocks and allocate_tiles share: claiming a block's key, listing the blocks touched this frame,
// and the per-invocation cache of the blocks visited last. Included after the layout and ALLOCATE_DIRECTION.
#ifndef VKMESH_BLOCK_VISITS_GLSL
#define VKMESH_BLOCK_VISITS_GLSL

uint requests = 0u, found = 0u, inserted = 0u, full = 0u, outOfRange = 0u, outsideRadius = 0u, repeated = 0u;

// Claims `cell`'s key without waiting on anyone (structure/block_hash.glsl). Returns the slot, or
// NO_BLOCK if none was free within the probe bound.
uint insertKey(ivec3 cell) {
    if (ALLOCATE_DIRECTION == FUSE_BY_FRAME ? framePose.deintegrate != 0u : ALLOCATE_DIRECTION == FUSE_DEINTEGRATE) {
        uint slot = findSlot(cell);
        if (slot != NO_BLOCK) ++found;
        return slot;
    }
    bool isNew;
    uint slot = hashInsertKey(cell, isNew);
    if (slot == NO_BLOCK) ++full;
    else if (isNew) ++inserted;
    else ++found;
    return slot;
}

void touchBlock(ivec3 cell) {
    uint slot = insertKey(cell);
    if (slot == NO_BLOCK) return;
    // The first invocation to stamp the slot with this frame's number lists it, so each block appears
    // once in the touched list however many pixels see it.
    if (hashStamps[slot] != frame.frameNumber &&
        atomicExchange(hashStamps[slot], frame.frameNumber) != frame.frameNumber) {
        uint at = atomicAdd(counters.touchedCount, 1u);
        if (at < params.touchedCapacity) {
            touched[at] = slot;
            // The dispatches over the touched list grow with it (from {0, 1, 1}: CounterBuffer::recordClearFrame),
            // so no one-invocation pass has to size them after this one: assign_blocks and mark_dirty, WG_LIST
            // entries per workgroup; fuse_depth, a workgroup per entry.
            atomicMax(counters.touchedListDispatch[0], at / WG_LIST + 1u);
            atomicMax(counters.blockDispatch[0], at + 1u);
        }
    }
}

// The blocks this invocation touched last, most recent first. Neighbouring pixels' bands cross mostly the same
// blocks, so one invocation walking a column of pixels finds most of its visits here and touches the hash (a
// scattered read costing ~6-8 ns on lavapipe, twice) only for the others. Eight named variables rather than an
// array: llvmpipe keeps an array indexed at run time in scratch memory. The first cell is one no band reaches.
ivec3 recent0 = ivec3(0x7FFFFFFF), recent1 = recent0, recent2 = recent0, recent3 = recent0,
      recent4 = recent0, recent5 = recent0, recent6 = recent0, recent7 = recent0;

void visitBlock(ivec3 cell) {
    ++requests;
    // Counted per visit, like the per-pixel reference: a block out of range or beyond the keep radius is never
    // looked up, so checking it again costs no scattered read.
    if (!blockCoordInRange(cell)) { ++outOfRange; return; }
    // Bounded maps: blocks beyond the keep radius are not allocated (the recycling passes free those
    // the camera has left behind), so the map stays a ball around the camera.
    if (blockOutsideKeepRadius(cell)) { ++outsideRadius; return; }
    if (cell == recent0 || cell == recent1 || cell == recent2 || cell == recent3 ||
        cell == recent4 || cell == recent5 || cell == recent6 || cell == recent7) {
        ++repeated;
        return;
    }
    recent7 = recent6; recent6 = recent5; recent5 = recent4; recent4 = recent3;
    recent3 = recent2; recent2 = recent1; recent1 = recent0; recent0 = cell;
    touchBlock(cell);
}

#endif
