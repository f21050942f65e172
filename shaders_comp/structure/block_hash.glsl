// Component: the block hash (src/gpu/block_hash.h). Block coordinate -> hash slot -> block index, with
// open addressing (linear probing) over a power-of-two table. Keys are claimed with compare-and-swap in
// allocate_blocks (and rehash_insert); everything else only reads them, in later dispatches. Shaders use
// the functions below and never the key words themselves: the key's layout depends on the device.
//
// Two layouts of the keys buffer, chosen from the device's features (docs/HASH.md):
//   default        one uint64 per slot, the packed key (shared_layout.h), claimed with one 64-bit CAS;
//   VKMESH_HASH32  HASH32_KEY_WORDS uints per slot (biased x, y, z), each claimed with its own 32-bit CAS
//                  in that order; no 64-bit type anywhere (Apple GPUs, many mobile GPUs).
// Both give every key exactly one slot, in one dispatch, without any invocation waiting for another.
#ifndef VKMESH_BLOCK_HASH_GLSL
#define VKMESH_BLOCK_HASH_GLSL
#include "structure/frame.glsl"

#ifdef VKMESH_HASH32
layout(std430, set = 0, binding = BINDING_HASH_KEYS) coherent buffer HashKeys { uint hashKeyWords[]; };
#else
layout(std430, set = 0, binding = BINDING_HASH_KEYS) coherent buffer HashKeys { uint64_t hashKeys[]; };
#endif
layout(std430, set = 0, binding = BINDING_HASH_VALUES) coherent buffer HashValues { uint hashValues[]; };
layout(std430, set = 0, binding = BINDING_HASH_STAMPS) coherent buffer HashStamps { uint hashStamps[]; };

bool blockCoordInRange(ivec3 c) {
    return all(greaterThanEqual(c, ivec3(-int(KEY_BIAS)))) && all(lessThan(c, ivec3(int(KEY_BIAS))));
}

// The spatial hash of Teschner et al. (the one voxel hashing uses); the same code is in src/cpu.
uint hashSlot(ivec3 c) {
    uint h = (uint(c.x) * 73856093u) ^ (uint(c.y) * 19349669u) ^ (uint(c.z) * 83492791u);
    return h & (params.hashCapacity - 1u);
}

uint nextSlot(uint slot) { return (slot + 1u) & (params.hashCapacity - 1u); }

#ifdef VKMESH_HASH32
// ---- 32-bit path -------------------------------------------------------------------------------
// Each key word is written at most once between two clears of the table (EMPTY -> coordinate, by CAS),
// so any value other than EMPTY that an invocation reads is final.
uvec3 keyWords(ivec3 c) { return uvec3(c + ivec3(int(KEY_BIAS))) & uvec3(KEY_AXIS_MASK); }

// Makes word `index` hold `part` if it is empty. Returns whether it holds `part` now (claimed by this
// invocation, `won`, or by another one earlier); false: it holds another key's word, final.
bool claimKeyWord(uint index, uint part, inout bool won) {
    uint v = hashKeyWords[index];
    won = false;
    if (v == HASH32_WORD_EMPTY) {
        v = atomicCompSwap(hashKeyWords[index], HASH32_WORD_EMPTY, part);
        if (v == HASH32_WORD_EMPTY) { won = true; return true; }
    }
    return v == part;
}

// Inserts c's key, or finds it. Per probed slot the x, y, z words are claimed in order; only invocations
// agreeing on the words before compete for the next one, so the slot ends up holding the full key of
// whoever claimed its z word, and every invocation of the same key reaches the same verdict on the slot
// (docs/HASH.md has the argument). Returns the slot, or NO_BLOCK when none fitted within HASH_MAX_PROBES;
// `inserted`: this invocation completed the key (exactly one per key and slot).
uint hashInsertKey(ivec3 c, out bool inserted) {
    uvec3 k = keyWords(c);
    uint slot = hashSlot(c);
    inserted = false;
    for (uint probe = 0u; probe < HASH_MAX_PROBES; ++probe) {
        uint base = slot * HASH32_KEY_WORDS;
        bool won = false;
        if (claimKeyWord(base, k.x, won) && claimKeyWord(base + 1u, k.y, won) && claimKeyWord(base + 2u, k.z, won)) {
            inserted = won;
            return slot;
        }
        slot = nextSlot(slot);
    }
    return NO_BLOCK;
}

// Read-only lookup, valid in any dispatch after the one that inserted the key. Returns the hash slot
// or NO_BLOCK when the key is absent.
uint findSlot(ivec3 c) {
    if (!blockCoordInRange(c)) return NO_BLOCK;
    uvec3 k = keyWords(c);
    uint slot = hashSlot(c);
    for (uint probe = 0u; probe < HASH_MAX_PROBES; ++probe) {
        uint base = slot * HASH32_KEY_WORDS;
        uint x = hashKeyWords[base];
        if (x == HASH32_WORD_EMPTY) return NO_BLOCK;
        if (x == k.x && hashKeyWords[base + 1u] == k.y && hashKeyWords[base + 2u] == k.z) return slot;
        slot = nextSlot(slot);
    }
    return NO_BLOCK;
}

// Whether the slot holds a key or a tombstone (not empty).
bool hashSlotUsed(uint slot) { return hashKeyWords[slot * HASH32_KEY_WORDS] != HASH32_WORD_EMPTY; }

// The block coordinate of the key in a slot that holds one.
ivec3 hashSlotCoord(uint slot) {
    uint base = slot * HASH32_KEY_WORDS;
    return ivec3(hashKeyWords[base], hashKeyWords[base + 1u], hashKeyWords[base + 2u]) - ivec3(int(KEY_BIAS));
}

// Removes the key of a slot (recycling), in a dispatch in which nothing is inserted.
void hashRemoveKey(uint slot) {
    hashKeyWords[slot * HASH32_KEY_WORDS] = HASH32_WORD_TOMBSTONE;
    hashValues[slot] = NO_BLOCK;
}

#else
// ---- 64-bit path -------------------------------------------------------------------------------
uint64_t packBlockKey(ivec3 c) {
    uvec3 u = uvec3(c + ivec3(int(KEY_BIAS))) & uvec3(KEY_AXIS_MASK);
    return uint64_t(u.x) | (uint64_t(u.y) << KEY_BITS) | (uint64_t(u.z) << (2u * KEY_BITS));
}

ivec3 unpackBlockKey(uint64_t key) {
    uvec3 u = uvec3(uint(key & uint64_t(KEY_AXIS_MASK)), uint((key >> KEY_BITS) & uint64_t(KEY_AXIS_MASK)),
                    uint((key >> (2u * KEY_BITS)) & uint64_t(KEY_AXIS_MASK)));
    return ivec3(u) - ivec3(int(KEY_BIAS));
}

// Inserts c's key, or finds it, with one compare-and-swap per probed slot. A slot that already holds the
// key needs no atomic (keys are never removed during an inserting dispatch, so a plain read equal to the
// key is final). Returns the slot, or NO_BLOCK when none was free within HASH_MAX_PROBES; `inserted`:
// this invocation's CAS put the key there.
uint hashInsertKey(ivec3 c, out bool inserted) {
    uint64_t key = packBlockKey(c);
    uint slot = hashSlot(c);
    inserted = false;
    // Fast path: nearly every visit finds its key already at its home slot.
    if (hashKeys[slot] == key) return slot;
    for (uint probe = 0u; probe < HASH_MAX_PROBES; ++probe) {
        uint64_t prev = atomicCompSwap(hashKeys[slot], KEY_EMPTY, key);
        if (prev == KEY_EMPTY) { inserted = true; return slot; }
        if (prev == key) return slot;
        slot = nextSlot(slot);
    }
    return NO_BLOCK;
}

uint findSlot(ivec3 c) {
    if (!blockCoordInRange(c)) return NO_BLOCK;
    uint64_t key = packBlockKey(c);
    uint slot = hashSlot(c);
    for (uint probe = 0u; probe < HASH_MAX_PROBES; ++probe) {
        uint64_t k = hashKeys[slot];
        if (k == key) return slot;
        if (k == KEY_EMPTY) return NO_BLOCK;
        slot = nextSlot(slot);
    }
    return NO_BLOCK;
}

bool hashSlotUsed(uint slot) { return hashKeys[slot] != KEY_EMPTY; }

ivec3 hashSlotCoord(uint slot) { return unpackBlockKey(hashKeys[slot]); }

void hashRemoveKey(uint slot) {
    hashKeys[slot] = KEY_TOMBSTONE;
    hashValues[slot] = NO_BLOCK;
}
#endif

// Block index of a block coordinate, or NO_BLOCK when it is not allocated.
uint findBlock(ivec3 c) {
    uint slot = findSlot(c);
    return slot == NO_BLOCK ? NO_BLOCK : hashValues[slot];
}
#endif
