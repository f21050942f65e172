// Component: the block hash (src/gpu/block_hash.h). Block coordinate -> hash slot -> block index, with
// open addressing (linear probing) over a power-of-two table. Keys are claimed with one atomicCompSwap in
// allocate_blocks; everything else only reads them, in later dispatches.
#ifndef VKMESH_BLOCK_HASH_GLSL
#define VKMESH_BLOCK_HASH_GLSL
#include "structure/frame.glsl"

layout(std430, set = 0, binding = BINDING_HASH_KEYS) coherent buffer HashKeys { uint64_t hashKeys[]; };
layout(std430, set = 0, binding = BINDING_HASH_VALUES) coherent buffer HashValues { uint hashValues[]; };
layout(std430, set = 0, binding = BINDING_HASH_STAMPS) coherent buffer HashStamps { uint hashStamps[]; };

bool blockCoordInRange(ivec3 c) {
    return all(greaterThanEqual(c, ivec3(-int(KEY_BIAS)))) && all(lessThan(c, ivec3(int(KEY_BIAS))));
}

uint64_t packBlockKey(ivec3 c) {
    uvec3 u = uvec3(c + ivec3(int(KEY_BIAS))) & uvec3(KEY_AXIS_MASK);
    return uint64_t(u.x) | (uint64_t(u.y) << KEY_BITS) | (uint64_t(u.z) << (2u * KEY_BITS));
}

ivec3 unpackBlockKey(uint64_t key) {
    uvec3 u = uvec3(uint(key & uint64_t(KEY_AXIS_MASK)), uint((key >> KEY_BITS) & uint64_t(KEY_AXIS_MASK)),
                    uint((key >> (2u * KEY_BITS)) & uint64_t(KEY_AXIS_MASK)));
    return ivec3(u) - ivec3(int(KEY_BIAS));
}

// The spatial hash of Teschner et al. (the one voxel hashing uses); the same code is in src/cpu.
uint hashSlot(ivec3 c) {
    uint h = (uint(c.x) * 73856093u) ^ (uint(c.y) * 19349669u) ^ (uint(c.z) * 83492791u);
    return h & (params.hashCapacity - 1u);
}

// Read-only lookup, valid in any dispatch after the one that inserted the key. Returns the hash slot
// or NO_BLOCK when the key is absent.
uint findSlot(ivec3 c) {
    if (!blockCoordInRange(c)) return NO_BLOCK;
    uint64_t key = packBlockKey(c);
    uint slot = hashSlot(c);
    for (uint probe = 0u; probe < HASH_MAX_PROBES; ++probe) {
        uint64_t k = hashKeys[slot];
        if (k == key) return slot;
        if (k == KEY_EMPTY) return NO_BLOCK;
        slot = (slot + 1u) & (params.hashCapacity - 1u);
    }
    return NO_BLOCK;
}

// Block index of a block coordinate, or NO_BLOCK when it is not allocated.
uint findBlock(ivec3 c) {
    uint slot = findSlot(c);
    return slot == NO_BLOCK ? NO_BLOCK : hashValues[slot];
}
#endif
