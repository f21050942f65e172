#version 460
// Test-only (tests/gpu/test_block_hash.cpp): the block hash alone, without a depth image, through the
// same functions the stages use (structure/block_hash.glsl). Entry i < frame.imageSize of the block
// coordinates buffer holds a key (xyz); many entries may hold the same key, so a dispatch has the
// contention of many pixels touching one block. MODE (specialization constant 0):
//   0 insert: hashInsertKey; touched[i] = slot (or NO_BLOCK). The invocation that inserted a key makes
//     entry i that key's block: hashValues = i, hashStamps = frameNumber + i, blockCoords[i].w = slot.
//     Counts blocksInserted, blocksFound, hashFull like allocate_blocks.
//   1 find: touched[i] = findSlot (NO_BLOCK when absent).
//   2 remove: entries that are blocks (w >= 0) with i % 3 == 0 remove their key (hashRemoveKey).
#extension GL_GOOGLE_include_directive : require
#include "structure/frame.glsl"
#include "structure/block_hash.glsl"
#include "structure/block_store.glsl"
#include "structure/frame_lists.glsl"

layout(local_size_x = WG_LIST) in;
layout(constant_id = 0) const uint MODE = 0u;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint found = 0u, inserted = 0u, full = 0u;
    if (i < frame.imageSize) {
        ivec3 c = blockCoords[i].xyz;
        if (MODE == 0u) {
            bool isNew;
            uint slot = hashInsertKey(c, isNew);
            touched[i] = slot;
            if (slot == NO_BLOCK) {
                full = 1u;
            } else if (isNew) {
                inserted = 1u;
                hashValues[slot] = i;
                hashStamps[slot] = frame.frameNumber + i;
                blockCoords[i].w = int(slot);
            } else {
                found = 1u;
            }
        } else if (MODE == 1u) {
            touched[i] = findSlot(c);
        } else if (blockCoords[i].w >= 0 && i % 3u == 0u) {
            hashRemoveKey(uint(blockCoords[i].w));
        }
    }
    ADD_COUNTER(blocksFound, found);
    ADD_COUNTER(blocksInserted, inserted);
    ADD_COUNTER(hashFull, full);
}
