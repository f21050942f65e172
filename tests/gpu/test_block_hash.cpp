// The block hash alone (src/gpu/block_hash.h, docs/HASH.md), on both atomic paths: the 64-bit one
// (one 64-bit CAS per key) and the 32-bit one (3 key words per slot, one 32-bit CAS each), the latter
// through VKMESH_PRETEND_MISSING on a device that has 64-bit atomics. Then fusion end to end on both
// paths: the same TSDF per block coordinate bit for bit, the same triangles, the same counters.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <span>
#include <string>

#include "core/mesh_analysis.h"
#include "cpu/reference_hash.h"
#include "cpu/reference_volume.h"
#include "gpu/structure/block_hash.h"
#include "gpu/gpu_volume.h"
#include "mesh_checks.h"
#include "synth/synthetic_scene.h"
#include "vk/commands.h"
#include "vk/pipeline.h"
#include "vk/shader_registry.h"

namespace vkmesh {
namespace {

using Coord = std::array<int, 3>;
constexpr const char* kPretendNo64 = "shaderBufferInt64Atomics,shaderInt64";

// One context per path for the whole program, validation on. The 32-bit one is created with
// VKMESH_PRETEND_MISSING naming both 64-bit features, the other one without it (whatever the environment).
std::unique_ptr<vk::Context> contexts[2];

// Destroys both contexts when the tests are done, before static destruction: two Vulkan instances left to
// static destruction crashed at exit (segfault after every test had passed; cause not established).
class ContextsTeardown : public ::testing::Environment {
public:
    void TearDown() override {
        contexts[0].reset();
        contexts[1].reset();
    }
};
const ::testing::Environment* const kTeardown = ::testing::AddGlobalTestEnvironment(new ContextsTeardown);

vk::Context& contextFor(bool int64) {
    std::unique_ptr<vk::Context>& c = contexts[int64 ? 1 : 0];
    if (!c) {
        const char* env = std::getenv("VKMESH_PRETEND_MISSING");
        const std::string saved = env ? env : "";
        if (int64) unsetenv("VKMESH_PRETEND_MISSING");
        else setenv("VKMESH_PRETEND_MISSING", kPretendNo64, 1);
        c = std::make_unique<vk::Context>(vk::ContextOptions{-1, true});
        if (env) setenv("VKMESH_PRETEND_MISSING", saved.c_str(), 1);
        else unsetenv("VKMESH_PRETEND_MISSING");
    }
    return *c;
}

class PathTest : public ::testing::TestWithParam<bool> {
protected:
    vk::Context& context() { return contextFor(GetParam()); }
    void SetUp() override {
        if (GetParam() && !context().int64Atomics()) GTEST_SKIP() << "the device has no 64-bit atomics";
        ASSERT_EQ(context().int64Atomics(), GetParam());
        context().takeValidationMessages();
    }
    void TearDown() override {
        auto messages = context().takeValidationMessages();
        EXPECT_TRUE(messages.empty()) << messages.size() << " validation messages, first: " << messages.front();
    }
};

std::string pathName(const ::testing::TestParamInfo<bool>& info) { return info.param ? "Int64Atomics" : "Atomics32"; }

// The shaders' home slot (structure/block_hash.glsl, the CPU reference's), to build keys that collide.
uint32_t homeSlot(const Coord& c, uint32_t capacity) { return cpu::hashHomeSlot(cpu::BlockCoord{c[0], c[1], c[2]}, capacity); }

// The CPU reference hash (src/cpu/reference_hash.h) fed the same entries serially: how many were found,
// inserted, full. Concurrent GPU insertions end in other slots, but these counts are the same.
std::array<uint32_t, 3> referenceCounts(cpu::ReferenceHash& ref, const std::vector<Coord>& entries) {
    std::array<uint32_t, 3> n{};
    for (const Coord& c : entries) {
        const cpu::HashInsert outcome = ref.insert(cpu::BlockCoord{c[0], c[1], c[2]}).outcome;
        ++n[outcome == cpu::HashInsert::Found ? 0 : outcome == cpu::HashInsert::Inserted ? 1 : 2];
    }
    return n;
}

// The hash with the few buffers its passes touch, driven by hash/test_hash_access.comp: entry i of the
// block coordinates holds a key; the invocation that inserts a key makes its entry that key's block.
class HashHarness {
public:
    HashHarness(const vk::Context& context, uint32_t capacity, const std::vector<Coord>& entries)
        : context_(context),
          n_(uint32_t(entries.size())),
          layout_(context, sizeof(gpu::FramePush)),
          hash_(context, layout_, capacity),
          insert_(context, layout_, "test_hash_access", 0u),
          find_(context, layout_, "test_hash_access", 1u),
          remove_(context, layout_, "test_hash_access", 2u),
          collect_(context, layout_, "collect_blocks"),
          planList_(context, layout_, "plan_block_list"),
          recorder_(context) {
        constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
        params_ = vk::Buffer(context, sizeof(gpu::VolumeParamsGpu), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, vk::MemoryUse::Device, "params");
        counters_ = vk::Buffer(context, sizeof(gpu::Counters), kStorage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, vk::MemoryUse::Device, "counters");
        coords_ = vk::Buffer(context, VkDeviceSize(n_) * 16, kStorage, vk::MemoryUse::Device, "block coords");
        touched_ = vk::Buffer(context, VkDeviceSize(n_) * 4, kStorage, vk::MemoryUse::Device, "touched");
        blockList_ = vk::Buffer(context, VkDeviceSize(n_) * 4, kStorage, vk::MemoryUse::Device, "block list");
        layout_.bind(gpu::BINDING_PARAMS, params_);
        layout_.bind(gpu::BINDING_COUNTERS, counters_);
        layout_.bind(gpu::BINDING_BLOCK_COORDS, coords_);
        layout_.bind(gpu::BINDING_TOUCHED, touched_);
        layout_.bind(gpu::BINDING_BLOCK_LIST, blockList_);
        gpu::VolumeParamsGpu gp{};
        gp.hashCapacity = capacity;
        gp.blockCapacity = n_;
        vk::uploadToBuffer(context, params_, &gp, sizeof(gp));
        gpu::Counters k{};
        vk::uploadToBuffer(context, counters_, &k, sizeof(k));
        std::vector<int32_t> c;
        for (const Coord& e : entries) c.insert(c.end(), {e[0], e[1], e[2], -1});
        vk::uploadToBuffer(context, coords_, c.data(), c.size() * 4);
    }

    // One dispatch of test_hash_access over every entry; returns its counters.
    gpu::Counters run(const vk::ComputePipeline& pipeline, uint32_t frameNumber) {
        VkCommandBuffer cmd = recorder_.begin();
        vkCmdFillBuffer(cmd, counters_.handle(), gpu::COUNTERS_PER_FRAME_OFFSET, gpu::COUNTERS_PER_FRAME_SIZE, 0);
        vk::memoryBarrier(cmd);
        gpu::FramePush push = pushFor(frameNumber);
        pipeline.dispatchItems(cmd, &push, n_);
        vk::memoryBarrier(cmd);
        recorder_.submitAndWait();
        return counters();
    }
    gpu::Counters insert(uint32_t frameNumber) { return run(insert_, frameNumber); }
    std::vector<uint32_t> find() {
        run(find_, 0);
        return touched();
    }
    void removeEveryThirdBlock() { run(remove_, 0); }

    void rebuild() {
        VkCommandBuffer cmd = recorder_.begin();
        recordLiveBlocks(cmd);
        gpu::FramePush push = pushFor(0);
        hash_.recordRebuild(cmd, push, n_);
        recorder_.submitAndWait();
    }
    uint32_t grow(uint32_t capacity) {
        return hash_.grow(capacity, params_, counters_, pushFor(0), n_, [&](VkCommandBuffer cmd) { recordLiveBlocks(cmd); });
    }

    std::vector<uint32_t> touched() const {
        std::vector<uint32_t> t(n_);
        vk::downloadFromBuffer(context_, touched_, t.data(), t.size() * 4);
        return t;
    }
    std::vector<std::array<int32_t, 4>> coords() const {
        std::vector<std::array<int32_t, 4>> c(n_);
        vk::downloadFromBuffer(context_, coords_, c.data(), c.size() * 16);
        return c;
    }
    gpu::Counters counters() const {
        gpu::Counters k{};
        vk::downloadFromBuffer(context_, counters_, &k, sizeof(k));
        return k;
    }
    const gpu::BlockHash& hash() const { return hash_; }

private:
    gpu::FramePush pushFor(uint32_t frameNumber) const {
        gpu::FramePush push{};
        push.imageSize = n_;   // test_hash_access: the number of entries
        push.frameNumber = frameNumber;
        return push;
    }
    void recordLiveBlocks(VkCommandBuffer cmd) {
        vkCmdFillBuffer(cmd, counters_.handle(), offsetof(gpu::Counters, liveBlockCount), sizeof(uint32_t), 0);
        vk::memoryBarrier(cmd);
        gpu::FramePush push = pushFor(0);
        collect_.dispatchItems(cmd, &push, hash_.capacity());
        vk::memoryBarrier(cmd);
        planList_.dispatch(cmd, &push, 1);
        vk::memoryBarrier(cmd);
    }

    const vk::Context& context_;
    uint32_t n_;
    vk::BindingTable layout_;
    gpu::BlockHash hash_;
    vk::ComputePipeline insert_, find_, remove_, collect_, planList_;
    vk::CommandRecorder recorder_;
    vk::Buffer params_, counters_, coords_, touched_, blockList_;
};

// Distinct keys: random ones, a cluster sharing one home slot (long probe sequences), and the corners of the
// key range (every bit of every key word used).
std::vector<Coord> testKeys(uint32_t capacity) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> d(-300, 300);
    std::set<Coord> keys;
    while (keys.size() < 300) keys.insert({d(rng), d(rng), d(rng)});
    const Coord first{d(rng), d(rng), d(rng)};
    keys.insert(first);
    for (size_t cluster = 1; cluster < 24;) {
        Coord c{d(rng), d(rng), d(rng)};
        if (homeSlot(c, capacity) == homeSlot(first, capacity) && keys.insert(c).second) ++cluster;
    }
    const int lo = -int(gpu::KEY_BIAS), hi = int(gpu::KEY_BIAS) - 1;
    for (Coord c : {Coord{lo, lo, lo}, Coord{hi, hi, hi}, Coord{lo, hi, lo}, Coord{hi, lo, hi}, Coord{0, 0, 0}, Coord{-1, -1, -1}})
        keys.insert(c);
    return {keys.begin(), keys.end()};
}

TEST_P(PathTest, HashUnderContentionInsertLookupRemoveRebuildGrow) {
    constexpr uint32_t kCapacity = 1024, kRepeats = 12;
    const std::vector<Coord> keys = testKeys(kCapacity);
    // Every key 12 times, shuffled: many invocations of one dispatch insert the same key at once.
    std::vector<Coord> entries;
    for (uint32_t r = 0; r < kRepeats; ++r) entries.insert(entries.end(), keys.begin(), keys.end());
    std::shuffle(entries.begin(), entries.end(), std::mt19937(11));
    HashHarness h(context(), kCapacity, entries);
    EXPECT_EQ(h.hash().int64Keys(), GetParam());

    const uint32_t kFrame = 5;
    gpu::Counters k = h.insert(kFrame);
    EXPECT_EQ(k.blocksInserted, keys.size()) << "exactly one invocation inserts each key";
    EXPECT_EQ(k.hashFull, 0u);
    EXPECT_EQ(k.blocksFound + k.blocksInserted, entries.size());
    cpu::ReferenceHash reference(kCapacity);
    EXPECT_EQ((std::array<uint32_t, 3>{k.blocksFound, k.blocksInserted, k.hashFull}), referenceCounts(reference, entries));
    EXPECT_TRUE(reference.checkInvariants().empty());

    // The table holds every key exactly once, and every invocation of a key got that key's slot.
    auto checkTable = [&](const std::set<Coord>& expected, const char* when) {
        std::map<Coord, gpu::BlockHash::Entry> bySlotKey;
        auto table = h.hash().downloadEntries();
        for (const auto& e : table) EXPECT_TRUE(bySlotKey.emplace(Coord{e.x, e.y, e.z}, e).second) << when << ": a key twice";
        EXPECT_EQ(table.size(), expected.size()) << when;
        std::set<Coord> got;
        for (const auto& [c, e] : bySlotKey) got.insert(c);
        EXPECT_EQ(got, expected) << when;
        return bySlotKey;
    };
    const std::set<Coord> all(keys.begin(), keys.end());
    auto table = checkTable(all, "after insert");
    std::vector<uint32_t> slots = h.touched();
    auto coords = h.coords();
    for (size_t i = 0; i < entries.size(); ++i) {
        const gpu::BlockHash::Entry& e = table.at(entries[i]);
        ASSERT_EQ(slots[i], e.slot) << "entry " << i;
        ASSERT_LT(e.block, entries.size());
        EXPECT_EQ(entries[e.block], entries[i]) << "the block of a key is an entry of that key";
        EXPECT_EQ(coords[e.block][3], int(e.slot));
        EXPECT_EQ(e.stamp, kFrame + e.block);
    }
    // Lookups find every key at its slot; keys never inserted are absent.
    slots = h.find();
    for (size_t i = 0; i < entries.size(); ++i) ASSERT_EQ(slots[i], table.at(entries[i]).slot);
    {
        std::vector<Coord> absent;
        std::mt19937 rng(3);
        std::uniform_int_distribution<int> d(-300, 300);
        while (absent.size() < 200) {
            Coord c{d(rng), d(rng), d(rng)};
            if (!all.count(c)) absent.push_back(c);
        }
        HashHarness probe(context(), kCapacity, absent);
        for (uint32_t s : probe.find()) EXPECT_EQ(s, gpu::NO_BLOCK);
    }

    // Remove the keys of every third block: lookups probe past the tombstones.
    std::set<Coord> kept;
    std::map<Coord, uint32_t> stampOf;
    for (const auto& [c, e] : table) {
        if (e.block % 3 != 0) kept.insert(c);
        stampOf[c] = e.stamp;
    }
    h.removeEveryThirdBlock();
    EXPECT_EQ(h.hash().downloadOccupancy().tombstones, keys.size() - kept.size());
    checkTable(kept, "after remove");
    slots = h.find();
    for (size_t i = 0; i < entries.size(); ++i)
        ASSERT_EQ(slots[i], kept.count(entries[i]) ? table.at(entries[i]).slot : gpu::NO_BLOCK) << "entry " << i;

    // Rebuild: no tombstones, every kept key findable at its new slot, its block and stamp unchanged.
    auto checkRebuilt = [&](const char* when) {
        EXPECT_EQ(h.hash().downloadOccupancy().tombstones, 0u) << when;
        auto now = checkTable(kept, when);
        gpu::Counters c = h.counters();
        EXPECT_EQ(c.rehashLost, 0u) << when;
        EXPECT_EQ(c.hashEntries, kept.size()) << when;
        EXPECT_EQ(c.hashTombstones, 0u) << when;
        auto coordsNow = h.coords();
        for (const auto& [key, e] : now) {
            EXPECT_EQ(e.block, table.at(key).block) << when;
            EXPECT_EQ(e.stamp, stampOf.at(key)) << when;
            EXPECT_EQ(coordsNow[e.block][3], int(e.slot)) << when << ": the block's w points at its new slot";
        }
        std::vector<uint32_t> found = h.find();
        for (size_t i = 0; i < entries.size(); ++i)
            EXPECT_EQ(found[i], kept.count(entries[i]) ? now.at(entries[i]).slot : gpu::NO_BLOCK) << when;
    };
    h.rebuild();
    checkRebuilt("after rebuild");

    // Grow into 4x the slots: the same, and params.hashCapacity is the new size (lookups use it).
    EXPECT_EQ(h.grow(4 * kCapacity), 0u);
    EXPECT_EQ(h.hash().capacity(), 4 * kCapacity);
    checkRebuilt("after grow");
    // Inserting everything again into the grown table: only the removed keys are new.
    k = h.insert(kFrame + 1);
    EXPECT_EQ(k.blocksInserted, keys.size() - kept.size());
    EXPECT_EQ(k.hashFull, 0u);
    checkTable(all, "after re-insert");
    EXPECT_THROW(h.grow(2 * kCapacity), Error);   // never shrinks
}

TEST_P(PathTest, FullHashIsCountedNotWaitedFor) {
    // 64 slots, 200 distinct keys each inserted 4 times: at most 64 get a slot, the rest count as full.
    std::vector<Coord> entries;
    for (int r = 0; r < 4; ++r)
        for (int i = 0; i < 200; ++i) entries.push_back({i, -i, 2 * i});
    HashHarness h(context(), 64, entries);
    gpu::Counters k = h.insert(1);
    EXPECT_EQ(k.blocksInserted, 64u);
    EXPECT_EQ(k.blocksInserted + k.blocksFound + k.hashFull, entries.size());
    EXPECT_EQ(h.hash().downloadEntries().size(), 64u);
    cpu::ReferenceHash reference(64);
    EXPECT_EQ((std::array<uint32_t, 3>{k.blocksFound, k.blocksInserted, k.hashFull}), referenceCounts(reference, entries));
}

INSTANTIATE_TEST_SUITE_P(BothAtomicPaths, PathTest, ::testing::Bool(), pathName);

// SPIR-V opcodes and capabilities of the check below (SPIR-V 1.x specification).
constexpr uint32_t kOpCapability = 17, kOpTypeInt = 21, kCapabilityInt64 = 11, kCapabilityInt64Atomics = 12;

TEST(ShaderBuilds, EveryComputeShaderHasA32BitBuildWithoutAny64BitType) {
    const auto& table = shaders::all();
    size_t plain = 0;
    for (const auto& [name, code] : table) {
        if (name.find('@') != std::string::npos) continue;
        ++plain;
        ASSERT_TRUE(table.count(shaders::computeShaderKey(name, false))) << name << " has no @hash32 build";
        std::span<const uint32_t> spv = shaders::computeShader(name, false);
        ASSERT_GT(spv.size(), 5u);
        for (size_t i = 5; i < spv.size();) {
            const uint32_t words = spv[i] >> 16, op = spv[i] & 0xFFFFu;
            ASSERT_GT(words, 0u) << name;
            if (op == kOpCapability) {
                EXPECT_NE(spv[i + 1], kCapabilityInt64) << name << "@hash32 declares Int64";
                EXPECT_NE(spv[i + 1], kCapabilityInt64Atomics) << name << "@hash32 declares Int64Atomics";
            }
            if (op == kOpTypeInt) {
                EXPECT_NE(spv[i + 2], 64u) << name << "@hash32 has a 64-bit integer type";
            }
            i += words;
        }
    }
    EXPECT_GT(plain, 30u);
}

TEST(ShaderBuilds, PretendMissingNamesUnknownFeatures) {
    setenv("VKMESH_PRETEND_MISSING", "shaderInt64,shaderFloat128", 1);
    std::string message;
    try {
        vk::pretendedMissingFeatures();
    } catch (const Error& e) {
        message = e.what();
    }
    unsetenv("VKMESH_PRETEND_MISSING");
    EXPECT_NE(message.find("shaderFloat128"), std::string::npos) << message;
    EXPECT_NE(message.find("shaderBufferInt64Atomics"), std::string::npos) << "lists the known names: " << message;
    setenv("VKMESH_PRETEND_MISSING", " shaderInt64 ,shaderBufferInt64Atomics", 1);
    EXPECT_EQ(vk::pretendedMissingFeatures().size(), 2u);
    unsetenv("VKMESH_PRETEND_MISSING");
}

// ---- end to end: fusion on both paths -------------------------------------------------------------

struct FusedRun {
    std::map<Coord, std::pair<std::vector<float>, std::vector<float>>> tsdf;
    std::vector<CanonicalTriangle> triangles;
    std::vector<std::array<uint32_t, 6>> frameCounts;   // per frame: inserted, found, full, touched, entries, rebuilt
    std::set<Coord> referenceBlocks;                      // the CPU reference's blocks at the end
};

// Fuses the room; returns what the test compares. hashGrowths: how many frames grew the hash (the library's
// growth policy, from a small initial hashCapacity).
FusedRun fuseRoom(vk::Context& context, const gpu::GpuVolumeConfig& config, size_t frames, size_t* hashGrowths = nullptr) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    gpu::GpuVolume volume(context, config);
    cpu::ReferenceVolume reference(config.params, config.minMeshWeight);
    reference.setRecycling(config.keepRadius, config.recycle ? config.recycleAfterFrames : 0u, config.starveWeight);
    Intrinsics intr = synth::kinectIntrinsics(config.imageWidth, config.imageHeight);
    auto poses = synth::cameraPath(24, synth::PathKind::Orbit);
    FusedRun run;
    for (size_t i = 0; i < frames; ++i) {
        synth::RenderOptions options;
        options.noise = true;
        options.seed = uint32_t(i + 1);
        DepthImage depth = scene.renderDepth(intr, poses[i % poses.size()], options);
        gpu::FrameReport r = volume.integrate(depth, intr, poses[i % poses.size()]);
        reference.integrate(depth, intr, poses[i % poses.size()]);
        EXPECT_TRUE(r.warnings.empty()) << "frame " << i << ": " << r.warnings.front();
        for (const std::string& g : r.growth)
            if (hashGrowths && g.find("block hash") != std::string::npos) ++*hashGrowths;
        const gpu::Counters& k = r.counters;
        run.frameCounts.push_back({k.blocksInserted, k.blocksFound, k.hashFull, k.touchedCount, k.hashEntries, k.hashRebuilt});
    }
    for (const auto& b : volume.downloadBlocks()) run.tsdf[{b.coord.x(), b.coord.y(), b.coord.z()}] = {b.sdf, b.weight};
    for (const auto& [c, b] : reference.blocks()) run.referenceBlocks.insert(c);
    run.triangles = canonicalTriangles(test::soupOf(volume.exportMesh()));
    return run;
}

void expectSameRuns(const FusedRun& a, const FusedRun& b, const std::string& what) {
    EXPECT_EQ(a.frameCounts, b.frameCounts) << what << ": per-frame hash counters";
    ASSERT_EQ(a.tsdf.size(), b.tsdf.size()) << what;
    size_t differing = 0;
    for (const auto& [c, t] : a.tsdf) {
        auto it = b.tsdf.find(c);
        if (it == b.tsdf.end() || std::memcmp(t.first.data(), it->second.first.data(), t.first.size() * 4) != 0 ||
            std::memcmp(t.second.data(), it->second.second.data(), t.second.size() * 4) != 0)
            ++differing;
    }
    EXPECT_EQ(differing, 0u) << what << ": blocks whose TSDF differs (bit for bit) or that are missing";
    EXPECT_GT(a.triangles.size(), 1000u) << what;
    EXPECT_EQ(a.triangles, b.triangles) << what << ": the triangle sets";
    std::set<Coord> blocks;
    for (const auto& [c, t] : b.tsdf) blocks.insert(c);
    EXPECT_EQ(blocks, b.referenceBlocks) << what << ": the blocks are the CPU reference's";
}

class BothPaths : public ::testing::Test {
protected:
    void SetUp() override {
        if (!contextFor(true).int64Atomics()) GTEST_SKIP() << "the device has no 64-bit atomics: nothing to compare with";
        for (bool p : {true, false}) contextFor(p).takeValidationMessages();
    }
    void TearDown() override {
        for (bool p : {true, false}) {
            auto messages = contextFor(p).takeValidationMessages();
            EXPECT_TRUE(messages.empty()) << messages.size() << " validation messages, first: " << messages.front();
        }
    }
};

TEST_F(BothPaths, FusionGivesTheSameTsdfAndMeshWithHashGrowth) {
    gpu::GpuVolumeConfig config = test::smallRoomConfig();
    config.hashCapacity = 256;   // the room needs more: the hash grows during the run
    const size_t kFrames = 12;
    size_t wideGrowths = 0, narrowGrowths = 0;
    FusedRun wide = fuseRoom(contextFor(true), config, kFrames, &wideGrowths);
    FusedRun narrow = fuseRoom(contextFor(false), config, kFrames, &narrowGrowths);
    EXPECT_GT(narrowGrowths, 0u);
    EXPECT_EQ(wideGrowths, narrowGrowths);
    expectSameRuns(wide, narrow, "64-bit vs 32-bit path");
    // Growing the hash changes slots, nothing else: the same as a run with an ample table from the start.
    config.hashCapacity = 1u << 14;
    size_t ampleGrowths = 0;
    FusedRun ample = fuseRoom(contextFor(false), config, kFrames, &ampleGrowths);
    EXPECT_EQ(ampleGrowths, 0u);
    EXPECT_EQ(ample.triangles, narrow.triangles);
    EXPECT_EQ(ample.tsdf, narrow.tsdf);
}

TEST_F(BothPaths, RecyclingWithTombstonesAndRebuildsGivesTheSameTsdfAndMesh) {
    gpu::GpuVolumeConfig config = test::smallRoomConfig();
    config.keepRadius = 2.5f;
    config.recycle = true;
    config.recycleAfterFrames = 4;
    config.starveWeight = 3.0f;
    config.hashRebuildTombstoneFraction = 0.01f;   // rebuilds within the run
    const size_t kFrames = 20;
    FusedRun wide = fuseRoom(contextFor(true), config, kFrames);
    FusedRun narrow = fuseRoom(contextFor(false), config, kFrames);
    expectSameRuns(wide, narrow, "recycling, 64-bit vs 32-bit path");
    uint32_t rebuilds = 0;
    for (const auto& f : narrow.frameCounts) rebuilds += f[5];
    EXPECT_GT(rebuilds, 0u) << "the run should exercise hash rebuilds";
}

}  // namespace
}  // namespace vkmesh
