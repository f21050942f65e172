// The .vkmap file (docs/MAPFILE.md): everything a GPU volume holds between two frames, so that a map outlives
// the process. This is the host side only (no Vulkan): the in-memory form (MapData), its serialisation, and a
// parser that checks everything (checksums, sizes, every index against the pools it points into) before
// anything reaches a GPU, and a reader of part of a file (BlockReader: the blocks of a box, for maps one process
// should not hold). src/gpu/map_file.cpp fills a MapData from a GpuVolume and back, asking each component for its
// sections.
//
// Little-endian throughout; a fixed header, then sections, each with a 4-character tag, a kind, the size of
// one record and the number of records, so a reader can skip what it does not know and a record whose size
// changed (Vertex growing a colour) is detected instead of misread.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "shared_layout.h"

namespace vkmesh::map {

constexpr std::array<char, 8> kMagic = {'V', 'K', 'M', 'A', 'P', '\r', '\n', '\x1a'};
// Version 2: a TSDF corner is an integer step sum and a count (exact fusion; shared_layout.h "A TSDF corner"),
// and Counters grew a per-frame group. Version 1 maps held float running averages, which cannot be taken
// apart again: they are refused with what to do (re-fuse the dataset).
constexpr uint32_t kVersion = 2;
constexpr uint32_t kHeaderBytes = 80;
constexpr uint32_t kSectionHeaderBytes = 24;

// Feature flags (header): what the map holds beyond version 1's TSDF + shared-vertex mesh. A reader refuses a
// map with a flag it does not know.
constexpr uint32_t FEATURE_INCREMENTAL_MESH = 1u << 0;   // the mesh sections describe a live incremental mesh
constexpr uint32_t FEATURE_COLOR = 1u << 1;              // per-corner colour ('colr' section) fused (Settings::colorMode != 0)
constexpr uint32_t kKnownFeatures = FEATURE_INCREMENTAL_MESH | FEATURE_COLOR;

// Section kinds: how the record count is to be read.
enum class SectionKind : uint32_t {
    Single = 1,     // exactly one record (a struct)
    PerBlock = 2,   // one record per live block, in the order of the block table (section 'BLKS')
    List = 3,       // any number of records
};

// A 4-character tag as the little-endian uint32 it is stored as ("sdf_" -> 's' in the lowest byte).
constexpr uint32_t tag(const char (&s)[5]) {
    return uint32_t(uint8_t(s[0])) | uint32_t(uint8_t(s[1])) << 8 | uint32_t(uint8_t(s[2])) << 16 | uint32_t(uint8_t(s[3])) << 24;
}
std::string tagName(uint32_t t);

// The settings a map was fused with: the command line's (or GpuVolumeConfig's) values that change results.
struct Settings {
    float voxelSize = 0, truncVoxels = 0, maxWeight = 0, minDepth = 0, maxDepth = 0;
    uint32_t allocationStride = 0;
    float minMeshWeight = 0;
    uint32_t incrementalMesh = 1;   // MeshMode::Incremental
    uint32_t refine = 0;
    float refineEpsilonVoxels = 0;
    uint32_t lockFree = 0, vertexUpdate = 0;
    float keepRadius = 0;
    uint32_t recycle = 0, recycleAfterFrames = 0;
    float starveWeight = 0, hashRebuildTombstoneFraction = 0;
    uint32_t imageWidth = 0, imageHeight = 0;
    uint32_t growCapacities = 1, touchedFollowsPool = 1;
    uint32_t colorMode = 0;          // ColorFusion: 0 off, 1 average, 2 recent (docs/COLOR.md)
    float colorRecency = 0.2f;
    // Allocation by tiles (VolumeParams::allocationTiles) with rules 1 or 2 (its allocationTileRules, shared_layout.h
    // ALLOC_TILE_RULES); 0: pixel by pixel. Maps written before allocation by tiles hold 0 in this (then reserved)
    // word: they were allocated pixel by pixel, which de-integrating their frames again must repeat.
    uint32_t allocationTiles = 0;
};

// Capacities when saved (the loader may use larger ones).
struct Capacities {
    uint32_t blocks = 0, hashSlots = 0, touched = 0, retype = 0, vertices = 0, chunks = 0;
};

// A free stack (entries [0, top) free indices, popped from the top) of a pool of `capacity`: at its bottom the
// indices never used, capacity - 1 down to `firstUntouched` (growFreeStack keeps them there), then `holes`,
// the indices freed since, bottom to top. Every index >= firstUntouched is free, so the pool's records need
// only be stored below it, and a larger capacity on load just extends the bottom run.
struct FreeStack {
    uint32_t firstUntouched = 0;
    std::vector<uint32_t> holes;
    // The stack entries for a pool of `capacity` (>= firstUntouched).
    std::vector<uint32_t> entries(uint32_t capacity) const;
    // The compact form of a downloaded stack.
    static FreeStack fromEntries(const std::vector<uint32_t>& entries, uint32_t capacity);
};

// One live block: coordinate, index in the pool (kept: vertex owners and the block list refer to it), the
// last frame that touched it (its hash stamp) and the cubes waiting to be retyped.
struct Block {
    int32_t x = 0, y = 0, z = 0;
    uint32_t index = 0;
    uint32_t hashStamp = 0;
    std::array<uint32_t, gpu::MASK_WORDS> retypeMask{};
};
constexpr uint32_t kBlockRecordBytes = 20 + 4 * gpu::MASK_WORDS;

// A per-corner (per-cube) array of the live blocks: VOXELS_PER_BLOCK 32-bit words per block, in the order of
// MapData::blocks. BlockStore's (TSDF sdf, weight, ...) and CubeMesh's (cube state, edge slots x/y/z).
struct CornerArray {
    uint32_t tag = 0;
    std::vector<uint32_t> words;
};

struct MapData {
    uint32_t version = kVersion;
    uint32_t features = 0;
    Settings settings;
    Capacities capacities;
    uint32_t frameNumber = 0, framesIntegrated = 0, retryPending = 0;
    // A number drawn anew at every save, written into the frame store saved beside the map too (docs/CORRECTION.md):
    // a store is only used with the very map it was saved with.
    uint64_t saveId = 0;
    gpu::Counters counters{};   // as after the last frame (free-stack tops recomputed on load)
    gpu::FramePush lastPush{};  // the last frame's push constants (whole-volume passes reuse its frame number)
    std::vector<Block> blocks;
    std::vector<CornerArray> cornerArrays;   // in the order the components list them
    FreeStack blockFree, vertexFree, chunkFree;
    std::vector<gpu::Vertex> vertices;        // the heap below vertexFree.firstUntouched
    std::vector<uint32_t> vertexOwners;       // the same range
    std::vector<uint32_t> chunkWords;         // CHUNK_WORDS per chunk below chunkFree.firstUntouched

    const CornerArray* corners(uint32_t t) const;
};

// Byte layout (docs/MAPFILE.md). serialize() checks nothing; parse() checks everything and throws vkmesh::Error
// naming `name` and the problem.
std::string serialize(const MapData& map);
MapData parse(std::string_view bytes, const std::string& name);

MapData readFile(const std::filesystem::path& path);
// Written to `path`.tmp and renamed, so a crash never leaves a half-written map under the name.
void writeFile(const std::filesystem::path& path, const MapData& map);

// Which blocks (by block coordinate) a partial read or a merge keeps.
using BlockFilter = std::function<bool(int32_t x, int32_t y, int32_t z)>;

// A box of block coordinates, both corners included.
struct BlockBox {
    std::array<int32_t, 3> lo{}, hi{};
    bool contains(int32_t x, int32_t y, int32_t z) const {
        return lo[0] <= x && x <= hi[0] && lo[1] <= y && y <= hi[1] && lo[2] <= z && z <= hi[2];
    }
};

// Reads a map file a part at a time, for maps one process should not hold (tiles made on separate workers:
// api/map_merge.h, mergeTiles). The sections are stored uncompressed, back to back, each announcing its size, so
// the reader seeks: opening it reads the header, the small single-record sections and the block table (kept as
// 16 bytes a block: coordinate and hash stamp, against 14 kB of corner data); read() then reads, from every
// per-block section, the records of the blocks it keeps and nothing else. Memory is bounded by what is kept,
// not by the file.
//
// What read() returns is the TSDF of those blocks as a map with no mesh (what merging and a rebuild need, as
// map::merge's result): the blocks in file order with pool indices 0..N-1, the TSDF's per-block arrays ('sdf_',
// 'wght', 'colr' and any other but the mesh's) as stored, the mesh's ('cube', 'edgx', 'edgy', 'edgz') empty and
// not read, no vertices or triangles, the counters of a map with no mesh; settings, frame numbers, save id and
// capacities are the file's.
//
// Checks (vkmesh::Error naming the file): everything parse() checks of the header, the section table, the settings
// and the block table (coordinates in the key range and distinct, stamps not after the last frame). Not the CRC of
// the sections, which needs every byte of the file: verifyChecksum() streams the file through it (one buffer of
// memory), for a caller that wants it once per file rather than once per part. The corners read are checked by
// whoever adds them (map::merge refuses counts and sums no fusion gives).
class BlockReader {
public:
    explicit BlockReader(const std::filesystem::path& path);

    struct TableEntry {
        int32_t x = 0, y = 0, z = 0;
        uint32_t hashStamp = 0;
    };
    const std::string& name() const { return name_; }
    // Every live block's coordinate, in file order.
    const std::vector<TableEntry>& blocks() const { return table_; }
    // Settings, features, capacities, frame numbers, counters, last push: the file's (no blocks, no arrays).
    const MapData& header() const { return header_; }

    // The blocks inside `box` (lo <= hi on every axis, inside the key range [-2^20, 2^20); otherwise an error naming
    // the file and the box), or those `keep` accepts.
    MapData read(const BlockBox& box);
    MapData read(const BlockFilter& keep);

    // The sections' CRC-32 against the header's (throws "<file>: checksum mismatch ..." when it differs).
    void verifyChecksum();

private:
    struct PerBlockSection {
        uint32_t tag = 0;
        uint64_t offset = 0;   // of its first record, from the start of the file
    };
    void readAt(uint64_t offset, void* out, size_t bytes);

    std::filesystem::path path_;
    std::string name_;
    std::ifstream in_;
    uint64_t fileBytes_ = 0;
    uint32_t payloadCrc_ = 0;
    MapData header_;
    std::vector<TableEntry> table_;
    std::vector<PerBlockSection> perBlock_;   // in file order (MapData::cornerArrays' order)
};

// CRC-32 (IEEE 802.3, the zlib / PNG one: reflected polynomial 0xEDB88320, initial and final xor 0xFFFFFFFF).
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0);

}  // namespace vkmesh::map
