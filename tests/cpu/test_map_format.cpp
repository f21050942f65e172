// The .vkmap parser and writer (src/core/map_format.h, docs/MAPFILE.md) on the host alone: a map survives
// serialisation exactly; every kind of bad file is a vkmesh::Error naming the file and the problem.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <string>

#include "core/map_format.h"
#include "core/types.h"

namespace vkmesh {
namespace {

using namespace gpu;

// A small, consistent map: 2 live blocks (pool indices 0 and 2; 1 freed), 3 vertices (1 free), 1 chunk.
map::MapData smallMap() {
    map::MapData m;
    m.features = map::FEATURE_INCREMENTAL_MESH;
    m.settings.voxelSize = 0.04f;
    m.settings.truncVoxels = 4, m.settings.maxWeight = 255, m.settings.minDepth = 0.1f, m.settings.maxDepth = 6;
    m.settings.allocationStride = 2, m.settings.minMeshWeight = 1, m.settings.imageWidth = 160, m.settings.imageHeight = 120;
    m.capacities = {16, 1024, 16, 1024, 64, 64};
    m.frameNumber = 7, m.framesIntegrated = 7;
    m.counters.blocksInUse = 2, m.counters.verticesInUse = 2, m.counters.vertexHighWater = 3;
    m.lastPush.frameNumber = 7;
    m.blocks = {{-1, 2, 3, 0, 7, {}}, {4, -5, 6, 2, 5, {}}};
    m.blocks[1].retypeMask[3] = 0x80000001u;
    for (const char* t : {"sdf_", "wght", "cube", "edgx", "edgy", "edgz"}) {
        map::CornerArray a{map::tag({t[0], t[1], t[2], t[3], 0}), std::vector<uint32_t>(2 * VOXELS_PER_BLOCK, 0)};
        if (t[0] == 'e') std::fill(a.words.begin(), a.words.end(), EMPTY_SLOT);
        m.cornerArrays.push_back(a);
    }
    m.cornerArrays[0].words[5] = 0x3f800000u;        // sdf 1.0
    m.cornerArrays[2].words[9] = 1u << CUBE_CHUNK_SHIFT | 3u;   // cube 9 of block 0: type 3, chunk 0
    m.cornerArrays[3].words[9] = 0;                   // its +x edge: vertex 0
    m.blockFree = {3, {1}};
    m.vertexFree = {3, {2}};
    m.chunkFree = {1, {}};
    m.vertices.resize(3);
    m.vertices[0] = {0.1f, 0.2f, 0.3f, 1, 0, 0, 1, 4};
    m.vertices[1] = {0.4f, 0.5f, 0.6f, 1, 0, 1, 0, 5};
    m.vertices[2].refcount = DEAD_REFCOUNT;
    m.vertexOwners = {27, 30, 0};
    m.chunkWords.assign(CHUNK_WORDS, INVALID_INDEX);
    m.chunkWords[0] = 0, m.chunkWords[1] = 1, m.chunkWords[2] = 0;
    return m;
}

std::string errorOf(const std::string& bytes) {
    try {
        map::parse(bytes, "bad.vkmap");
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// Changes a header word and recomputes the header checksum (a file written by another version, not a corrupt one).
std::string withHeaderWord(std::string bytes, size_t offset, uint32_t value) {
    std::memcpy(bytes.data() + offset, &value, 4);
    const uint32_t crc = map::crc32(bytes.data(), map::kHeaderBytes - 4);
    std::memcpy(bytes.data() + map::kHeaderBytes - 4, &crc, 4);
    return bytes;
}

TEST(MapFormat, Crc32IsTheStandardOne) {
    EXPECT_EQ(map::crc32("123456789", 9), 0xCBF43926u);   // the CRC-32/ISO-HDLC check value
    EXPECT_EQ(map::crc32("", 0), 0u);
}

TEST(MapFormat, RoundTripKeepsEverything) {
    const map::MapData m = smallMap();
    const std::string bytes = map::serialize(m);
    ASSERT_EQ(bytes.substr(0, 5), "VKMAP");
    const map::MapData r = map::parse(bytes, "small.vkmap");
    EXPECT_EQ(r.version, map::kVersion);
    EXPECT_EQ(r.features, m.features);
    EXPECT_EQ(r.settings.voxelSize, 0.04f);
    EXPECT_EQ(r.settings.imageWidth, 160u);
    EXPECT_EQ(r.capacities.hashSlots, 1024u);
    EXPECT_EQ(r.frameNumber, 7u);
    EXPECT_EQ(std::memcmp(&r.counters, &m.counters, sizeof(Counters)), 0);
    EXPECT_EQ(r.lastPush.frameNumber, 7u);
    ASSERT_EQ(r.blocks.size(), 2u);
    EXPECT_EQ(r.blocks[0].x, -1);
    EXPECT_EQ(r.blocks[1].y, -5);
    EXPECT_EQ(r.blocks[1].index, 2u);
    EXPECT_EQ(r.blocks[1].hashStamp, 5u);
    EXPECT_EQ(r.blocks[1].retypeMask[3], 0x80000001u);
    ASSERT_EQ(r.cornerArrays.size(), 6u);
    for (size_t i = 0; i < 6; ++i) {
        EXPECT_EQ(r.cornerArrays[i].tag, m.cornerArrays[i].tag);
        EXPECT_EQ(r.cornerArrays[i].words, m.cornerArrays[i].words);
    }
    ASSERT_NE(r.corners(map::tag("wght")), nullptr);
    EXPECT_EQ(r.blockFree.firstUntouched, 3u);
    EXPECT_EQ(r.blockFree.holes, std::vector<uint32_t>{1});
    ASSERT_EQ(r.vertices.size(), 3u);
    EXPECT_EQ(std::memcmp(r.vertices.data(), m.vertices.data(), 3 * sizeof(Vertex)), 0);
    EXPECT_EQ(r.vertexOwners, m.vertexOwners);
    EXPECT_EQ(r.chunkWords, m.chunkWords);
    EXPECT_EQ(map::serialize(r), bytes);   // and writes back byte for byte
}

// The settings' last word, reserved (0) before allocation by tiles: maps written then read as allocated pixel by
// pixel, a map allocated by tiles says so, and any other value is refused.
TEST(MapFormat, AllocationModeReadsZeroAsPixelByPixel) {
    map::MapData m = smallMap();
    EXPECT_EQ(map::parse(map::serialize(m), "old.vkmap").settings.allocationTiles, 0u) << "a map written before tiles";
    m.settings.allocationTiles = 1;   // by tiles, the first rules
    EXPECT_EQ(map::parse(map::serialize(m), "tiles.vkmap").settings.allocationTiles, 1u);
    m.settings.allocationTiles = 2;   // by tiles, the current rules
    EXPECT_EQ(map::parse(map::serialize(m), "tiles.vkmap").settings.allocationTiles, 2u);
    m.settings.allocationTiles = 3;
    const std::string e = errorOf(map::serialize(m));
    EXPECT_NE(e.find("allocation mode 3"), std::string::npos) << e;
}

TEST(MapFormat, FreeStacksKeepOnlyTheHoles) {
    // Capacity 8: never used 7..4 at the bottom, then 1 and 3 freed.
    const std::vector<uint32_t> entries = {7, 6, 5, 4, 1, 3};
    const map::FreeStack f = map::FreeStack::fromEntries(entries, 8);
    EXPECT_EQ(f.firstUntouched, 4u);
    EXPECT_EQ(f.holes, (std::vector<uint32_t>{1, 3}));
    EXPECT_EQ(f.entries(8), entries);
    // A larger pool on load: the new indices join the untouched run, as growFreeStack puts them.
    EXPECT_EQ(f.entries(10), (std::vector<uint32_t>{9, 8, 7, 6, 5, 4, 1, 3}));
    // Everything in use.
    EXPECT_EQ(map::FreeStack::fromEntries({}, 8).firstUntouched, 8u);
}

TEST(MapFormat, TruncatedFilesAreRefused) {
    const std::string bytes = map::serialize(smallMap());
    for (size_t size : {size_t(0), size_t(5), size_t(40), size_t(map::kHeaderBytes), size_t(map::kHeaderBytes + 30), bytes.size() / 2,
                        bytes.size() - 1}) {
        const std::string e = errorOf(bytes.substr(0, size));
        EXPECT_NE(e.find("bad.vkmap"), std::string::npos) << size << ": " << e;
        EXPECT_TRUE(e.find("truncated") != std::string::npos || e.find("magic") != std::string::npos) << size << ": " << e;
    }
    EXPECT_NE(errorOf(bytes + "x").find("trailing"), std::string::npos);
}

TEST(MapFormat, WrongMagicIsRefused) {
    std::string bytes = map::serialize(smallMap());
    bytes[0] = 'P';
    EXPECT_NE(errorOf(bytes).find("wrong magic"), std::string::npos) << errorOf(bytes);
    EXPECT_NE(errorOf("ply\nformat binary_little_endian 1.0\n").find("not a vkmesh map"), std::string::npos);
}

TEST(MapFormat, NewerVersionIsRefused) {
    map::MapData m = smallMap();
    m.version = map::kVersion + 1;
    const std::string e = errorOf(map::serialize(m));
    EXPECT_NE(e.find("version " + std::to_string(map::kVersion + 1) + " is newer"), std::string::npos) << e;
}

// Version 1 held float running averages (before exact fusion): refused with what it is and what to do.
TEST(MapFormat, VersionOneIsRefusedWithWhatToDo) {
    map::MapData m = smallMap();
    m.version = 1;
    const std::string e = errorOf(map::serialize(m));
    EXPECT_NE(e.find("bad.vkmap"), std::string::npos) << e;
    EXPECT_NE(e.find("version 1"), std::string::npos) << e;
    EXPECT_NE(e.find("vkmesh fuse DATASET --save"), std::string::npos) << e;
}

TEST(MapFormat, ChecksumMismatchIsRefused) {
    std::string bytes = map::serialize(smallMap());
    bytes[bytes.size() - 7] ^= 0x10;   // a bit of the last chunk
    std::string e = errorOf(bytes);
    EXPECT_NE(e.find("checksum mismatch"), std::string::npos) << e;
    bytes = map::serialize(smallMap());
    bytes[24] ^= 0x01;   // the header's voxel size
    e = errorOf(bytes);
    EXPECT_NE(e.find("header checksum mismatch"), std::string::npos) << e;
}

TEST(MapFormat, UnknownFeaturesAndRecordSizesAreRefused) {
    map::MapData m = smallMap();
    m.features |= 1u << 7;   // a feature of a later build
    std::string e = errorOf(map::serialize(m));
    EXPECT_NE(e.find("features this build of vkmesh does not know"), std::string::npos) << e;
    // Colour in the flags but not in the settings (or the other way round): inconsistent.
    m = smallMap();
    m.features |= map::FEATURE_COLOR;
    m.settings.colorMode = 0;
    e = errorOf(map::serialize(m));
    EXPECT_NE(e.find("colour mode in the settings disagrees"), std::string::npos) << e;
    m.settings.colorMode = 7;
    e = errorOf(map::serialize(m));
    EXPECT_NE(e.find("colour mode 7"), std::string::npos) << e;
    // A Vertex of another size (an older build's 32 bytes, or a later one's): detected, not misread.
    e = errorOf(withHeaderWord(map::serialize(smallMap()), 28, 32));
    EXPECT_NE(e.find("vertex records of 32 bytes"), std::string::npos) << e;
}

TEST(MapFormat, IndicesOutsideThePoolsAreRefused) {
    auto refused = [](const std::function<void(map::MapData&)>& change, const std::string& expected) {
        map::MapData m = smallMap();
        change(m);
        const std::string e = errorOf(map::serialize(m));
        EXPECT_NE(e.find(expected), std::string::npos) << "expected '" << expected << "', got: " << e;
    };
    refused([](map::MapData& m) { m.cornerArrays[4].words[0] = 3; }, "outside the heap");           // edge slot
    refused([](map::MapData& m) { m.cornerArrays[2].words[0] = 2u << CUBE_CHUNK_SHIFT; }, "triangle chunk outside");
    refused([](map::MapData& m) { m.chunkWords[3] = 99; }, "outside the heap");                      // triangle
    refused([](map::MapData& m) { m.blocks[1].index = 1; }, "used twice or both used and free");      // a free block
    refused([](map::MapData& m) { m.blocks[1].index = 0; }, "used twice");
    refused([](map::MapData& m) { m.blocks[1].index = 9; }, "never used");
    refused([](map::MapData& m) { m.blocks[1].x = -1, m.blocks[1].y = 2, m.blocks[1].z = 3; }, "repeats a block coordinate");
    refused([](map::MapData& m) { m.blocks[0].x = 1 << 21; }, "key range");
    refused([](map::MapData& m) { m.vertexFree.holes = {2, 2}; }, "twice");
    refused([](map::MapData& m) { m.vertexFree.firstUntouched = 65; }, "beyond the capacity");
    refused([](map::MapData& m) { m.vertexOwners.pop_back(); }, "owners");
    refused([](map::MapData& m) { m.vertexOwners[0] = 16 * 512 * 3; }, "owner edge outside");
    refused([](map::MapData& m) { m.vertices[2].refcount = 0; }, "on the free stack but alive");
    refused([](map::MapData& m) { m.vertices[1].refcount = DEAD_REFCOUNT; }, "free but not on the free stack");
    refused([](map::MapData& m) { m.cornerArrays[4].words[0] = 2; }, "which is free");
    refused([](map::MapData& m) { m.cornerArrays[2].words[10] = 1u << CUBE_CHUNK_SHIFT; }, "belongs to two cubes");
    refused([](map::MapData& m) { m.capacities.hashSlots = 1000; }, "not a power of two");
    refused([](map::MapData& m) { m.counters.vertexHighWater = 1000; }, "exceed the capacities");
}

}  // namespace
}  // namespace vkmesh
