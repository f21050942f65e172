// The CPU reference of the GPU's spatial block hash (docs/MESH.md): block keys (structure/block_hash.glsl packBlockKey),
// the spatial hash of Teschner et al. (hashSlot), insertion with linear probing (allocate_blocks.comp
// insertKey), read-only lookup (findSlot), removal by tombstone (recycle_free.comp) and the rebuild that
// drops tombstones (rehash_save / rehash_insert / commit_rehash.comp), serially. Slots hold a key
// (KEY_EMPTY, KEY_TOMBSTONE or a packed coordinate), a value (block index or NO_BLOCK) and a stamp (the
// frame number that last touched the slot).
//
// Concurrent GPU insertions of colliding keys may end in other slots than the serial order gives; what both
// agree on is which keys the table holds, what each maps to, and that every key lies within HASH_MAX_PROBES
// of its home slot with no EMPTY slot in between (checkInvariants()).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cpu/reference_block.h"

namespace vkmesh::cpu {

// Whether a block coordinate has a key: every axis in [-KEY_BIAS, KEY_BIAS).
bool blockCoordInRange(const BlockCoord& c);
// KEY_BITS per axis, biased by KEY_BIAS; bit 63 is never set. Throws Error for a coordinate out of range.
uint64_t packBlockKey(const BlockCoord& c);
BlockCoord unpackBlockKey(uint64_t key);
// The home slot of a block in a table of `capacity` slots (a power of two).
uint32_t hashHomeSlot(const BlockCoord& c, uint32_t capacity);

enum class HashInsert {
    Found,       // the key was already in the table (Counters::blocksFound)
    Inserted,    // it took the first EMPTY slot of its probe sequence (blocksInserted)
    Full,        // no EMPTY slot within HASH_MAX_PROBES (hashFull); slot = NO_BLOCK
    OutOfRange,  // the coordinate has no key (outOfRange); slot = NO_BLOCK
};
struct HashInsertResult {
    HashInsert outcome;
    uint32_t slot;
};

class ReferenceHash {
public:
    // Throws Error unless capacity is a power of two (the probe sequence wraps with a mask).
    explicit ReferenceHash(uint32_t capacity);

    uint32_t capacity() const { return uint32_t(keys_.size()); }

    // insertKey of allocate_blocks.comp: probes from the home slot; a tombstone is never reused (a key's
    // probe sequence must not change under a concurrent lookup), only an EMPTY slot is claimed.
    HashInsertResult insert(const BlockCoord& c);
    // findSlot of structure/block_hash.glsl: the slot holding the key, or NO_BLOCK (probes past tombstones, stops at
    // EMPTY or after HASH_MAX_PROBES).
    uint32_t find(const BlockCoord& c) const;
    // findBlock: the block index stored with the key, or NO_BLOCK.
    uint32_t findBlock(const BlockCoord& c) const;

    uint64_t key(uint32_t slot) const { return keys_.at(slot); }
    uint32_t value(uint32_t slot) const { return values_.at(slot); }
    uint32_t stamp(uint32_t slot) const { return stamps_.at(slot); }
    // The assign stage stores the block index; allocation stamps the slot with the frame number.
    void setValue(uint32_t slot, uint32_t block);
    void setStamp(uint32_t slot, uint32_t frameNumber);
    // recycle_free.comp: the key becomes KEY_TOMBSTONE and the value NO_BLOCK. Throws Error unless the slot
    // holds a key.
    void remove(uint32_t slot);

    uint32_t entries() const { return entries_; }        // Counters::hashEntries: slots holding a key
    uint32_t tombstones() const { return tombstones_; }  // Counters::hashTombstones

    // The hash rebuild into a table of newCapacity slots (the same capacity: dropping tombstones; a larger
    // one: growing). Only keys holding a block are kept, with their value and stamp, inserted in the order
    // of their block index; keys holding NO_BLOCK are dropped (they ask again when next touched). `lost`
    // counts the blocks that found no EMPTY slot within HASH_MAX_PROBES (Counters::rehashLost).
    struct Rebuilt;
    Rebuilt rebuilt(uint32_t newCapacity) const;

    // Violated invariants, empty when all hold: entry and tombstone counts match the slots; every key is
    // in range, appears once, lies within HASH_MAX_PROBES of its home slot with no EMPTY slot between
    // (so find() reaches it); EMPTY and tombstone slots hold NO_BLOCK.
    std::vector<std::string> checkInvariants() const;

private:
    std::vector<uint64_t> keys_;
    std::vector<uint32_t> values_, stamps_;
    uint32_t entries_ = 0, tombstones_ = 0;
};

struct ReferenceHash::Rebuilt {
    ReferenceHash table;
    uint32_t lost = 0;
};

}  // namespace vkmesh::cpu
