#include "cpu/reference_hash.h"

#include <algorithm>
#include <set>

#include "core/types.h"

namespace vkmesh::cpu {

using gpu::HASH_MAX_PROBES;
using gpu::KEY_EMPTY;
using gpu::KEY_TOMBSTONE;
using gpu::NO_BLOCK;

bool blockCoordInRange(const BlockCoord& c) {
    const int bias = int(gpu::KEY_BIAS);
    return c[0] >= -bias && c[1] >= -bias && c[2] >= -bias && c[0] < bias && c[1] < bias && c[2] < bias;
}

uint64_t packBlockKey(const BlockCoord& c) {
    if (!blockCoordInRange(c))
        throw Error("block (" + std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]) +
                    ") is beyond the block key range of +-" + std::to_string(gpu::KEY_BIAS) + " blocks per axis");
    uint64_t key = 0;
    for (int k = 0; k < 3; ++k)
        key |= uint64_t(uint32_t(c[k] + int(gpu::KEY_BIAS)) & gpu::KEY_AXIS_MASK) << (uint32_t(k) * gpu::KEY_BITS);
    return key;
}

BlockCoord unpackBlockKey(uint64_t key) {
    BlockCoord c;
    for (int k = 0; k < 3; ++k)
        c[k] = int(uint32_t(key >> (uint32_t(k) * gpu::KEY_BITS)) & gpu::KEY_AXIS_MASK) - int(gpu::KEY_BIAS);
    return c;
}

uint32_t hashHomeSlot(const BlockCoord& c, uint32_t capacity) {
    const uint32_t h = (uint32_t(c[0]) * 73856093u) ^ (uint32_t(c[1]) * 19349669u) ^ (uint32_t(c[2]) * 83492791u);
    return h & (capacity - 1u);
}

ReferenceHash::ReferenceHash(uint32_t capacity) {
    if (capacity == 0 || (capacity & (capacity - 1u)) != 0)
        throw Error("hash capacity " + std::to_string(capacity) + " is not a power of two");
    keys_.assign(capacity, KEY_EMPTY);
    values_.assign(capacity, NO_BLOCK);
    stamps_.assign(capacity, 0u);
}

HashInsertResult ReferenceHash::insert(const BlockCoord& c) {
    if (!blockCoordInRange(c)) return {HashInsert::OutOfRange, NO_BLOCK};
    const uint64_t key = packBlockKey(c);
    const uint32_t mask = capacity() - 1u;
    uint32_t slot = hashHomeSlot(c, capacity());
    for (uint32_t probe = 0; probe < HASH_MAX_PROBES; ++probe) {
        if (keys_[slot] == key) return {HashInsert::Found, slot};
        if (keys_[slot] == KEY_EMPTY) {
            keys_[slot] = key;
            ++entries_;
            return {HashInsert::Inserted, slot};
        }
        slot = (slot + 1u) & mask;
    }
    return {HashInsert::Full, NO_BLOCK};
}

uint32_t ReferenceHash::find(const BlockCoord& c) const {
    if (!blockCoordInRange(c)) return NO_BLOCK;
    const uint64_t key = packBlockKey(c);
    const uint32_t mask = capacity() - 1u;
    uint32_t slot = hashHomeSlot(c, capacity());
    for (uint32_t probe = 0; probe < HASH_MAX_PROBES; ++probe) {
        if (keys_[slot] == key) return slot;
        if (keys_[slot] == KEY_EMPTY) return NO_BLOCK;
        slot = (slot + 1u) & mask;
    }
    return NO_BLOCK;
}

uint32_t ReferenceHash::findBlock(const BlockCoord& c) const {
    const uint32_t slot = find(c);
    return slot == NO_BLOCK ? NO_BLOCK : values_[slot];
}

void ReferenceHash::setValue(uint32_t slot, uint32_t block) {
    const uint64_t k = keys_.at(slot);
    if (k == KEY_EMPTY || k == KEY_TOMBSTONE) throw Error("hash slot " + std::to_string(slot) + " holds no key");
    values_[slot] = block;
}

void ReferenceHash::setStamp(uint32_t slot, uint32_t frameNumber) { stamps_.at(slot) = frameNumber; }

void ReferenceHash::remove(uint32_t slot) {
    const uint64_t k = keys_.at(slot);
    if (k == KEY_EMPTY || k == KEY_TOMBSTONE) throw Error("hash slot " + std::to_string(slot) + " holds no key to remove");
    keys_[slot] = KEY_TOMBSTONE;
    values_[slot] = NO_BLOCK;
    --entries_;
    ++tombstones_;
}

ReferenceHash::Rebuilt ReferenceHash::rebuilt(uint32_t newCapacity) const {
    Rebuilt out{ReferenceHash(newCapacity), 0};
    // rehash_insert.comp runs one invocation per live block; serially, in block-index order.
    std::vector<uint32_t> live;
    for (uint32_t slot = 0; slot < capacity(); ++slot)
        if (keys_[slot] != KEY_EMPTY && keys_[slot] != KEY_TOMBSTONE && values_[slot] != NO_BLOCK) live.push_back(slot);
    std::sort(live.begin(), live.end(), [&](uint32_t a, uint32_t b) { return values_[a] < values_[b]; });
    for (uint32_t slot : live) {
        const HashInsertResult r = out.table.insert(unpackBlockKey(keys_[slot]));
        if (r.outcome != HashInsert::Inserted) {  // keys are unique, so Found cannot happen
            ++out.lost;
            continue;
        }
        out.table.values_[r.slot] = values_[slot];
        out.table.stamps_[r.slot] = stamps_[slot];
    }
    return out;
}

std::vector<std::string> ReferenceHash::checkInvariants() const {
    std::vector<std::string> problems;
    uint32_t entries = 0, tombstones = 0;
    std::set<uint64_t> seen;
    const uint32_t mask = capacity() - 1u;
    for (uint32_t slot = 0; slot < capacity(); ++slot) {
        const uint64_t k = keys_[slot];
        const std::string at = "slot " + std::to_string(slot);
        if (k == KEY_EMPTY || k == KEY_TOMBSTONE) {
            if (k == KEY_TOMBSTONE) ++tombstones;
            if (values_[slot] != NO_BLOCK) problems.push_back(at + ": holds no key but a block");
            continue;
        }
        ++entries;
        if (k >> (3u * gpu::KEY_BITS)) problems.push_back(at + ": key has bits above the three axes");
        if (!seen.insert(k).second) problems.push_back(at + ": key appears twice");
        const BlockCoord c = unpackBlockKey(k);
        const uint32_t home = hashHomeSlot(c, capacity());
        const uint32_t distance = (slot - home) & mask;
        if (distance >= HASH_MAX_PROBES) {
            problems.push_back(at + ": key " + std::to_string(distance) + " slots from its home slot");
            continue;
        }
        for (uint32_t s = home; s != slot; s = (s + 1u) & mask)
            if (keys_[s] == KEY_EMPTY) {
                problems.push_back(at + ": an EMPTY slot lies between the key and its home slot " + std::to_string(home));
                break;
            }
        if (find(c) != slot) problems.push_back(at + ": find() does not reach the key");
    }
    if (entries != entries_) problems.push_back("entry count " + std::to_string(entries_) + " but " + std::to_string(entries) + " keys");
    if (tombstones != tombstones_)
        problems.push_back("tombstone count " + std::to_string(tombstones_) + " but " + std::to_string(tombstones) + " tombstones");
    return problems;
}

}  // namespace vkmesh::cpu
