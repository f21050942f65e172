// The CPU reference of the block hash (src/cpu/reference_hash.h) alone: keys, the Teschner home slot,
// insertion with linear probing, tombstones, the probe bound, a full table and the rebuild.
#include "cpu/reference_hash.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <vector>

#include "core/types.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using cpu::BlockCoord;
using cpu::HashInsert;
using cpu::ReferenceHash;

using test::joined;

// `count` distinct coordinates whose home slot in a table of `capacity` is `home`.
std::vector<BlockCoord> collidingCoords(uint32_t capacity, uint32_t home, size_t count) {
    std::vector<BlockCoord> out;
    for (int z = -40; z < 40 && out.size() < count; ++z)
        for (int y = -40; y < 40 && out.size() < count; ++y)
            for (int x = -40; x < 40 && out.size() < count; ++x)
                if (cpu::hashHomeSlot({x, y, z}, capacity) == home) out.push_back({x, y, z});
    return out;
}

TEST(ReferenceHash, KeysRoundTripAtTheEdgesOfTheRange) {
    const int lo = -int(gpu::KEY_BIAS), hi = int(gpu::KEY_BIAS) - 1;
    for (const BlockCoord& c : {BlockCoord{0, 0, 0}, BlockCoord{lo, lo, lo}, BlockCoord{hi, hi, hi}, BlockCoord{lo, 0, hi},
                                BlockCoord{-1, 1, -1}, BlockCoord{hi, lo, 7}}) {
        const uint64_t key = cpu::packBlockKey(c);
        EXPECT_EQ(cpu::unpackBlockKey(key), c);
        EXPECT_EQ(key >> 63, 0u) << "bit 63 stays clear, so no key equals KEY_EMPTY or KEY_TOMBSTONE";
        EXPECT_NE(key, gpu::KEY_EMPTY);
        EXPECT_NE(key, gpu::KEY_TOMBSTONE);
    }
    EXPECT_EQ(cpu::packBlockKey({lo, lo, lo}), 0u);
    EXPECT_NE(cpu::packBlockKey({1, 0, 0}), cpu::packBlockKey({0, 1, 0}));
    EXPECT_TRUE(cpu::blockCoordInRange({lo, hi, 0}));
    EXPECT_FALSE(cpu::blockCoordInRange({hi + 1, 0, 0}));
    EXPECT_FALSE(cpu::blockCoordInRange({0, lo - 1, 0}));
    EXPECT_THROW(cpu::packBlockKey({0, 0, hi + 1}), Error);
}

TEST(ReferenceHash, HomeSlotIsTeschnersHashMaskedToTheCapacity) {
    // 73856093 = 72125 * 1024 + 93, 19349669 = 18896 * 1024 + 165; -1 wraps to 2^32 - 1.
    EXPECT_EQ(cpu::hashHomeSlot({1, 0, 0}, 1024), 93u);
    EXPECT_EQ(cpu::hashHomeSlot({0, 1, 0}, 1024), 165u);
    EXPECT_EQ(cpu::hashHomeSlot({-1, 0, 0}, 1024), 1024u - 93u);
    EXPECT_EQ(cpu::hashHomeSlot({0, 0, 0}, 1024), 0u);
    EXPECT_EQ(cpu::hashHomeSlot({1, 1, 0}, 1u << 20), (73856093u ^ 19349669u) & ((1u << 20) - 1));
}

TEST(ReferenceHash, CapacityMustBeAPowerOfTwo) {
    EXPECT_THROW(ReferenceHash(0), Error);
    EXPECT_THROW(ReferenceHash(1000), Error);
    EXPECT_NO_THROW(ReferenceHash(1));
    EXPECT_EQ(ReferenceHash(256).capacity(), 256u);
}

TEST(ReferenceHash, EveryInsertedKeyIsFoundWhereItWasInserted) {
    ReferenceHash hash(4096);
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> coord(-200, 200);
    std::map<BlockCoord, uint32_t> slotOf;
    for (int i = 0; i < 1500; ++i) {
        const BlockCoord c{coord(rng), coord(rng), coord(rng)};
        const auto r = hash.insert(c);
        ASSERT_NE(r.outcome, HashInsert::Full) << "a table under half full";
        if (slotOf.count(c)) {
            EXPECT_EQ(r.outcome, HashInsert::Found);
            EXPECT_EQ(r.slot, slotOf[c]);
        } else {
            EXPECT_EQ(r.outcome, HashInsert::Inserted);
            EXPECT_EQ(hash.key(r.slot), cpu::packBlockKey(c));
            EXPECT_EQ(hash.value(r.slot), gpu::NO_BLOCK) << "a new key holds no block until the assign stage";
            slotOf[c] = r.slot;
            hash.setValue(r.slot, uint32_t(slotOf.size()));
        }
    }
    EXPECT_EQ(hash.entries(), slotOf.size());
    EXPECT_EQ(hash.tombstones(), 0u);
    for (const auto& [c, slot] : slotOf) {
        EXPECT_EQ(hash.find(c), slot);
        EXPECT_EQ(hash.findBlock(c), hash.value(slot));
        EXPECT_NE(hash.findBlock(c), gpu::NO_BLOCK);
    }
    EXPECT_EQ(hash.find({1000, 1000, 1000}), gpu::NO_BLOCK);
    EXPECT_EQ(hash.findBlock({1000, 1000, 1000}), gpu::NO_BLOCK);
    EXPECT_EQ(hash.find({int(gpu::KEY_BIAS), 0, 0}), gpu::NO_BLOCK) << "out of range";
    EXPECT_EQ(hash.insert({int(gpu::KEY_BIAS), 0, 0}).outcome, HashInsert::OutOfRange);
    const auto problems = hash.checkInvariants();
    EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST(ReferenceHash, CollisionsProbeLinearlyAndWrapAround) {
    const uint32_t capacity = 256;
    ReferenceHash hash(capacity);
    const auto keys = collidingCoords(capacity, capacity - 2, 4);
    ASSERT_EQ(keys.size(), 4u);
    const uint32_t expected[4] = {capacity - 2, capacity - 1, 0, 1};
    for (int i = 0; i < 4; ++i) {
        const auto r = hash.insert(keys[i]);
        EXPECT_EQ(r.outcome, HashInsert::Inserted);
        EXPECT_EQ(r.slot, expected[i]) << "key " << i;
    }
    for (int i = 0; i < 4; ++i) EXPECT_EQ(hash.find(keys[i]), expected[i]);
    const auto problems = hash.checkInvariants();
    EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST(ReferenceHash, TombstonesKeepProbeSequencesAndAreNotReused) {
    const uint32_t capacity = 128;
    ReferenceHash hash(capacity);
    const auto keys = collidingCoords(capacity, 10, 4);
    ASSERT_EQ(keys.size(), 4u);
    for (int i = 0; i < 3; ++i) hash.setValue(hash.insert(keys[i]).slot, uint32_t(i));
    hash.remove(11);   // keys[1]
    EXPECT_EQ(hash.key(11), gpu::KEY_TOMBSTONE);
    EXPECT_EQ(hash.value(11), gpu::NO_BLOCK);
    EXPECT_EQ(hash.entries(), 2u);
    EXPECT_EQ(hash.tombstones(), 1u);
    EXPECT_EQ(hash.find(keys[1]), gpu::NO_BLOCK);
    EXPECT_EQ(hash.find(keys[2]), 12u) << "a lookup probes past the tombstone";
    EXPECT_EQ(hash.findBlock(keys[2]), 2u);
    EXPECT_THROW(hash.remove(11), Error) << "a tombstone holds no key";
    EXPECT_THROW(hash.remove(50), Error) << "an EMPTY slot holds no key";
    EXPECT_THROW(hash.setValue(11, 5), Error);
    // Re-inserting the removed key (or a new colliding one) takes the first EMPTY slot, not the tombstone.
    auto again = hash.insert(keys[1]);
    EXPECT_EQ(again.outcome, HashInsert::Inserted);
    EXPECT_EQ(again.slot, 13u);
    EXPECT_EQ(hash.insert(keys[3]).slot, 14u);
    EXPECT_EQ(hash.key(11), gpu::KEY_TOMBSTONE);
    EXPECT_EQ(hash.entries(), 4u);
    const auto problems = hash.checkInvariants();
    EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST(ReferenceHash, ProbingStopsAtTheBound) {
    // 65 keys with one home slot in a table of 128: the first HASH_MAX_PROBES fit, the next finds no slot
    // within the bound although the table has room.
    const uint32_t capacity = 128;
    ReferenceHash hash(capacity);
    const auto keys = collidingCoords(capacity, 5, gpu::HASH_MAX_PROBES + 1);
    ASSERT_EQ(keys.size(), gpu::HASH_MAX_PROBES + 1);
    for (uint32_t i = 0; i < gpu::HASH_MAX_PROBES; ++i) EXPECT_EQ(hash.insert(keys[i]).outcome, HashInsert::Inserted) << i;
    const auto r = hash.insert(keys.back());
    EXPECT_EQ(r.outcome, HashInsert::Full);
    EXPECT_EQ(r.slot, gpu::NO_BLOCK);
    EXPECT_EQ(hash.find(keys.back()), gpu::NO_BLOCK);
    EXPECT_EQ(hash.entries(), gpu::HASH_MAX_PROBES);
    EXPECT_EQ(hash.find(keys[gpu::HASH_MAX_PROBES - 1]), (5u + gpu::HASH_MAX_PROBES - 1) % capacity);
    // A key with another home slot still fits.
    const auto other = collidingCoords(capacity, 100, 1);
    EXPECT_EQ(hash.insert(other[0]).outcome, HashInsert::Inserted);
    const auto problems = hash.checkInvariants();
    EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST(ReferenceHash, AFullTableReportsFullAndLookupsEnd) {
    ReferenceHash hash(4);
    std::vector<BlockCoord> inserted;
    uint32_t full = 0;
    for (int x = 0; x < 10; ++x) {
        const auto r = hash.insert({x, 0, 0});
        if (r.outcome == HashInsert::Full) ++full;
        else inserted.push_back({x, 0, 0});
    }
    EXPECT_EQ(inserted.size(), 4u);
    EXPECT_EQ(full, 6u);
    EXPECT_EQ(hash.entries(), 4u);
    for (const auto& c : inserted) EXPECT_NE(hash.find(c), gpu::NO_BLOCK);
    EXPECT_EQ(hash.find({50, 0, 0}), gpu::NO_BLOCK) << "no EMPTY slot: the lookup ends at the probe bound";
}

TEST(ReferenceHash, RebuildKeepsLiveBlocksDropsTombstonesAndEmptyKeys) {
    ReferenceHash hash(512);
    std::map<BlockCoord, std::pair<uint32_t, uint32_t>> live;   // value, stamp
    std::vector<BlockCoord> removed, withoutBlock;
    uint32_t block = 0;
    for (int x = -6; x < 6; ++x)
        for (int y = -6; y < 6; ++y) {
            const BlockCoord c{x, y, x * y};
            const auto r = hash.insert(c);
            ASSERT_EQ(r.outcome, HashInsert::Inserted);
            hash.setStamp(r.slot, uint32_t(100 + x + y));
            if ((x + y) % 5 == 0) { withoutBlock.push_back(c); continue; }   // pool exhausted: NO_BLOCK stays
            hash.setValue(r.slot, block);
            if ((x * 7 + y) % 4 == 0) { hash.remove(r.slot); removed.push_back(c); }
            else live[c] = {block, uint32_t(100 + x + y)};
            ++block;
        }
    ASSERT_GT(hash.tombstones(), 10u);
    ASSERT_GT(withoutBlock.size(), 10u);
    for (uint32_t capacity : {512u, 2048u, 256u}) {   // rebuild, grow, shrink
        const auto rebuilt = hash.rebuilt(capacity);
        const ReferenceHash& table = rebuilt.table;
        EXPECT_EQ(rebuilt.lost, 0u);
        EXPECT_EQ(table.capacity(), capacity);
        EXPECT_EQ(table.entries(), live.size());
        EXPECT_EQ(table.tombstones(), 0u);
        for (const auto& [c, vs] : live) {
            const uint32_t slot = table.find(c);
            ASSERT_NE(slot, gpu::NO_BLOCK);
            EXPECT_EQ(table.value(slot), vs.first);
            EXPECT_EQ(table.stamp(slot), vs.second) << "the stamp (starvation's clock) survives the rebuild";
        }
        for (const auto& c : removed) EXPECT_EQ(table.find(c), gpu::NO_BLOCK);
        for (const auto& c : withoutBlock) EXPECT_EQ(table.find(c), gpu::NO_BLOCK);
        const auto problems = table.checkInvariants();
        EXPECT_TRUE(problems.empty()) << joined(problems);
    }
    // A table too small for the live blocks loses the ones that find no slot, and says how many.
    const auto tiny = hash.rebuilt(16);
    EXPECT_EQ(tiny.table.entries(), 16u);
    EXPECT_EQ(tiny.lost, live.size() - 16u);
}

}  // namespace
}  // namespace vkmesh
