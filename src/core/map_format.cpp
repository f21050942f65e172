#include "core/map_format.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <tuple>

#include "core/fuzzing.h"
#include "core/types.h"

namespace vkmesh::map {

using namespace gpu;

namespace {

static_assert(std::endian::native == std::endian::little, "the map format is little-endian; a big-endian host needs byte swaps here");
static_assert(sizeof(Counters) % 4 == 0 && sizeof(FramePush) % 4 == 0 && sizeof(Vertex) % 4 == 0);

constexpr uint32_t kStateBytes = 24;   // version 2: + the save id
constexpr uint32_t kSettings = tag("SETT"), kState = tag("STAT"), kCounters = tag("CNTR"), kPush = tag("PUSH"),
                   kBlocks = tag("BLKS"), kBlockFree = tag("BFRE"), kVertices = tag("VERT"), kOwners = tag("VOWN"),
                   kVertexFree = tag("VFRE"), kChunks = tag("CHNK"), kChunkFree = tag("CFRE");
constexpr uint32_t kCornerRecordBytes = 4 * VOXELS_PER_BLOCK;
constexpr uint32_t kChunkRecordBytes = 4 * CHUNK_WORDS;
constexpr uint32_t kSettingsWords = 24;   // the fields of Settings, in order (docs/MAPFILE.md)

// ---- writing ----------------------------------------------------------------------------------------

struct Writer {
    std::string out;
    void bytes(const void* p, size_t n) { out.append(static_cast<const char*>(p), n); }
    void u32(uint32_t v) { bytes(&v, 4); }
    void f32(float v) { bytes(&v, 4); }
    void u64(uint64_t v) { bytes(&v, 8); }
    void section(uint32_t t, SectionKind kind, uint32_t recordBytes, uint64_t count) {
        u32(t);
        u32(uint32_t(kind));
        u32(recordBytes);
        u32(0);
        u64(count);
    }
};

void writeSettings(Writer& w, const Settings& s) {
    w.f32(s.voxelSize), w.f32(s.truncVoxels), w.f32(s.maxWeight), w.f32(s.minDepth), w.f32(s.maxDepth);
    w.u32(s.allocationStride), w.f32(s.minMeshWeight), w.u32(s.incrementalMesh), w.u32(s.refine), w.f32(s.refineEpsilonVoxels);
    w.u32(s.lockFree), w.u32(s.vertexUpdate), w.f32(s.keepRadius), w.u32(s.recycle), w.u32(s.recycleAfterFrames);
    w.f32(s.starveWeight), w.f32(s.hashRebuildTombstoneFraction), w.u32(s.imageWidth), w.u32(s.imageHeight);
    w.u32(s.growCapacities), w.u32(s.touchedFollowsPool), w.u32(s.colorMode), w.f32(s.colorRecency), w.u32(s.allocationTiles);
}

void writeFreeStack(Writer& w, uint32_t t, const FreeStack& f) {
    w.section(t, SectionKind::List, 4, 1 + f.holes.size());
    w.u32(f.firstUntouched);
    w.bytes(f.holes.data(), f.holes.size() * 4);
}

// ---- reading ----------------------------------------------------------------------------------------

struct Section {
    uint32_t tag;
    SectionKind kind;
    uint32_t recordBytes;
    uint64_t count;
    std::string_view data;   // parse(): the records; BlockReader: empty (read from the file at `offset`)
    uint64_t offset = 0;     // of the records, from the start of the file
};

class Reader {
public:
    Reader(std::string_view bytes, const std::string& name) : bytes_(bytes), name_(name) {}
    [[noreturn]] void fail(const std::string& problem) const { throw Error(name_ + ": " + problem); }
    uint32_t u32(size_t at) const { return word<uint32_t>(at); }
    float f32(size_t at) const { return word<float>(at); }
    uint64_t u64(size_t at) const { return word<uint64_t>(at); }

private:
    template <typename T>
    T word(size_t at) const {
        T v;
        std::memcpy(&v, bytes_.data() + at, sizeof(T));
        return v;
    }
    std::string_view bytes_;
    const std::string& name_;
};

template <typename T>
std::vector<T> copyRecords(const Section& s) {
    std::vector<T> out(s.data.size() / sizeof(T));
    if (!out.empty()) std::memcpy(out.data(), s.data.data(), out.size() * sizeof(T));
    return out;
}

// ---- checks parse() and BlockReader share ----------------------------------------------------------

struct HeaderFields {
    uint64_t payloadBytes = 0;
    uint32_t payloadCrc = 0;
    float voxelSize = 0;
};

// The fixed header: `head` holds the file's first bytes (the whole header, when the file is that long), `fileBytes`
// is the file's size. Fills version, features and capacities; the payload's checksum is the caller's to check (it
// needs the payload).
HeaderFields parseHeader(std::string_view head, uint64_t fileBytes, const std::string& name, MapData& map) {
    Reader r(head, name);
    if (head.size() < kMagic.size() || std::memcmp(head.data(), kMagic.data(), kMagic.size()) != 0)
        r.fail("not a vkmesh map (wrong magic; a .vkmap file starts with \"VKMAP\\r\\n\\x1a\")");
    if (fileBytes < kHeaderBytes || head.size() < kHeaderBytes)
        r.fail("truncated: " + std::to_string(fileBytes) + " bytes, shorter than the " + std::to_string(kHeaderBytes) + "-byte header");
    map.version = r.u32(8);
    if (map.version > kVersion)
        r.fail("map format version " + std::to_string(map.version) + " is newer than this build of vkmesh reads (version " +
               std::to_string(kVersion) + "); use a newer vkmesh");
    if (map.version == 0) r.fail("map format version 0 is not a valid version");
    if (map.version == 1)
        r.fail("map format version 1 holds float running-average TSDF values, written by a vkmesh before exact fusion; this "
               "vkmesh reads version " + std::to_string(kVersion) + " (integer sums that can be de-integrated, docs/MAPFILE.md): "
               "fuse the dataset again with this vkmesh (vkmesh fuse DATASET --save map.vkmap)");
    if (r.u32(12) != kHeaderBytes) r.fail("header size " + std::to_string(r.u32(12)) + " is not " + std::to_string(kHeaderBytes));
    // A fuzzer cannot forge checksums: under the fuzz targets (only) they are not checked, so that it reaches the
    // checks behind them (core/fuzzing.h).
    if (!fuzzing::active() && crc32(head.data(), kHeaderBytes - 4) != r.u32(kHeaderBytes - 4))
        r.fail("header checksum mismatch (the file is corrupt)");
    HeaderFields h;
    h.payloadBytes = r.u64(64);
    h.payloadCrc = r.u32(72);
    if (fileBytes - kHeaderBytes < h.payloadBytes)
        r.fail("truncated: the header announces " + std::to_string(kHeaderBytes + h.payloadBytes) + " bytes, the file has " +
               std::to_string(fileBytes));
    if (fileBytes - kHeaderBytes > h.payloadBytes)
        r.fail(std::to_string(fileBytes - kHeaderBytes - h.payloadBytes) + " bytes of trailing garbage after the map");
    map.features = r.u32(16);
    if (map.features & ~kKnownFeatures) {
        std::string what = (map.features & FEATURE_COLOR) ? "colour (FEATURE_COLOR)" : "flags " + std::to_string(map.features & ~kKnownFeatures);
        r.fail("the map uses features this build of vkmesh does not know: " + what);
    }
    if (r.u32(20) != BLOCK_SIDE || r.u32(36) != VOXELS_PER_BLOCK)
        r.fail("blocks of " + std::to_string(r.u32(20)) + "^3 (" + std::to_string(r.u32(36)) + " corners); this build uses " +
               std::to_string(BLOCK_SIDE) + "^3");
    if (r.u32(28) != sizeof(Vertex))
        r.fail("vertex records of " + std::to_string(r.u32(28)) + " bytes; this build's Vertex has " + std::to_string(sizeof(Vertex)));
    if (r.u32(32) != kChunkRecordBytes)
        r.fail("triangle chunks of " + std::to_string(r.u32(32)) + " bytes; this build's have " + std::to_string(kChunkRecordBytes));
    h.voxelSize = r.f32(24);
    Capacities& cap = map.capacities;
    cap = {r.u32(40), r.u32(44), r.u32(48), r.u32(52), r.u32(56), r.u32(60)};
    if (cap.blocks == 0 || cap.blocks > (1u << 30)) r.fail("block capacity " + std::to_string(cap.blocks) + " is outside [1, 2^30]");
    if (cap.hashSlots == 0 || (cap.hashSlots & (cap.hashSlots - 1)) != 0)
        r.fail("hash capacity " + std::to_string(cap.hashSlots) + " is not a power of two");
    if (cap.vertices < 64 || cap.vertices >= CLAIMED_SLOT) r.fail("vertex capacity " + std::to_string(cap.vertices) + " is outside [64, 2^32 - 2)");
    if (cap.chunks < 64 || cap.chunks >= (1u << (32 - CUBE_CHUNK_SHIFT)) - 1)
        r.fail("triangle chunk capacity " + std::to_string(cap.chunks) + " is outside [64, 2^23 - 1)");
    if (cap.touched == 0 || cap.retype == 0) r.fail("touched and retype capacities must be at least 1");
    return h;
}

// A section header (24 bytes at `p`) whose records start at file offset `offset`, with `available` bytes of the
// payload left after the header. The records themselves are the caller's.
Section parseSectionHeader(const char* p, uint64_t offset, uint64_t available, const std::string& name) {
    Section s{};
    uint32_t kind;
    std::memcpy(&s.tag, p, 4);
    std::memcpy(&kind, p + 4, 4);
    std::memcpy(&s.recordBytes, p + 8, 4);
    std::memcpy(&s.count, p + 16, 8);
    s.offset = offset;
    const std::string label = name + ": section '" + tagName(s.tag) + "'";
    if (kind < 1 || kind > 3) throw Error(label + " has unknown kind " + std::to_string(kind));
    s.kind = SectionKind(kind);
    if (s.recordBytes == 0 || s.recordBytes % 4 != 0) throw Error(label + " has records of " + std::to_string(s.recordBytes) + " bytes");
    if (s.count > available / s.recordBytes)
        throw Error(label + " announces " + std::to_string(s.count) + " records of " + std::to_string(s.recordBytes) +
                    " bytes, more than the file holds");
    if (s.kind == SectionKind::Single && s.count != 1) throw Error(label + " must hold exactly one record");
    return s;
}

// The section `t`, which must be there with that kind and record size.
const Section& needSection(const std::map<uint32_t, Section>& sections, uint32_t t, SectionKind kind, uint32_t recordBytes,
                           const std::string& name) {
    auto it = sections.find(t);
    if (it == sections.end()) throw Error(name + ": section '" + tagName(t) + "' is missing");
    const Section& s = it->second;
    if (s.kind != kind) throw Error(name + ": section '" + tagName(t) + "' has the wrong kind");
    if (s.recordBytes != recordBytes)
        throw Error(name + ": section '" + tagName(t) + "' has records of " + std::to_string(s.recordBytes) + " bytes; this build's are " +
                    std::to_string(recordBytes));
    return s;
}

// Settings, state, counters and last push: `bytesOf` gives a (present, checked) section's records.
void parseSingles(const std::map<uint32_t, Section>& sections, const std::function<std::string(const Section&)>& bytesOf,
                  float headerVoxel, const std::string& name, MapData& map) {
    auto fail = [&](const std::string& problem) { throw Error(name + ": " + problem); };
    const std::string settings = bytesOf(needSection(sections, kSettings, SectionKind::Single, 4 * kSettingsWords, name));
    {
        const char* p = settings.data();
        auto u = [&](int i) { uint32_t v; std::memcpy(&v, p + 4 * i, 4); return v; };
        auto f = [&](int i) { float v; std::memcpy(&v, p + 4 * i, 4); return v; };
        Settings& s = map.settings;
        s = {f(0), f(1), f(2), f(3), f(4), u(5), f(6), u(7), u(8), f(9), u(10), u(11), f(12), u(13), u(14), f(15), f(16),
             u(17), u(18), u(19), u(20), u(21), f(22), u(23)};
        if (s.allocationTiles > 2)
            fail("allocation mode " + std::to_string(s.allocationTiles) +
                 " is not 0 (pixel by pixel), 1 or 2 (by tiles, with the first or the current rules)");
        if (s.colorMode > 2) fail("colour mode " + std::to_string(s.colorMode) + " is not 0 (off), 1 (average) or 2 (recent)");
        if (s.colorMode != 0 && !(s.colorRecency > 0 && s.colorRecency <= 1))
            fail("colour recency " + std::to_string(s.colorRecency) + " is outside (0, 1]");
        if (!(std::isfinite(s.voxelSize) && s.voxelSize > 0)) fail("voxel size is not a positive number");
        if (s.voxelSize != headerVoxel) fail("the header's voxel size disagrees with the settings section");
        if (s.imageWidth == 0 || s.imageHeight == 0 || s.imageWidth > 65535 || s.imageHeight > 65535)
            fail("image size " + std::to_string(s.imageWidth) + "x" + std::to_string(s.imageHeight) + " is not supported");
    }
    if ((map.settings.incrementalMesh != 0) != ((map.features & FEATURE_INCREMENTAL_MESH) != 0))
        fail("the mesh mode in the settings disagrees with the header's feature flags");
    if ((map.settings.colorMode != 0) != ((map.features & FEATURE_COLOR) != 0))
        fail("the colour mode in the settings disagrees with the header's feature flags");
    const std::string state = bytesOf(needSection(sections, kState, SectionKind::Single, kStateBytes, name));
    {
        Reader sr(state, name);
        map.frameNumber = sr.u32(0), map.framesIntegrated = sr.u32(4), map.retryPending = sr.u32(8);
        map.saveId = sr.u64(16);
        if (map.framesIntegrated > map.frameNumber) fail("more frames integrated than frame numbers used");
    }
    std::memcpy(&map.counters, bytesOf(needSection(sections, kCounters, SectionKind::Single, sizeof(Counters), name)).data(), sizeof(Counters));
    std::memcpy(&map.lastPush, bytesOf(needSection(sections, kPush, SectionKind::Single, sizeof(FramePush), name)).data(), sizeof(FramePush));
}

// Block record i of the block table: the checks that need nothing but the record and the last frame number (the
// pool indices are checked against the free stack by parse()).
Block parseBlockRecord(const char* p, size_t i, uint32_t frameNumber, const std::string& name) {
    Block b;
    std::memcpy(&b.x, p, 4), std::memcpy(&b.y, p + 4, 4), std::memcpy(&b.z, p + 8, 4);
    std::memcpy(&b.index, p + 12, 4), std::memcpy(&b.hashStamp, p + 16, 4);
    std::memcpy(b.retypeMask.data(), p + 20, 4 * MASK_WORDS);
    const int64_t lo = -int64_t(KEY_BIAS), hi = int64_t(KEY_BIAS);
    if (b.x < lo || b.x >= hi || b.y < lo || b.y >= hi || b.z < lo || b.z >= hi)
        throw Error(name + ": block " + std::to_string(i) + " has a coordinate outside the key range");
    if (b.hashStamp > frameNumber) throw Error(name + ": block " + std::to_string(i) + " was touched after the last frame");
    return b;
}

bool isMeshArray(uint32_t t) { return t == tag("cube") || t == tag("edgx") || t == tag("edgy") || t == tag("edgz"); }

}  // namespace

std::string tagName(uint32_t t) {
    std::string s;
    for (int i = 0; i < 4; ++i) {
        const char c = char((t >> (8 * i)) & 0xFF);
        s += (c >= 0x20 && c < 0x7F) ? c : '?';
    }
    return s;
}

uint32_t crc32(const void* data, size_t size, uint32_t crc) {
    static const std::array<uint32_t, 256> table = [] {
        std::array<uint32_t, 256> t{};
        for (uint32_t i = 0; i < 256; ++i) {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            t[i] = c;
        }
        return t;
    }();
    const auto* p = static_cast<const uint8_t*>(data);
    crc = ~crc;
    for (size_t i = 0; i < size; ++i) crc = table[(crc ^ p[i]) & 0xFF] ^ (crc >> 8);
    return ~crc;
}

std::vector<uint32_t> FreeStack::entries(uint32_t capacity) const {
    std::vector<uint32_t> e;
    e.reserve(size_t(capacity - firstUntouched) + holes.size());
    for (uint32_t i = capacity; i > firstUntouched; --i) e.push_back(i - 1);
    e.insert(e.end(), holes.begin(), holes.end());
    return e;
}

FreeStack FreeStack::fromEntries(const std::vector<uint32_t>& entries, uint32_t capacity) {
    size_t run = 0;
    while (run < entries.size() && run < capacity && entries[run] == capacity - 1 - run) ++run;
    FreeStack f;
    f.firstUntouched = uint32_t(capacity - run);
    f.holes.assign(entries.begin() + ptrdiff_t(run), entries.end());
    return f;
}

const CornerArray* MapData::corners(uint32_t t) const {
    for (const CornerArray& a : cornerArrays)
        if (a.tag == t) return &a;
    return nullptr;
}

std::string serialize(const MapData& map) {
    Writer w;
    w.section(kSettings, SectionKind::Single, 4 * kSettingsWords, 1);
    writeSettings(w, map.settings);
    w.section(kState, SectionKind::Single, kStateBytes, 1);
    w.u32(map.frameNumber), w.u32(map.framesIntegrated), w.u32(map.retryPending), w.u32(0), w.u64(map.saveId);
    w.section(kCounters, SectionKind::Single, sizeof(Counters), 1);
    w.bytes(&map.counters, sizeof(Counters));
    w.section(kPush, SectionKind::Single, sizeof(FramePush), 1);
    w.bytes(&map.lastPush, sizeof(FramePush));
    w.section(kBlocks, SectionKind::List, kBlockRecordBytes, map.blocks.size());
    for (const Block& b : map.blocks) {
        w.u32(uint32_t(b.x)), w.u32(uint32_t(b.y)), w.u32(uint32_t(b.z)), w.u32(b.index), w.u32(b.hashStamp);
        w.bytes(b.retypeMask.data(), 4 * MASK_WORDS);
    }
    for (const CornerArray& a : map.cornerArrays) {
        w.section(a.tag, SectionKind::PerBlock, kCornerRecordBytes, map.blocks.size());
        w.bytes(a.words.data(), a.words.size() * 4);
    }
    writeFreeStack(w, kBlockFree, map.blockFree);
    w.section(kVertices, SectionKind::List, sizeof(Vertex), map.vertices.size());
    w.bytes(map.vertices.data(), map.vertices.size() * sizeof(Vertex));
    w.section(kOwners, SectionKind::List, 4, map.vertexOwners.size());
    w.bytes(map.vertexOwners.data(), map.vertexOwners.size() * 4);
    writeFreeStack(w, kVertexFree, map.vertexFree);
    w.section(kChunks, SectionKind::List, kChunkRecordBytes, map.chunkWords.size() / CHUNK_WORDS);
    w.bytes(map.chunkWords.data(), map.chunkWords.size() * 4);
    writeFreeStack(w, kChunkFree, map.chunkFree);

    Writer h;
    h.bytes(kMagic.data(), kMagic.size());
    h.u32(map.version), h.u32(kHeaderBytes), h.u32(map.features), h.u32(BLOCK_SIDE), h.f32(map.settings.voxelSize);
    h.u32(sizeof(Vertex)), h.u32(kChunkRecordBytes), h.u32(VOXELS_PER_BLOCK);
    const Capacities& c = map.capacities;
    h.u32(c.blocks), h.u32(c.hashSlots), h.u32(c.touched), h.u32(c.retype), h.u32(c.vertices), h.u32(c.chunks);
    h.u64(w.out.size());
    h.u32(crc32(w.out.data(), w.out.size()));
    h.u32(crc32(h.out.data(), h.out.size()));
    return h.out + w.out;
}

MapData parse(std::string_view bytes, const std::string& name) {
    Reader r(bytes, name);
    MapData map;
    const HeaderFields header = parseHeader(bytes, bytes.size(), name, map);
    const std::string_view payload = bytes.substr(kHeaderBytes);
    if (!fuzzing::active() && crc32(payload.data(), payload.size()) != header.payloadCrc)
        r.fail("checksum mismatch (CRC-32 of the sections; the file is corrupt)");
    const Capacities& cap = map.capacities;

    // ---- sections ----
    std::map<uint32_t, Section> sections;
    std::vector<uint32_t> order;
    for (size_t at = 0; at < payload.size();) {
        if (payload.size() - at < kSectionHeaderBytes) r.fail("truncated section header at byte " + std::to_string(kHeaderBytes + at));
        Section s = parseSectionHeader(payload.data() + at, kHeaderBytes + at + kSectionHeaderBytes,
                                       payload.size() - at - kSectionHeaderBytes, name);
        at += kSectionHeaderBytes;
        s.data = payload.substr(at, size_t(s.count) * s.recordBytes);
        at += s.data.size();
        if (!sections.emplace(s.tag, s).second) r.fail("section '" + tagName(s.tag) + "' appears twice");
        order.push_back(s.tag);
    }
    auto need = [&](uint32_t t, SectionKind kind, uint32_t recordBytes) -> const Section& {
        return needSection(sections, t, kind, recordBytes, name);
    };
    parseSingles(sections, [](const Section& s) { return std::string(s.data); }, header.voxelSize, name, map);

    // Free stacks: every index below the pool's capacity, each at most once, the holes below the untouched run.
    auto freeStack = [&](uint32_t t, uint32_t capacity, const char* pool) {
        const Section& s = need(t, SectionKind::List, 4);
        if (s.count < 1) r.fail("section '" + tagName(t) + "' is empty (its first word is the untouched index)");
        FreeStack f;
        std::memcpy(&f.firstUntouched, s.data.data(), 4);
        if (f.firstUntouched > capacity)
            r.fail(std::string(pool) + " free stack starts at " + std::to_string(f.firstUntouched) + ", beyond the capacity " +
                   std::to_string(capacity));
        f.holes.resize(size_t(s.count - 1));
        if (!f.holes.empty()) std::memcpy(f.holes.data(), s.data.data() + 4, f.holes.size() * 4);
        for (uint32_t i : f.holes)
            if (i >= f.firstUntouched) r.fail(std::string(pool) + " free stack holds index " + std::to_string(i) + ", out of range");
        // Sorting (not a bitmap of the capacity): memory bounded by the file's size, whatever it claims.
        std::vector<uint32_t> sorted = f.holes;
        std::sort(sorted.begin(), sorted.end());
        if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) r.fail(std::string(pool) + " free stack holds an index twice");
        return f;
    };
    map.blockFree = freeStack(kBlockFree, cap.blocks, "block");
    map.vertexFree = freeStack(kVertexFree, cap.vertices, "vertex");
    map.chunkFree = freeStack(kChunkFree, cap.chunks, "triangle chunk");

    // Blocks: distinct indices in use (below the untouched run, not free), distinct coordinates in the key range.
    const Section& blocks = need(kBlocks, SectionKind::List, kBlockRecordBytes);
    {
        std::vector<uint32_t> used = map.blockFree.holes;   // free or in use: each index once
        std::set<std::tuple<int32_t, int32_t, int32_t>> coords;
        map.blocks.resize(size_t(blocks.count));
        for (size_t i = 0; i < map.blocks.size(); ++i) {
            Block& b = map.blocks[i];
            b = parseBlockRecord(blocks.data.data() + i * kBlockRecordBytes, i, map.frameNumber, name);
            if (b.index >= map.blockFree.firstUntouched)
                r.fail("block " + std::to_string(i) + " has pool index " + std::to_string(b.index) + ", which is never used");
            used.push_back(b.index);
            if (!coords.emplace(b.x, b.y, b.z).second) r.fail("block " + std::to_string(i) + " repeats a block coordinate");
        }
        std::sort(used.begin(), used.end());
        if (std::adjacent_find(used.begin(), used.end()) != used.end()) r.fail("a block index is used twice or both used and free");
    }

    // Vertex heap and chunks: exactly the part below the untouched runs.
    map.vertices = copyRecords<Vertex>(need(kVertices, SectionKind::List, sizeof(Vertex)));
    map.vertexOwners = copyRecords<uint32_t>(need(kOwners, SectionKind::List, 4));
    map.chunkWords = copyRecords<uint32_t>(need(kChunks, SectionKind::List, kChunkRecordBytes));
    const uint32_t vertexCount = map.vertexFree.firstUntouched, chunkCount = map.chunkFree.firstUntouched;
    if (map.vertices.size() != vertexCount || map.vertexOwners.size() != vertexCount)
        r.fail("the vertex heap holds " + std::to_string(map.vertices.size()) + " vertices and " + std::to_string(map.vertexOwners.size()) +
               " owners, its free stack says " + std::to_string(vertexCount));
    if (map.chunkWords.size() != size_t(chunkCount) * CHUNK_WORDS)
        r.fail("the chunk heap holds " + std::to_string(map.chunkWords.size() / CHUNK_WORDS) + " chunks, its free stack says " +
               std::to_string(chunkCount));
    // Free means DEAD: the GC frees a vertex by swapping its refcount 0 -> DEAD and pushes it once, so a live
    // refcount on the free stack would be pushed a second time (past the stack's end).
    std::vector<char> vertexFree(vertexCount, 0), chunkFree(chunkCount, 0), chunkUsed(chunkCount, 0);
    for (uint32_t v : map.vertexFree.holes) vertexFree[v] = 1;
    for (uint32_t c : map.chunkFree.holes) chunkFree[c] = 1;
    for (uint32_t v = 0; v < vertexCount; ++v)
        if ((map.vertices[v].refcount == DEAD_REFCOUNT) != bool(vertexFree[v]))
            r.fail("vertex " + std::to_string(v) + (vertexFree[v] ? " is on the free stack but alive" : " is free but not on the free stack"));
    const uint64_t edgeIds = uint64_t(cap.blocks) * VOXELS_PER_BLOCK * 3;
    for (uint32_t v = 0; v < vertexCount; ++v)
        if (map.vertices[v].refcount != DEAD_REFCOUNT && map.vertexOwners[v] >= edgeIds)
            r.fail("vertex " + std::to_string(v) + " has an owner edge outside the block pool");
    for (uint32_t w : map.chunkWords)
        if (w != INVALID_INDEX && w >= vertexCount) r.fail("a triangle refers to vertex " + std::to_string(w) + ", outside the heap");

    // Per-corner arrays: any number (components list theirs), one record per block. The mesh's are checked
    // against the heaps: every index the GPU will follow must stay inside them.
    for (uint32_t t : order) {
        const Section& s = sections.at(t);
        if (s.kind != SectionKind::PerBlock) continue;
        if (s.recordBytes != kCornerRecordBytes || s.count != map.blocks.size())
            r.fail("section '" + tagName(t) + "' must hold one record of " + std::to_string(kCornerRecordBytes) + " bytes per block");
        map.cornerArrays.push_back({t, copyRecords<uint32_t>(s)});
    }
    for (const CornerArray& a : map.cornerArrays) {
        if (a.tag == tag("cube")) {
            for (uint32_t st : a.words) {
                const uint32_t chunk = st >> CUBE_CHUNK_SHIFT;   // chunk + 1, 0 = none
                if (chunk > chunkCount) r.fail("a cube refers to a triangle chunk outside the heap");
                if (chunk && (chunkFree[chunk - 1] || chunkUsed[chunk - 1]++))
                    r.fail("triangle chunk " + std::to_string(chunk - 1) + " is free or belongs to two cubes");
            }
        } else if (a.tag == tag("edgx") || a.tag == tag("edgy") || a.tag == tag("edgz")) {
            for (uint32_t slot : a.words)
                if (slot != EMPTY_SLOT && (slot >= vertexCount || vertexFree[slot]))
                    r.fail("an edge refers to vertex " + std::to_string(slot) + (slot >= vertexCount ? ", outside the heap" : ", which is free"));
        }
    }
    const Counters& k = map.counters;
    if (k.vertexHighWater > cap.vertices || k.chunkHighWater > cap.chunks || k.verticesInUse > cap.vertices ||
        k.chunksInUse > cap.chunks || k.blocksInUse > cap.blocks)
        r.fail("the counters exceed the capacities");
    return map;
}

MapData readFile(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open map file " + path.string());
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw Error("cannot read map file " + path.string());
    return parse(bytes, path.string());
}

void writeFile(const std::filesystem::path& path, const MapData& map) {
    const std::string bytes = serialize(map);
    std::filesystem::path tmp = path;
    tmp += ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw Error("cannot write map file " + tmp.string());
        out.write(bytes.data(), std::streamsize(bytes.size()));
        out.close();
        if (!out) throw Error("cannot write map file " + tmp.string() + " (disk full?)");
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw Error("cannot rename " + tmp.string() + " to " + path.string() + ": " + ec.message());
}

// ---- reading part of a file --------------------------------------------------------------------------

BlockReader::BlockReader(const std::filesystem::path& path) : path_(path), name_(path.string()) {
    in_.open(path, std::ios::binary);
    if (!in_) throw Error("cannot open map file " + name_);
    std::error_code ec;
    fileBytes_ = std::filesystem::file_size(path, ec);
    if (ec) throw Error("cannot read map file " + name_ + ": " + ec.message());
    std::string head(size_t(std::min<uint64_t>(fileBytes_, kHeaderBytes)), '\0');
    readAt(0, head.data(), head.size());
    const HeaderFields fields = parseHeader(head, fileBytes_, name_, header_);
    payloadCrc_ = fields.payloadCrc;

    // The section table: the headers only, each followed by a seek past its records.
    std::map<uint32_t, Section> sections;
    const uint64_t end = fileBytes_;
    for (uint64_t at = kHeaderBytes; at < end;) {
        if (end - at < kSectionHeaderBytes) throw Error(name_ + ": truncated section header at byte " + std::to_string(at));
        char sectionHeader[kSectionHeaderBytes];
        readAt(at, sectionHeader, kSectionHeaderBytes);
        const Section s = parseSectionHeader(sectionHeader, at + kSectionHeaderBytes, end - at - kSectionHeaderBytes, name_);
        if (!sections.emplace(s.tag, s).second) throw Error(name_ + ": section '" + tagName(s.tag) + "' appears twice");
        if (s.kind == SectionKind::PerBlock) perBlock_.push_back({s.tag, s.offset});
        at = s.offset + s.count * s.recordBytes;
    }
    parseSingles(
        sections,
        [&](const Section& s) {
            std::string bytes(size_t(s.count) * s.recordBytes, '\0');
            readAt(s.offset, bytes.data(), bytes.size());
            return bytes;
        },
        fields.voxelSize, name_, header_);

    // The block table, a slice at a time (its records hold a retype mask this reader does not keep).
    const Section& blocks = needSection(sections, kBlocks, SectionKind::List, kBlockRecordBytes, name_);
    table_.reserve(size_t(blocks.count));
    constexpr size_t kSlice = 4096;
    std::string slice;
    for (uint64_t first = 0; first < blocks.count; first += kSlice) {
        const size_t n = size_t(std::min<uint64_t>(kSlice, blocks.count - first));
        slice.resize(n * kBlockRecordBytes);
        readAt(blocks.offset + first * kBlockRecordBytes, slice.data(), slice.size());
        for (size_t k = 0; k < n; ++k) {
            const Block b = parseBlockRecord(slice.data() + k * kBlockRecordBytes, size_t(first + k), header_.frameNumber, name_);
            table_.push_back({b.x, b.y, b.z, b.hashStamp});
        }
    }
    {
        std::vector<std::tuple<int32_t, int32_t, int32_t>> coords;
        coords.reserve(table_.size());
        for (const TableEntry& e : table_) coords.emplace_back(e.x, e.y, e.z);
        std::sort(coords.begin(), coords.end());
        const auto repeated = std::adjacent_find(coords.begin(), coords.end());
        if (repeated != coords.end())
            throw Error(name_ + ": block (" + std::to_string(std::get<0>(*repeated)) + ", " + std::to_string(std::get<1>(*repeated)) + ", " +
                        std::to_string(std::get<2>(*repeated)) + ") appears twice in the block table");
    }
    for (const PerBlockSection& p : perBlock_) {
        const Section& s = sections.at(p.tag);
        if (s.recordBytes != kCornerRecordBytes || s.count != table_.size())
            throw Error(name_ + ": section '" + tagName(p.tag) + "' must hold one record of " + std::to_string(kCornerRecordBytes) +
                        " bytes per block");
    }
}

void BlockReader::readAt(uint64_t offset, void* out, size_t bytes) {
    in_.clear();
    in_.seekg(std::streamoff(offset));
    in_.read(static_cast<char*>(out), std::streamsize(bytes));
    if (!in_ || size_t(in_.gcount()) != bytes)
        throw Error("cannot read map file " + name_ + " (" + std::to_string(bytes) + " bytes at byte " + std::to_string(offset) +
                    "; changed or truncated while read?)");
}

MapData BlockReader::read(const BlockBox& box) {
    const int64_t lo = -int64_t(KEY_BIAS), hi = int64_t(KEY_BIAS);
    auto corner = [](const std::array<int32_t, 3>& c) {
        return "(" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " + std::to_string(c[2]) + ")";
    };
    const std::string what = "block box " + corner(box.lo) + " to " + corner(box.hi);
    for (int a = 0; a < 3; ++a) {
        if (box.lo[a] > box.hi[a])
            throw Error(name_ + ": " + what + " is empty: its low corner is above its high one on " + std::string(1, "xyz"[a]));
        if (box.lo[a] < lo || box.hi[a] >= hi)
            throw Error(name_ + ": " + what + " reaches outside the block coordinates a map holds, [-" + std::to_string(KEY_BIAS) + ", " +
                        std::to_string(KEY_BIAS) + ")");
    }
    return read([&](int32_t x, int32_t y, int32_t z) { return box.contains(x, y, z); });
}

MapData BlockReader::read(const BlockFilter& keep) {
    std::vector<size_t> kept;
    for (size_t i = 0; i < table_.size(); ++i)
        if (keep(table_[i].x, table_[i].y, table_[i].z)) kept.push_back(i);
    const size_t n = kept.size();

    MapData out;
    out.version = header_.version;
    out.features = header_.features;
    out.settings = header_.settings;
    out.capacities = header_.capacities;
    out.capacities.blocks = std::max(out.capacities.blocks, uint32_t(n));
    out.frameNumber = header_.frameNumber, out.framesIntegrated = header_.framesIntegrated;
    out.saveId = header_.saveId;
    out.lastPush = header_.lastPush;
    out.blocks.reserve(n);
    for (size_t k = 0; k < n; ++k) {
        const TableEntry& e = table_[kept[k]];
        out.blocks.push_back({e.x, e.y, e.z, uint32_t(k), e.hashStamp, {}});
    }
    for (const PerBlockSection& p : perBlock_) {
        const bool edges = isMeshArray(p.tag) && p.tag != tag("cube");
        CornerArray a{p.tag, std::vector<uint32_t>(n * VOXELS_PER_BLOCK, edges ? EMPTY_SLOT : 0u)};
        // The mesh's arrays stay empty (the mesh is rebuilt from the TSDF); the others are read a run of consecutive
        // records at a time.
        for (size_t k = 0; k < n && !isMeshArray(p.tag);) {
            size_t run = 1;
            while (k + run < n && kept[k + run] == kept[k] + run) ++run;
            readAt(p.offset + uint64_t(kept[k]) * kCornerRecordBytes, a.words.data() + k * VOXELS_PER_BLOCK, run * kCornerRecordBytes);
            k += run;
        }
        out.cornerArrays.push_back(std::move(a));
    }
    // Counters of a map with no mesh (as map::merge's result).
    out.counters.blocksInUse = out.counters.liveBlockCount = out.counters.hashEntries = uint32_t(n);
    out.blockFree = {uint32_t(n), {}};
    out.vertexFree = {0, {}};
    out.chunkFree = {0, {}};
    return out;
}

void BlockReader::verifyChecksum() {
    std::vector<char> buffer(size_t(1) << 20);
    uint32_t crc = 0;
    for (uint64_t at = kHeaderBytes; at < fileBytes_;) {
        const size_t n = size_t(std::min<uint64_t>(buffer.size(), fileBytes_ - at));
        readAt(at, buffer.data(), n);
        crc = crc32(buffer.data(), n, crc);
        at += n;
    }
    if (!fuzzing::active() && crc != payloadCrc_) throw Error(name_ + ": checksum mismatch (CRC-32 of the sections; the file is corrupt)");
}

}  // namespace vkmesh::map
