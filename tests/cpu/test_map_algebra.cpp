// Map algebra on the host (core/map_merge.h, docs/SCALING.md): the sum of saved maps is their corners' sums and
// counts added, blocks united, in coordinate order, with no mesh; whatever the order of the inputs; colour the
// weighted mean. Everything that cannot be added is refused naming the file, the setting and its option. And the
// frame stores beside the maps: FrameStore::absorb moves every frame bit for bit under its new index.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "core/frame_store.h"
#include "core/map_format.h"
#include "core/map_merge.h"
#include "core/types.h"
#include "core/voxel_color.h"
#include "test_support.h"

namespace vkmesh {
namespace {

namespace fs = std::filesystem;
using namespace gpu;
using test::errorMessageOf;

const uint32_t kSums = map::tag("sdf_"), kCounts = map::tag("wght"), kColors = map::tag("colr"), kCubes = map::tag("cube");
const uint32_t kEdges[3] = {map::tag("edgx"), map::tag("edgy"), map::tag("edgz")};
constexpr int64_t kSteps = SDF_STEPS_PER_TRUNCATION;

// splitmix64: the same numbers on every platform and standard library (std's distributions are not).
struct Rng {
    uint64_t s;
    uint64_t next() {
        uint64_t z = (s += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    uint32_t below(uint32_t n) { return uint32_t(next() % n); }
    int64_t between(int64_t lo, int64_t hi) { return lo + int64_t(next() % uint64_t(hi - lo + 1)); }
};

using Coord = std::tuple<int32_t, int32_t, int32_t>;   // x, y, z

// The settings of smallMap() (test_map_format.cpp), allocated by tiles with the current rules.
map::Settings baseSettings(bool color) {
    map::Settings s;
    s.voxelSize = 0.04f;
    s.truncVoxels = 4, s.maxWeight = 255, s.minDepth = 0.1f, s.maxDepth = 6;
    s.allocationStride = 2, s.minMeshWeight = 1, s.imageWidth = 160, s.imageHeight = 120;
    s.allocationTiles = 2;
    s.colorMode = color ? COLOR_MODE_AVERAGE : COLOR_MODE_OFF;
    return s;
}

// Features as the settings say (parse checks they agree).
void syncFeatures(map::MapData& m) {
    m.features = (m.settings.incrementalMesh ? map::FEATURE_INCREMENTAL_MESH : 0u) | (m.settings.colorMode ? map::FEATURE_COLOR : 0u);
}

// A map with no blocks yet: the arrays of smallMap() ('sdf_', 'wght', 'cube', 'edgx/y/z'), and 'colr' with colour.
map::MapData emptyMap(uint32_t frames, bool color = false) {
    map::MapData m;
    m.settings = baseSettings(color);
    syncFeatures(m);
    m.capacities = {64, 1024, 16, 1024, 64, 64};
    m.frameNumber = frames, m.framesIntegrated = frames;
    m.lastPush.frameNumber = frames;
    for (const char* t : {"sdf_", "wght", "cube", "edgx", "edgy", "edgz"}) m.cornerArrays.push_back({map::tag({t[0], t[1], t[2], t[3], 0}), {}});
    if (color) m.cornerArrays.push_back({kColors, {}});
    m.vertexFree = {0, {}};
    m.chunkFree = {0, {}};
    return m;
}

std::vector<uint32_t>& words(map::MapData& m, uint32_t t) {
    for (map::CornerArray& a : m.cornerArrays)
        if (a.tag == t) return a.words;
    throw Error("no array " + map::tagName(t));
}
const std::vector<uint32_t>& words(const map::MapData& m, uint32_t t) {
    const map::CornerArray* a = m.corners(t);
    if (!a) throw Error("no array " + map::tagName(t));
    return a->words;
}

// Appends a block at (x, y, z) whose corners are what fusion gives: about a third never observed (count 0, sum 0),
// the others a whole count of observations and a sum of steps within +-4096 per observation (now and then exactly
// at the bound), and in a colour map a colour (every frame had a colour image: a corner observed without colour
// is AColourOnOneSideOnlyIsTaken's). Its mesh words are those of a live mesh with no chunk (a cube
// type, no vertices), which the sum must not keep. Pool indices are given later (finishPool).
size_t addBlock(map::MapData& m, Coord c, Rng& rng) {
    const size_t b = m.blocks.size();
    m.blocks.push_back({std::get<0>(c), std::get<1>(c), std::get<2>(c), 0, rng.below(m.frameNumber + 1), {}});
    m.blocks.back().retypeMask[rng.below(MASK_WORDS)] = uint32_t(rng.next());
    const bool color = m.settings.colorMode != 0;
    for (map::CornerArray& a : m.cornerArrays) {
        const bool edge = a.tag == kEdges[0] || a.tag == kEdges[1] || a.tag == kEdges[2];
        a.words.resize(m.blocks.size() * VOXELS_PER_BLOCK, edge ? EMPTY_SLOT : 0u);
    }
    for (uint32_t i = 0; i < VOXELS_PER_BLOCK; ++i) {
        const size_t at = b * VOXELS_PER_BLOCK + i;
        words(m, kCubes)[at] = rng.below(256);
        if (rng.below(3) == 0) continue;   // never observed
        const int64_t count = 1 + rng.below(rng.below(8) == 0 ? 2000 : 60);
        int64_t sum = rng.between(-kSteps * count, kSteps * count);
        if (rng.below(16) == 0) sum = (rng.below(2) ? 1 : -1) * kSteps * count;
        words(m, kSums)[at] = uint32_t(int32_t(sum));
        words(m, kCounts)[at] = std::bit_cast<uint32_t>(float(count));
        if (color) words(m, kColors)[at] = packVoxelColor(rng.below(1021), rng.below(1021), rng.below(1021));
    }
    return b;
}

// Pool indices as a volume leaves them: not in the order of the block list, some indices freed between them.
void finishPool(map::MapData& m, Rng& rng) {
    const uint32_t n = uint32_t(m.blocks.size()), holes = 3;
    std::vector<uint32_t> pool(n + holes);
    for (uint32_t i = 0; i < pool.size(); ++i) pool[i] = i;
    for (uint32_t i = uint32_t(pool.size()) - 1; i > 0; --i) std::swap(pool[i], pool[rng.below(i + 1)]);
    for (uint32_t i = 0; i < n; ++i) m.blocks[i].index = pool[i];
    m.blockFree = {n + holes, std::vector<uint32_t>(pool.begin() + n, pool.end())};
    m.counters.blocksInUse = m.counters.liveBlockCount = m.counters.hashEntries = n;
    m.counters.verticesInUse = 0;
}

map::MapData randomMap(uint64_t seed, uint32_t frames, const std::vector<Coord>& coords, bool color) {
    Rng rng{seed};
    map::MapData m = emptyMap(frames, color);
    for (const Coord& c : coords) addBlock(m, c, rng);
    finishPool(m, rng);
    return m;
}

// Three maps, in no coordinate order: (1, 0, 0) in all three, others in two, the rest in one.
const std::vector<Coord> kCoordsA = {{3, -1, 2}, {0, 0, 0}, {1, 0, 0}, {-2, 5, 0}, {7, 7, -3}, {0, 1, 0}};
const std::vector<Coord> kCoordsB = {{1, 0, 0}, {-4, 0, 9}, {0, 0, 0}, {2, 2, 2}, {-2, 5, 1}};
const std::vector<Coord> kCoordsC = {{2, 2, 2}, {1, 0, 0}, {0, 0, -1}, {7, 7, -3}};

struct Maps {
    map::MapData a, b, c;
};
Maps threeMaps(bool color) {
    Maps m{randomMap(11, 7, kCoordsA, color), randomMap(22, 13, kCoordsB, color), randomMap(33, 5, kCoordsC, color)};
    m.b.framesIntegrated = 12;   // a frame skipped
    m.b.capacities = {128, 512, 32, 512, 128, 96};
    m.b.settings.imageWidth = 320, m.b.settings.imageHeight = 240;   // image size: the caller's, not compared
    m.b.lastPush.imageSize = 320u | 240u << 16;
    return m;
}

map::MapData merged(const std::vector<std::pair<std::string, const map::MapData*>>& maps, map::MergeSummary* summary = nullptr) {
    std::vector<map::MergeInput> in;
    for (const auto& [name, m] : maps) in.push_back({name, m});
    return map::merge(in, summary);
}

// Where each coordinate is in a map's block list.
std::map<Coord, size_t> blockAt(const map::MapData& m) {
    std::map<Coord, size_t> out;
    for (size_t i = 0; i < m.blocks.size(); ++i) out[{m.blocks[i].x, m.blocks[i].y, m.blocks[i].z}] = i;
    return out;
}

float countOf(const map::MapData& m, size_t block, uint32_t corner) {
    return std::bit_cast<float>(words(m, kCounts)[block * VOXELS_PER_BLOCK + corner]);
}
int32_t sumOf(const map::MapData& m, size_t block, uint32_t corner) { return int32_t(words(m, kSums)[block * VOXELS_PER_BLOCK + corner]); }

// The inputs are maps parse accepts (so that what is refused below is refused for its reason alone).
TEST(MapAlgebra, TheHandMadeMapsAreValidMaps) {
    const Maps m = threeMaps(true);
    for (const map::MapData* x : {&m.a, &m.b, &m.c}) {
        const map::MapData r = map::parse(map::serialize(*x), "input.vkmap");
        EXPECT_EQ(r.blocks.size(), x->blocks.size());
        for (size_t i = 0; i < x->blocks.size() * VOXELS_PER_BLOCK; ++i) {
            const float w = std::bit_cast<float>(words(*x, kCounts)[i]);
            ASSERT_EQ(w, std::floor(w));
            ASSERT_LE(std::abs(int64_t(int32_t(words(*x, kSums)[i]))), kSteps * int64_t(w));
        }
    }
}

TEST(MapAlgebra, SumsAndCountsAddCornerByCorner) {
    const Maps m = threeMaps(false);
    map::MergeSummary summary;
    const map::MapData r = merged({{"a.vkmap", &m.a}, {"b.vkmap", &m.b}}, &summary);
    const auto inA = blockAt(m.a), inB = blockAt(m.b);
    size_t shared = 0;
    uint64_t observed = 0;
    for (size_t k = 0; k < r.blocks.size(); ++k) {
        const Coord c{r.blocks[k].x, r.blocks[k].y, r.blocks[k].z};
        const auto a = inA.find(c), b = inB.find(c);
        ASSERT_TRUE(a != inA.end() || b != inB.end());
        if (a == inA.end() || b == inB.end()) continue;
        ++shared;
        for (uint32_t i = 0; i < VOXELS_PER_BLOCK; ++i) {
            const int64_t sum = int64_t(sumOf(m.a, a->second, i)) + sumOf(m.b, b->second, i);
            const float count = countOf(m.a, a->second, i) + countOf(m.b, b->second, i);
            ASSERT_EQ(sumOf(r, k, i), sum) << "block " << k << " corner " << i;
            ASSERT_EQ(words(r, kCounts)[k * VOXELS_PER_BLOCK + i], std::bit_cast<uint32_t>(count)) << "block " << k << " corner " << i;
        }
        EXPECT_EQ(r.blocks[k].hashStamp, std::max(m.a.blocks[a->second].hashStamp, m.b.blocks[b->second].hashStamp));
    }
    EXPECT_EQ(shared, 2u);   // (0, 0, 0) and (1, 0, 0); (-2, 5, 0) and (-2, 5, 1) are not the same block
    for (size_t i = 0; i < r.blocks.size() * VOXELS_PER_BLOCK; ++i) observed += countOf(r, i / VOXELS_PER_BLOCK, uint32_t(i % VOXELS_PER_BLOCK)) > 0;
    EXPECT_EQ(summary.blocks, r.blocks.size());
    EXPECT_EQ(summary.sharedBlocks, shared);
    EXPECT_EQ(summary.corners, observed);
}

TEST(MapAlgebra, BlocksOfOneInputOnlyAreCopiedAsTheyAre) {
    const Maps m = threeMaps(true);
    const map::MapData r = merged({{"a.vkmap", &m.a}, {"b.vkmap", &m.b}});
    const auto inA = blockAt(m.a), inB = blockAt(m.b);
    size_t copied = 0;
    for (size_t k = 0; k < r.blocks.size(); ++k) {
        const Coord c{r.blocks[k].x, r.blocks[k].y, r.blocks[k].z};
        const bool a = inA.count(c), b = inB.count(c);
        if (a && b) continue;
        const map::MapData& from = a ? m.a : m.b;
        const size_t fb = a ? inA.at(c) : inB.at(c);
        ++copied;
        for (uint32_t t : {kSums, kCounts, kColors})
            for (uint32_t i = 0; i < VOXELS_PER_BLOCK; ++i)
                ASSERT_EQ(words(r, t)[k * VOXELS_PER_BLOCK + i], words(from, t)[fb * VOXELS_PER_BLOCK + i])
                    << map::tagName(t) << " block " << k << " corner " << i;
        EXPECT_EQ(r.blocks[k].hashStamp, from.blocks[fb].hashStamp);
        EXPECT_EQ(r.blocks[k].retypeMask, (std::array<uint32_t, MASK_WORDS>{})) << "no mesh: nothing to retype";
    }
    EXPECT_EQ(copied, 4u + 3u);   // A's (3, -1, 2), (-2, 5, 0), (7, 7, -3), (0, 1, 0); B's (-4, 0, 9), (2, 2, 2), (-2, 5, 1)
}

TEST(MapAlgebra, TheUnionHasPoolIndicesInCoordinateOrder) {
    const Maps m = threeMaps(false);
    const map::MapData r = merged({{"b.vkmap", &m.b}, {"c.vkmap", &m.c}, {"a.vkmap", &m.a}});
    std::vector<std::tuple<int32_t, int32_t, int32_t>> want;   // z, y, x
    for (const auto* x : {&m.a, &m.b, &m.c})
        for (const map::Block& b : x->blocks) want.emplace_back(b.z, b.y, b.x);
    std::sort(want.begin(), want.end());
    want.erase(std::unique(want.begin(), want.end()), want.end());
    ASSERT_EQ(r.blocks.size(), want.size());
    for (size_t k = 0; k < want.size(); ++k) {
        EXPECT_EQ(r.blocks[k].index, k);
        EXPECT_EQ((std::tuple{r.blocks[k].z, r.blocks[k].y, r.blocks[k].x}), want[k]) << k;
    }
    EXPECT_EQ(r.blockFree.firstUntouched, want.size());
    EXPECT_TRUE(r.blockFree.holes.empty());
}

TEST(MapAlgebra, FrameNumbersAddUp) {
    const Maps m = threeMaps(false);
    const map::MapData r = merged({{"a.vkmap", &m.a}, {"b.vkmap", &m.b}, {"c.vkmap", &m.c}});
    EXPECT_EQ(r.frameNumber, 7u + 13u + 5u);
    EXPECT_EQ(r.framesIntegrated, 7u + 12u + 5u);
    EXPECT_EQ(r.lastPush.frameNumber, r.frameNumber);
    EXPECT_EQ(r.lastPush.imageSize, 320u | 240u << 16) << "the last push of the input with the most frames (B)";
    EXPECT_EQ(r.retryPending, 0u);
}

TEST(MapAlgebra, TheSumParsesAndHoldsNoMesh) {
    Maps m = threeMaps(true);
    // Inputs with a mesh (a vertex on an edge, a triangle chunk): none of it is carried over.
    m.a.vertices.resize(1);
    m.a.vertices[0] = {0.1f, 0.2f, 0.3f, 1, 0, 0, 1, 4};
    m.a.vertexOwners = {3};
    m.a.vertexFree = {1, {}};
    words(m.a, kEdges[0])[3] = 0;
    m.a.counters.verticesInUse = 1, m.a.counters.vertexHighWater = 1;
    ASSERT_NO_THROW(map::parse(map::serialize(m.a), "a.vkmap"));
    const map::MapData r0 = merged({{"a.vkmap", &m.a}, {"b.vkmap", &m.b}, {"c.vkmap", &m.c}});
    const map::MapData r = map::parse(map::serialize(r0), "sum.vkmap");
    EXPECT_EQ(map::serialize(r), map::serialize(r0));
    const size_t n = r.blocks.size();
    EXPECT_EQ(n, 10u);   // 6 + 5 + 4, less 2 + 2 + 2 held twice, plus (1, 0, 0) held three times
    EXPECT_EQ(r.features, map::FEATURE_INCREMENTAL_MESH | map::FEATURE_COLOR);
    for (uint32_t t : {kSums, kCounts, kColors, kCubes, kEdges[0], kEdges[1], kEdges[2]}) ASSERT_EQ(words(r, t).size(), n * VOXELS_PER_BLOCK);
    EXPECT_TRUE(std::all_of(words(r, kCubes).begin(), words(r, kCubes).end(), [](uint32_t w) { return w == 0; }));
    for (uint32_t t : kEdges)
        EXPECT_TRUE(std::all_of(words(r, t).begin(), words(r, t).end(), [](uint32_t w) { return w == EMPTY_SLOT; })) << map::tagName(t);
    EXPECT_TRUE(r.vertices.empty());
    EXPECT_TRUE(r.vertexOwners.empty());
    EXPECT_TRUE(r.chunkWords.empty());
    EXPECT_EQ(r.vertexFree.firstUntouched, 0u);
    EXPECT_EQ(r.chunkFree.firstUntouched, 0u);
    Counters want{};
    want.blocksInUse = want.liveBlockCount = want.hashEntries = uint32_t(n);
    EXPECT_EQ(std::memcmp(&r.counters, &want, sizeof(Counters)), 0) << "counters of a map with no mesh";
    EXPECT_EQ(r.counters.blocksInUse, n);
    EXPECT_EQ(r.counters.liveBlockCount, n);
    EXPECT_EQ(r.counters.hashEntries, n);
    // Capacities: the largest of the inputs'.
    EXPECT_EQ(r.capacities.blocks, 128u);
    EXPECT_EQ(r.capacities.hashSlots, 1024u);
    EXPECT_EQ(r.capacities.vertices, 128u);
    EXPECT_EQ(r.capacities.chunks, 96u);
    EXPECT_EQ(r.settings.imageWidth, 320u);
    EXPECT_EQ(r.settings.imageHeight, 240u);
}

// More blocks than the inputs' capacities: the sum's pool and hash hold them.
TEST(MapAlgebra, CapacitiesGrowToHoldTheUnion) {
    std::vector<Coord> ca, cb;
    for (int i = 0; i < 40; ++i) ca.push_back({i, 0, 0}), cb.push_back({i, 1, 0});
    map::MapData a = randomMap(5, 3, ca, false), b = randomMap(6, 3, cb, false);
    a.capacities.blocks = b.capacities.blocks = 64;
    a.capacities.hashSlots = b.capacities.hashSlots = 64;
    const map::MapData r = map::parse(map::serialize(merged({{"a.vkmap", &a}, {"b.vkmap", &b}})), "sum.vkmap");
    EXPECT_EQ(r.blocks.size(), 80u);
    EXPECT_GE(r.capacities.blocks, 80u);
    EXPECT_GE(r.capacities.hashSlots, 160u);
    EXPECT_EQ(std::popcount(r.capacities.hashSlots), 1);
}

TEST(MapAlgebra, TheOrderOfTwoInputsDoesNotChangeAByte) {
    for (bool color : {false, true}) {
        const Maps m = threeMaps(color);
        ASSERT_EQ(m.a.saveId, 0u);
        ASSERT_EQ(m.b.saveId, 0u);
        const std::string ab = map::serialize(merged({{"a.vkmap", &m.a}, {"b.vkmap", &m.b}}));
        const std::string ba = map::serialize(merged({{"b.vkmap", &m.b}, {"a.vkmap", &m.a}}));
        EXPECT_TRUE(ab == ba) << "colour " << color << ": merge(A, B) and merge(B, A) differ";
        // Same frame count: the larger last push, whichever comes first.
        map::MapData c = m.c;
        c.frameNumber = m.a.frameNumber, c.framesIntegrated = m.a.framesIntegrated, c.lastPush.frameNumber = m.a.frameNumber;
        c.lastPush.imageSize = 1u | 1u << 16;
        EXPECT_TRUE(map::serialize(merged({{"a.vkmap", &m.a}, {"c.vkmap", &c}})) == map::serialize(merged({{"c.vkmap", &c}, {"a.vkmap", &m.a}})))
            << "colour " << color << ": inputs with as many frames";
        // Settings that are not compared (the caller's, and the recency of an average colour) differ.
        map::MapData d = m.b;
        d.settings.lockFree = 1, d.settings.vertexUpdate = 1, d.settings.growCapacities = 0, d.settings.colorRecency = 0.5f;
        EXPECT_TRUE(map::serialize(merged({{"a.vkmap", &m.a}, {"d.vkmap", &d}})) == map::serialize(merged({{"d.vkmap", &d}, {"a.vkmap", &m.a}})))
            << "colour " << color << ": inputs whose caller settings differ";
    }
}

TEST(MapAlgebra, AddingInStepsIsAssociative) {
    const Maps m = threeMaps(true);
    const map::MapData ab = merged({{"a.vkmap", &m.a}, {"b.vkmap", &m.b}});
    const map::MapData bc = merged({{"b.vkmap", &m.b}, {"c.vkmap", &m.c}});
    const map::MapData left = merged({{"ab.vkmap", &ab}, {"c.vkmap", &m.c}});
    const map::MapData right = merged({{"a.vkmap", &m.a}, {"bc.vkmap", &bc}});
    const map::MapData all = merged({{"a.vkmap", &m.a}, {"b.vkmap", &m.b}, {"c.vkmap", &m.c}});
    for (const map::MapData* x : {&right, &all}) {
        ASSERT_EQ(left.blocks.size(), x->blocks.size());
        for (size_t k = 0; k < left.blocks.size(); ++k) {
            EXPECT_EQ(left.blocks[k].x, x->blocks[k].x);
            EXPECT_EQ(left.blocks[k].y, x->blocks[k].y);
            EXPECT_EQ(left.blocks[k].z, x->blocks[k].z);
            EXPECT_EQ(left.blocks[k].index, x->blocks[k].index);
            EXPECT_EQ(left.blocks[k].hashStamp, x->blocks[k].hashStamp);
        }
        EXPECT_TRUE(words(left, kSums) == words(*x, kSums));
        EXPECT_TRUE(words(left, kCounts) == words(*x, kCounts));
        EXPECT_EQ(left.frameNumber, x->frameNumber);
        EXPECT_EQ(left.framesIntegrated, x->framesIntegrated);
        size_t differ = 0;
        for (size_t i = 0; i < words(left, kColors).size(); ++i) {
            const uint32_t l = words(left, kColors)[i], o = words(*x, kColors)[i];
            ASSERT_EQ(hasVoxelColor(l), hasVoxelColor(o)) << i;
            const ColorChannels cl = unpackVoxelColor(l), co = unpackVoxelColor(o);
            for (int ch = 0; ch < 3; ++ch)
                ASSERT_LE(std::abs(cl[ch] - co[ch]), 1.0f) << "block " << i / VOXELS_PER_BLOCK << " corner " << i % VOXELS_PER_BLOCK << " channel " << ch;
            differ += l != o;
        }
        EXPECT_GT(words(left, kColors).size(), differ);
    }
}

// One shared block at (0, 0, 0) of a colour map, corner `corner` set in each input.
struct ColorPair {
    map::MapData a, b;
};
ColorPair colorPair() {
    ColorPair p{randomMap(1, 4, {{0, 0, 0}, {5, 0, 0}}, true), randomMap(2, 4, {{0, 0, 0}}, true)};
    return p;
}
void setCorner(map::MapData& m, size_t block, uint32_t corner, float count, int32_t sum, uint32_t color) {
    const size_t at = block * VOXELS_PER_BLOCK + corner;
    words(m, kCounts)[at] = std::bit_cast<uint32_t>(count);
    words(m, kSums)[at] = uint32_t(sum);
    if (m.corners(kColors)) words(m, kColors)[at] = color;
}

TEST(MapAlgebra, ColourIsTheWeightedMeanRounded) {
    ColorPair p = colorPair();
    const size_t a = blockAt(p.a).at({0, 0, 0}), b = blockAt(p.b).at({0, 0, 0});
    setCorner(p.a, a, 17, 3, 5000, packVoxelColor(100, 200, 1020));
    setCorner(p.b, b, 17, 1, -300, packVoxelColor(2, 203, 1));
    // red (3 * 100 + 2) / 4 = 75.5 -> 76, green (600 + 203) / 4 = 200.75 -> 201, blue (3060 + 1) / 4 = 765.25 -> 765.
    const uint32_t want = packVoxelColor(76, 201, 765);
    for (bool swap : {false, true}) {
        const map::MapData r = swap ? merged({{"b.vkmap", &p.b}, {"a.vkmap", &p.a}}) : merged({{"a.vkmap", &p.a}, {"b.vkmap", &p.b}});
        const size_t k = blockAt(r).at({0, 0, 0});
        const uint32_t got = words(r, kColors)[k * VOXELS_PER_BLOCK + 17];
        const ColorChannels c = unpackVoxelColor(got);
        EXPECT_EQ(got, want) << "got " << c[0] << " " << c[1] << " " << c[2];
        EXPECT_EQ(sumOf(r, k, 17), 4700);
        EXPECT_EQ(countOf(r, k, 17), 4.0f);
    }
}

TEST(MapAlgebra, AColourOnOneSideOnlyIsTaken) {
    ColorPair p = colorPair();
    const size_t a = blockAt(p.a).at({0, 0, 0}), b = blockAt(p.b).at({0, 0, 0});
    const uint32_t x = packVoxelColor(1, 513, 1019), y = packVoxelColor(1020, 0, 7);
    setCorner(p.a, a, 0, 5, 100, x);        // observed with colour ...
    setCorner(p.b, b, 0, 4, -100, 0);       // ... and observed without (frames with no colour image)
    setCorner(p.a, a, 1, 2, 10, x);         // observed with colour ...
    setCorner(p.b, b, 1, 0, 0, 0);          // ... and never
    setCorner(p.a, a, 2, 0, 0, 0);          // never ...
    setCorner(p.b, b, 2, 9, -9, y);         // ... and with colour
    setCorner(p.a, a, 3, 0, 0, 0);          // neither has a colour
    setCorner(p.b, b, 3, 3, 0, 0);
    // A colour on a corner whose count was taken back to 0 (its frames de-integrated): kept when nothing else has one.
    const uint32_t z = packVoxelColor(300, 301, 302);
    setCorner(p.a, a, 4, 0, 0, z);
    setCorner(p.b, b, 4, 0, 0, 0);
    setCorner(p.a, a, 5, 0, 0, z);
    setCorner(p.b, b, 5, 2, 1, y);
    for (bool swap : {false, true}) {
        const map::MapData r = swap ? merged({{"b.vkmap", &p.b}, {"a.vkmap", &p.a}}) : merged({{"a.vkmap", &p.a}, {"b.vkmap", &p.b}});
        const size_t k = blockAt(r).at({0, 0, 0});
        const uint32_t* c = &words(r, kColors)[k * VOXELS_PER_BLOCK];
        EXPECT_EQ(c[0], x) << swap;
        EXPECT_EQ(c[1], x) << swap;
        EXPECT_EQ(c[2], y) << swap;
        EXPECT_EQ(c[3], 0u) << swap;
        EXPECT_EQ(c[4], z) << swap;
        EXPECT_EQ(c[5], y) << swap;
        EXPECT_EQ(countOf(r, k, 0), 9.0f);
    }
}

// ---- refusals ----------------------------------------------------------------------------------------------

std::string mergeError(const map::MapData& a, const map::MapData& b) {
    return errorMessageOf([&] { merged({{"a.vkmap", &a}, {"b.vkmap", &b}}); });
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Every setting of settingDifferences' table: it reports it (its option, both values), and merge refuses the two
// maps naming the option (the bounded, baseline and recent-colour ones are refused as such, before the comparison).
TEST(MapAlgebra, EverySettingThatDiffersIsRefusedNamingItsOption) {
    struct Case {
        const char* option;        // settingDifferences' option
        std::function<void(map::Settings&)> both, other;   // applied to both maps / to B only
        const char* mergeNames;    // what merge's message must hold
        double a, b;
        const char* file = "b.vkmap";   // the input it names (a bounded or recent-colour A is refused first)
    };
    const auto none = [](map::Settings&) {};
    const std::vector<Case> cases = {
        {"--voxel", none, [](map::Settings& s) { s.voxelSize = 0.05f; }, "--voxel", 0.04f, 0.05f},
        {"--trunc", none, [](map::Settings& s) { s.truncVoxels = 3; }, "--trunc", 4, 3},
        {"--max-weight", none, [](map::Settings& s) { s.maxWeight = 64; }, "--max-weight", 255, 64},
        {"--min-weight", none, [](map::Settings& s) { s.minMeshWeight = 2; }, "--min-weight", 1, 2},
        {"--alloc-stride", none, [](map::Settings& s) { s.allocationStride = 1; }, "--alloc-stride", 2, 1},
        {"--alloc-tiles, --alloc-pixels", none, [](map::Settings& s) { s.allocationTiles = 1; }, "--alloc-tiles", 2, 1},
        {"--alloc-tiles, --alloc-pixels", none, [](map::Settings& s) { s.allocationTiles = 0; }, "--alloc-pixels", 2, 0},
        {"--mode", none, [](map::Settings& s) { s.incrementalMesh = 0; }, "--mode", 1, 0},
        {"--refine", none, [](map::Settings& s) { s.refine = 1, s.refineEpsilonVoxels = 0.5f; }, "--refine", 0, 1},
        {"--refine-eps", [](map::Settings& s) { s.refine = 1, s.refineEpsilonVoxels = 0.5f; },
         [](map::Settings& s) { s.refineEpsilonVoxels = 0.25f; }, "--refine-eps", 0.5, 0.25},
        {"--keep-radius", none, [](map::Settings& s) { s.keepRadius = 3; }, "--keep-radius", 0, 3},
        {"--recycle", none, [](map::Settings& s) { s.recycle = 1, s.recycleAfterFrames = 30, s.starveWeight = 2; }, "--recycle", 0, 1},
        {"--recycle-after", [](map::Settings& s) { s.recycle = 1, s.recycleAfterFrames = 30, s.starveWeight = 2; },
         [](map::Settings& s) { s.recycleAfterFrames = 60; }, "--recycle", 30, 60, "a.vkmap"},
        {"--starve-weight", [](map::Settings& s) { s.recycle = 1, s.recycleAfterFrames = 30, s.starveWeight = 2; },
         [](map::Settings& s) { s.starveWeight = 4; }, "--recycle", 2, 4, "a.vkmap"},
        {"--no-color, --color-mode", none, [](map::Settings& s) { s.colorMode = COLOR_MODE_AVERAGE; }, "--color-mode", 0, 1},
        {"--color-recency", [](map::Settings& s) { s.colorMode = COLOR_MODE_RECENT, s.colorRecency = 0.2f; },
         [](map::Settings& s) { s.colorRecency = 0.5f; }, "--color-mode", 0.2f, 0.5f, "a.vkmap"},
    };
    std::vector<std::string> options;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.option);
        options.push_back(c.option);
        map::MapData a = randomMap(7, 3, {{0, 0, 0}, {1, 0, 0}}, false), b = randomMap(8, 3, {{1, 0, 0}}, false);
        c.both(a.settings), c.both(b.settings), c.other(b.settings);
        for (map::MapData* m : {&a, &b}) {
            syncFeatures(*m);
            if (m->settings.colorMode && !m->corners(kColors))
                m->cornerArrays.push_back({kColors, std::vector<uint32_t>(m->blocks.size() * VOXELS_PER_BLOCK, 0)});
        }
        const std::vector<map::SettingDifference> d = map::settingDifferences(a.settings, b.settings, map::AllocationRules::Exact);
        ASSERT_EQ(d.size(), 1u);
        EXPECT_EQ(d[0].option, c.option);
        EXPECT_FLOAT_EQ(float(d[0].a), float(c.a));
        EXPECT_FLOAT_EQ(float(d[0].b), float(c.b));
        const std::string e = mergeError(a, b);
        EXPECT_TRUE(has(e, c.mergeNames)) << e;
        EXPECT_TRUE(has(e, c.file)) << e;
    }
    // Every row of the table is covered: a pair of settings differing in everything lists as many.
    map::Settings x = baseSettings(false), y = baseSettings(false);
    x.refine = 1, x.recycle = 1, x.colorMode = COLOR_MODE_RECENT;
    y = x;
    y.voxelSize = 1, y.truncVoxels = 1, y.maxWeight = 1, y.minMeshWeight = 5, y.allocationStride = 7, y.allocationTiles = 0;
    y.incrementalMesh = 0, y.refine = 0, y.refineEpsilonVoxels = 3, y.keepRadius = 1, y.recycle = 0, y.recycleAfterFrames = 9;
    y.starveWeight = 9, y.colorMode = 3, y.colorRecency = 0.9f;
    const std::vector<map::SettingDifference> all = map::settingDifferences(x, y, map::AllocationRules::Exact);
    std::vector<std::string> allOptions;
    for (const map::SettingDifference& d : all) allOptions.push_back(d.option);
    std::sort(options.begin(), options.end());
    options.erase(std::unique(options.begin(), options.end()), options.end());
    std::sort(allOptions.begin(), allOptions.end());
    EXPECT_EQ(allOptions, options);
}

// The refinement epsilon is compared only with refinement on (and the recycling and recency details likewise).
TEST(MapAlgebra, SettingsThatDoNotApplyAreNotCompared) {
    map::MapData a = randomMap(7, 3, {{0, 0, 0}}, false), b = randomMap(8, 3, {{1, 0, 0}}, false);
    a.settings.refineEpsilonVoxels = 0.5f, b.settings.refineEpsilonVoxels = 0.25f;   // refinement off
    a.settings.recycleAfterFrames = 10, b.settings.recycleAfterFrames = 20;        // recycling off
    a.settings.starveWeight = 1, b.settings.starveWeight = 2;
    a.settings.colorRecency = 0.2f, b.settings.colorRecency = 0.7f;                // colour off
    a.settings.lockFree = 1, a.settings.vertexUpdate = 1, b.settings.growCapacities = 0;   // the caller's
    a.settings.imageWidth = 640;
    EXPECT_TRUE(map::settingDifferences(a.settings, b.settings, map::AllocationRules::Exact).empty());
    EXPECT_NO_THROW(merged({{"a.vkmap", &a}, {"b.vkmap", &b}}));
    b.settings.refine = a.settings.refine = 1;
    const auto d = map::settingDifferences(a.settings, b.settings, map::AllocationRules::Exact);
    ASSERT_EQ(d.size(), 1u);
    EXPECT_EQ(d[0].option, "--refine-eps");
}

TEST(MapAlgebra, BoundedMapsAreRefused) {
    for (int which : {0, 1}) {
        map::MapData a = randomMap(7, 3, {{0, 0, 0}}, false), b = randomMap(8, 3, {{0, 0, 0}}, false);
        // Bounded in both, alike: not a difference of settings, still refused.
        for (map::MapData* m : {&a, &b}) {
            if (which == 0) m->settings.keepRadius = 4;
            else m->settings.recycle = 1, m->settings.recycleAfterFrames = 30, m->settings.starveWeight = 2;
        }
        ASSERT_TRUE(map::settingDifferences(a.settings, b.settings, map::AllocationRules::Exact).empty());
        const std::string e = mergeError(a, b);
        EXPECT_TRUE(has(e, "--keep-radius")) << e;
        EXPECT_TRUE(has(e, "--recycle")) << e;
        EXPECT_TRUE(has(e, "a.vkmap")) << e;
        EXPECT_TRUE(has(e, "bounded")) << e;
        // Also a single input is refused.
        EXPECT_TRUE(has(errorMessageOf([&] { merged({{"a.vkmap", &a}}); }), "--keep-radius"));
    }
}

TEST(MapAlgebra, RecentColourIsRefused) {
    map::MapData a = randomMap(7, 3, {{0, 0, 0}}, true), b = randomMap(8, 3, {{0, 0, 0}}, true);
    b.settings.colorMode = a.settings.colorMode = COLOR_MODE_RECENT;
    const std::string e = mergeError(a, b);
    EXPECT_TRUE(has(e, "a.vkmap")) << e;
    EXPECT_TRUE(has(e, "recent")) << e;
    EXPECT_TRUE(has(e, "--color-mode")) << e;
}

TEST(MapAlgebra, BaselineMapsAreRefused) {
    map::MapData a = randomMap(7, 3, {{0, 0, 0}}, false), b = randomMap(8, 3, {{0, 0, 0}}, false);
    b.settings.incrementalMesh = 0;
    syncFeatures(b);
    ASSERT_NO_THROW(map::parse(map::serialize(b), "b.vkmap"));
    std::string e = mergeError(a, b);
    EXPECT_TRUE(has(e, "b.vkmap")) << e;
    EXPECT_TRUE(has(e, "--mode baseline")) << e;
    a.settings.incrementalMesh = 0;   // both
    syncFeatures(a);
    e = mergeError(a, b);
    EXPECT_TRUE(has(e, "--mode baseline")) << e;
}

TEST(MapAlgebra, ADifferentDepthRangeIsRefused) {
    map::MapData a = randomMap(7, 3, {{0, 0, 0}}, false), b = randomMap(8, 3, {{0, 0, 0}}, false);
    b.settings.maxDepth = 4;
    ASSERT_TRUE(map::settingDifferences(a.settings, b.settings, map::AllocationRules::Exact).empty()) << "the caller's, in that table";
    std::string e = mergeError(a, b);
    EXPECT_TRUE(has(e, "--max-depth")) << e;
    EXPECT_TRUE(has(e, "b.vkmap")) << e;
    b.settings.maxDepth = a.settings.maxDepth, b.settings.minDepth = 0.3f;
    e = mergeError(a, b);
    EXPECT_TRUE(has(e, "--max-depth")) << e;
}

TEST(MapAlgebra, ACornerPastTheLargestCountIsRefusedNamingItsBlock) {
    map::MapData a = randomMap(7, 3, {{0, 0, 0}, {-3, 4, 9}}, false), b = randomMap(8, 3, {{-3, 4, 9}}, false);
    const size_t ab = blockAt(a).at({-3, 4, 9});
    const float half = float((SDF_MAX_COUNT + 1) / 2);   // 262144: twice is one too many
    setCorner(a, ab, 100, half, -int32_t(kSteps) * 1000, 0);
    setCorner(b, 0, 100, half - 1, 123456, 0);
    // Exactly SDF_MAX_COUNT: accepted.
    const map::MapData r = merged({{"a.vkmap", &a}, {"b.vkmap", &b}});
    EXPECT_EQ(countOf(r, blockAt(r).at({-3, 4, 9}), 100), float(SDF_MAX_COUNT));
    setCorner(b, 0, 100, half, 123456, 0);
    const std::string e = mergeError(a, b);
    EXPECT_TRUE(has(e, "block (-3, 4, 9)")) << e;
    EXPECT_TRUE(has(e, "corner 100")) << e;
    EXPECT_TRUE(has(e, std::to_string(SDF_MAX_COUNT + 1))) << e;
}

TEST(MapAlgebra, ACorruptInputIsRefusedNamingTheFile) {
    const map::MapData a = randomMap(7, 3, {{0, 0, 0}}, false);
    const map::MapData clean = randomMap(8, 3, {{2, 0, 0}}, false);
    auto refused = [&](float count, int64_t sum) {
        map::MapData b = clean;
        setCorner(b, 0, 42, count, int32_t(sum), 0);
        return mergeError(a, b);
    };
    for (auto [count, sum] : std::vector<std::pair<float, int64_t>>{{1.5f, 0}, {2, 2 * kSteps + 1}, {2, -2 * kSteps - 1}, {0, 1}, {-1, 0},
                                                                     {std::numeric_limits<float>::quiet_NaN(), 0}, {float(SDF_MAX_COUNT + 1), 0}}) {
        const std::string e = refused(count, sum);
        EXPECT_TRUE(has(e, "b.vkmap")) << count << " " << sum << ": " << e;
        EXPECT_TRUE(has(e, "block (2, 0, 0)")) << e;
        EXPECT_TRUE(has(e, "corner 42")) << e;
    }
    // At the bound: what fusion can give.
    for (auto [count, sum] : std::vector<std::pair<float, int64_t>>{{2, 2 * kSteps}, {2, -2 * kSteps}, {0, 0}}) {
        map::MapData b = clean;
        setCorner(b, 0, 42, count, int32_t(sum), 0);
        EXPECT_NO_THROW(merged({{"a.vkmap", &a}, {"b.vkmap", &b}})) << count << " " << sum;
    }
}

TEST(MapAlgebra, ASectionMergingCannotAddIsRefused) {
    const map::MapData a = randomMap(7, 3, {{0, 0, 0}}, false);
    map::MapData b = randomMap(8, 3, {{0, 0, 0}}, false);
    b.cornerArrays.push_back({map::tag("msgn"), std::vector<uint32_t>(VOXELS_PER_BLOCK, 0)});
    const std::string e = mergeError(a, b);
    EXPECT_TRUE(has(e, "b.vkmap")) << e;
    EXPECT_TRUE(has(e, "'msgn'")) << e;
}

// A colour map (FEATURE_COLOR, colour mode average) with no 'colr' section, which map::parse accepts, after one that
// has it (this once read the missing section through a null pointer).
TEST(MapAlgebra, AColourMapWithoutItsColourSectionIsRefused) {
    const map::MapData a = randomMap(7, 3, {{0, 0, 0}}, true);
    map::MapData b = randomMap(8, 3, {{0, 0, 0}}, true);
    b.cornerArrays.erase(std::remove_if(b.cornerArrays.begin(), b.cornerArrays.end(), [](const map::CornerArray& x) { return x.tag == kColors; }),
                         b.cornerArrays.end());
    b = map::parse(map::serialize(b), "b.vkmap");
    const std::string e = mergeError(a, b);
    EXPECT_TRUE(has(e, "b.vkmap")) << e;
    EXPECT_TRUE(has(e, "colr")) << e;
}

TEST(MapAlgebra, TilesRulesAreEqualOnOrOffButNotExactly) {
    map::Settings a = baseSettings(false), b = baseSettings(false);
    a.allocationTiles = 1, b.allocationTiles = 2;
    EXPECT_TRUE(map::settingDifferences(a, b, map::AllocationRules::OnOrOff).empty());
    const auto exact = map::settingDifferences(a, b, map::AllocationRules::Exact);
    ASSERT_EQ(exact.size(), 1u);
    EXPECT_EQ(exact[0].option, "--alloc-tiles, --alloc-pixels");
    EXPECT_EQ(exact[0].a, 1);
    EXPECT_EQ(exact[0].b, 2);
    // By tiles or pixel by pixel differs either way.
    b.allocationTiles = 0;
    for (auto rules : {map::AllocationRules::OnOrOff, map::AllocationRules::Exact}) {
        const auto d = map::settingDifferences(a, b, rules);
        ASSERT_EQ(d.size(), 1u);
        EXPECT_EQ(d[0].option, "--alloc-tiles, --alloc-pixels");
        EXPECT_EQ(d[0].b, 0);
    }
}

// ---- FrameStore::absorb --------------------------------------------------------------------------------------

Pose poseAt(uint32_t i) {
    Pose T = Pose::Identity();
    const double c = std::cos(0.3 * i + 0.1), s = std::sin(0.3 * i + 0.1);
    T(0, 0) = c, T(0, 1) = -s, T(1, 0) = s, T(1, 1) = c;
    T(0, 3) = 0.123456789 * i, T(1, 3) = -1.0 / 3.0, T(2, 3) = 2.5e-3 * i + 1e-300;
    return T;
}

// A tiny frame: depth quantised as TUM's PNGs give it, a hole, and two values == would not tell apart (-0, NaN).
StoredFrame makeFrame(uint32_t index, uint32_t seed, bool withColor = true) {
    const int w = 7, h = 5;
    Rng rng{seed};
    StoredFrame f;
    f.index = index;
    f.timestamp = 1305031229.528784 + 0.0333 * seed;
    f.intrinsics = {5.173f + seed, 5.165f, 3.186f, 2.553f, w, h};
    f.pose = poseAt(seed);
    f.depth = {w, h, std::vector<float>(size_t(w) * h)};
    for (float& d : f.depth.meters) d = float(rng.between(2000, 20000)) / 5000.0f;
    f.depth.meters[3] = 0;
    f.depth.meters[4] = -0.0f;
    f.depth.meters[5] = std::bit_cast<float>(0x7FC12345u);
    if (withColor) {
        f.color = {w, h, std::vector<uint8_t>(size_t(w) * h * 3)};
        for (uint8_t& v : f.color.rgb) v = uint8_t(rng.next());
    }
    return f;
}

void expectSameFrame(const StoredFrame& got, const StoredFrame& want, uint32_t index) {
    EXPECT_EQ(got.index, index);
    EXPECT_EQ(std::bit_cast<uint64_t>(got.timestamp), std::bit_cast<uint64_t>(want.timestamp)) << index;
    EXPECT_EQ(std::memcmp(&got.intrinsics, &want.intrinsics, sizeof(Intrinsics)), 0) << index;
    EXPECT_EQ(std::memcmp(got.pose.data(), want.pose.data(), sizeof(double) * 16), 0) << index;
    ASSERT_EQ(got.depth.width, want.depth.width);
    ASSERT_EQ(got.depth.height, want.depth.height);
    ASSERT_EQ(got.depth.meters.size(), want.depth.meters.size());
    EXPECT_EQ(std::memcmp(got.depth.meters.data(), want.depth.meters.data(), 4 * want.depth.meters.size()), 0) << index;
    EXPECT_EQ(got.color.empty(), want.color.empty()) << index;
    EXPECT_EQ(got.color.rgb, want.color.rgb) << index;
    if (!want.color.empty()) {
        EXPECT_EQ(got.color.width, want.color.width);
    }
}

// Frames of a store, by index, as added.
struct Stored {
    FrameStore store;
    std::map<uint32_t, StoredFrame> frames;
};
Stored storeWith(const std::vector<uint32_t>& indices, uint32_t seed, FrameStoreOptions options = {}) {
    Stored s{FrameStore(std::move(options)), {}};
    for (uint32_t i : indices) {
        StoredFrame f = makeFrame(i, seed + i, (seed + i) % 3 != 1);
        s.store.add(f);
        s.frames.emplace(i, std::move(f));
    }
    return s;
}

void expectHolds(const FrameStore& store, const std::map<uint32_t, StoredFrame>& frames, uint32_t offset = 0) {
    std::vector<uint32_t> want;
    for (const auto& [i, f] : frames) want.push_back(i + offset);
    std::vector<uint32_t> got = store.indices();
    for (uint32_t i : got)
        if (std::find(want.begin(), want.end(), i) == want.end()) ADD_FAILURE() << "frame " << i << " should not be there";
    for (const auto& [i, f] : frames) {
        ASSERT_TRUE(store.contains(i + offset)) << i + offset;
        expectSameFrame(store.get(i + offset), f, i + offset);
        EXPECT_EQ(std::memcmp(store.pose(i + offset).data(), f.pose.data(), sizeof(double) * 16), 0);
        EXPECT_EQ(std::bit_cast<uint64_t>(store.timestamp(i + offset)), std::bit_cast<uint64_t>(f.timestamp));
    }
}

TEST(FrameStoreAbsorb, EveryFrameKeepsEveryBitUnderItsIndexPlusTheOffset) {
    Stored x = storeWith({0, 1, 2}, 10), y = storeWith({0, 1, 7}, 50);
    const FrameStoreStats sx = x.store.stats(), sy = y.store.stats();
    x.store.absorb(std::move(y.store), 100);
    EXPECT_EQ(x.store.indices(), (std::vector<uint32_t>{0, 1, 2, 100, 101, 107}));
    for (const auto& [i, f] : x.frames) expectSameFrame(x.store.get(i), f, i);
    for (const auto& [i, f] : y.frames) expectSameFrame(x.store.get(i + 100), f, i + 100);
    const FrameStoreStats s = x.store.stats();
    EXPECT_EQ(s.frames, 6u);
    EXPECT_EQ(s.rawBytes, sx.rawBytes + sy.rawBytes);
    EXPECT_EQ(s.compressedBytes, sx.compressedBytes + sy.compressedBytes) << "nothing recompressed";
    EXPECT_EQ(y.store.size(), 0u);
    EXPECT_EQ(y.store.stats().compressedBytes, 0u);
    EXPECT_EQ(y.store.stats().rawBytes, 0u);
    // Without an offset, into an empty store.
    FrameStore z;
    Stored w = storeWith({3, 9}, 80);
    z.absorb(std::move(w.store));
    expectHolds(z, w.frames);
}

TEST(FrameStoreAbsorb, ACollisionThrowsBeforeAnythingMoves) {
    Stored x = storeWith({0, 1, 2, 20}, 10), y = storeWith({3, 4, 18}, 50);   // + 2: 5, 6, then 20, in both
    std::string e = errorMessageOf([&] { x.store.absorb(std::move(y.store), 2); });
    EXPECT_TRUE(has(e, "frame 20")) << e;
    EXPECT_TRUE(has(e, "in both stores")) << e;
    expectHolds(x.store, x.frames);
    expectHolds(y.store, y.frames);
    // An index past 2^32 - 1 (the last of the frames): nothing moves either.
    Stored big = storeWith({5, 6, std::numeric_limits<uint32_t>::max() - 3}, 90);
    e = errorMessageOf([&] { x.store.absorb(std::move(big.store), 4); });
    EXPECT_TRUE(has(e, "passes the largest index")) << e;
    expectHolds(x.store, x.frames);
    expectHolds(big.store, big.frames);
    // And a store cannot absorb itself.
    e = errorMessageOf([&] { x.store.absorb(std::move(x.store), 100); });
    EXPECT_TRUE(has(e, "itself")) << e;
    expectHolds(x.store, x.frames);
}

TEST(FrameStoreAbsorb, ASpilledStoreIsAbsorbedAndItsSpillFolderRemoved) {
    const fs::path dir = test::makeTempDir("map_algebra_absorb");
    FrameStoreOptions spillAll;
    spillAll.memoryBudgetBytes = 1;   // every frame spills
    spillAll.spillFolder = (dir / "y").string();
    Stored y = storeWith({0, 1, 2, 3}, 50, spillAll);
    ASSERT_EQ(y.store.stats().framesSpilled, 4u);
    ASSERT_FALSE(fs::is_empty(dir / "y"));
    // Into a store whose budget holds its own two frames and the first absorbed one, and spills the rest to a
    // folder of its own.
    const Stored own = storeWith({0, 1}, 10), first = storeWith({0}, 50);
    FrameStoreOptions some;
    some.memoryBudgetBytes = own.store.stats().compressedBytes + first.store.stats().compressedBytes;
    some.spillFolder = (dir / "x").string();
    Stored x = storeWith({0, 1}, 10, some);
    x.store.absorb(std::move(y.store), 10);
    EXPECT_TRUE(fs::exists(dir / "y")) << "the folder given is left";
    EXPECT_TRUE(fs::is_empty(dir / "y")) << "the source's own spill folder is removed";
    EXPECT_EQ(y.store.size(), 0u);
    EXPECT_EQ(y.store.stats().bytesOnDisk, 0u);
    const FrameStoreStats s = x.store.stats();
    EXPECT_EQ(s.frames, 6u);
    EXPECT_EQ(s.framesInMemory, 3u);
    EXPECT_EQ(s.framesSpilled, 3u);
    EXPECT_EQ(s.bytesInMemory, some.memoryBudgetBytes);
    EXPECT_EQ(x.store.indices(), (std::vector<uint32_t>{0, 1, 10, 11, 12, 13}));
    for (const auto& [i, f] : x.frames) expectSameFrame(x.store.get(i), f, i);
    for (const auto& [i, f] : y.frames) expectSameFrame(x.store.get(i + 10), f, i + 10);
    size_t files = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir / "x")) files += e.is_regular_file();
    EXPECT_EQ(files, s.framesSpilled);
}

}  // namespace
}  // namespace vkmesh
