#include "core/frame_store.h"

#include "core/fuzzing.h"
#include "core/map_format.h"  // map::crc32

#include <zstd.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstring>
#include <fstream>
#include <string_view>
#include <utility>

namespace vkmesh {

namespace fs = std::filesystem;

namespace {

static_assert(std::endian::native == std::endian::little, "the frame store file is little-endian; a big-endian host needs byte swaps here");

constexpr std::array<char, 8> kMagic = {'V', 'K', 'F', 'R', 'A', 'M', 'E', 'S'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 8 + 4 + 8 + 8;
// u32 index, f64 timestamp, 4 f32 + 2 i32 intrinsics, 16 f64 pose, u32 depth bytes, u32 colour bytes; then the CRC.
constexpr size_t kRecordFieldBytes = 4 + 8 + 16 + 8 + 128 + 4 + 4;
constexpr size_t kRecordHeaderBytes = kRecordFieldBytes + 4;
// The limits of the depth PNG decoder (io/parsers.h, not reachable from vkmesh_base): a hostile file cannot make
// load() allocate more than 256 MiB per image, and every payload's size fits a u32 field (zstd's bound on
// 256 MiB is barely above it).
constexpr int kMaxSide = 16384;
constexpr uint64_t kMaxPixels = uint64_t(1) << 26;

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

bool sizeAllowed(int w, int h) { return w > 0 && h > 0 && w <= kMaxSide && h <= kMaxSide && uint64_t(w) * uint64_t(h) <= kMaxPixels; }

bool finite(const Pose& p) { return p.allFinite(); }

// ---- what goes into zstd -----------------------------------------------------------------------------------
// Depth: the floats' bytes as they are. Depth from a sensor is quantised (TUM and ICL-NUIM: uint16 / 5000), so an
// image holds a few thousand distinct floats, each repeated along surfaces, which zstd's matches and entropy coder
// exploit directly. Both transforms that help integer images do harm here (bench/frame_store_bytes.cpp, 20 frames,
// level 3): row deltas of the bit patterns split into byte planes, 242 / 141 kB a frame (tum_fr1_rpy /
// iclnuim_office_traj0) against 113 / 110 kB raw, because a difference of two quantised floats is a different
// bit pattern nearly every time (the 1/5000 m step is ~1700 float ulps, rounded); byte planes alone 224 / 150 kB.
// Colour: three planes (R, G, B) of row differences (modulo 256, exactly invertible), 421 / 227 kB against
// 643 / 408 kB for the planes alone: neighbouring pixels of a photograph differ little.

std::vector<uint8_t> colorToPlanes(const ColorImage& c) {
    const size_t n = size_t(c.width) * size_t(c.height), w = size_t(c.width);
    std::vector<uint8_t> out(3 * n);
    for (size_t row = 0; row < n; row += w) {
        std::array<uint8_t, 3> prev{};
        for (size_t i = row; i < row + w; ++i)
            for (size_t k = 0; k < 3; ++k) {
                const uint8_t v = c.rgb[3 * i + k];
                out[k * n + i] = uint8_t(v - prev[k]);
                prev[k] = v;
            }
    }
    return out;
}

void planesToColor(const std::vector<uint8_t>& planes, ColorImage& c) {
    const size_t n = size_t(c.width) * size_t(c.height), w = size_t(c.width);
    for (size_t row = 0; row < n; row += w) {
        std::array<uint8_t, 3> prev{};
        for (size_t i = row; i < row + w; ++i)
            for (size_t k = 0; k < 3; ++k) {
                prev[k] = uint8_t(prev[k] + planes[k * n + i]);
                c.rgb[3 * i + k] = prev[k];
            }
    }
}

std::string compress(const void* raw, size_t rawBytes, int level) {
    std::string out(ZSTD_compressBound(rawBytes), '\0');
    const size_t n = ZSTD_compress(out.data(), out.size(), raw, rawBytes, level);
    if (ZSTD_isError(n)) throw Error(std::string("frame store: zstd compression failed: ") + ZSTD_getErrorName(n));
    out.resize(n);
    return out;
}

// Decompresses one zstd frame that must fill `rawBytes` at `raw` exactly; returns "" or what is wrong.
std::string decompress(std::string_view frame, void* raw, size_t rawBytes) {
    const unsigned long long content = ZSTD_getFrameContentSize(frame.data(), frame.size());
    if (content == ZSTD_CONTENTSIZE_ERROR || content == ZSTD_CONTENTSIZE_UNKNOWN) return "not a zstd frame";
    if (content != rawBytes) return "the zstd frame holds " + std::to_string(content) + " bytes, the image needs " + std::to_string(rawBytes);
    if (ZSTD_findFrameCompressedSize(frame.data(), frame.size()) != frame.size()) return "the zstd frame does not fill its payload";
    const size_t n = ZSTD_decompress(raw, rawBytes, frame.data(), frame.size());
    if (ZSTD_isError(n)) return std::string("zstd: ") + ZSTD_getErrorName(n);
    if (n != rawBytes) return "zstd gave " + std::to_string(n) + " bytes, the image needs " + std::to_string(rawBytes);
    return {};
}

// ---- the file -----------------------------------------------------------------------------------------------

struct Writer {
    std::string out;
    void bytes(const void* p, size_t n) { out.append(static_cast<const char*>(p), n); }
    void u32(uint32_t v) { bytes(&v, 4); }
    void i32(int32_t v) { bytes(&v, 4); }
    void u64(uint64_t v) { bytes(&v, 8); }
    void f32(float v) { bytes(&v, 4); }
    void f64(double v) { bytes(&v, 8); }
};

template <typename T>
T readAt(const char* p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    return v;
}

struct RecordFields {
    uint32_t index = 0;
    double timestamp = 0;
    Intrinsics intrinsics;
    Pose pose;
    uint32_t depthBytes = 0, colorBytes = 0;
};

std::string recordFields(uint32_t index, double timestamp, const Intrinsics& k, const Pose& pose, uint32_t depthBytes,
                         uint32_t colorBytes) {
    Writer w;
    w.u32(index);
    w.f64(timestamp);
    w.f32(k.fx), w.f32(k.fy), w.f32(k.cx), w.f32(k.cy);
    w.i32(k.width), w.i32(k.height);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) w.f64(pose(r, c));
    w.u32(depthBytes);
    w.u32(colorBytes);
    return w.out;
}

RecordFields parseRecordFields(const char* p) {
    RecordFields f;
    f.index = readAt<uint32_t>(p);
    f.timestamp = readAt<double>(p + 4);
    f.intrinsics.fx = readAt<float>(p + 12), f.intrinsics.fy = readAt<float>(p + 16);
    f.intrinsics.cx = readAt<float>(p + 20), f.intrinsics.cy = readAt<float>(p + 24);
    f.intrinsics.width = readAt<int32_t>(p + 28), f.intrinsics.height = readAt<int32_t>(p + 32);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) f.pose(r, c) = readAt<double>(p + 36 + 8 * (4 * r + c));
    f.depthBytes = readAt<uint32_t>(p + 164);
    f.colorBytes = readAt<uint32_t>(p + 168);
    return f;
}

struct Header {
    uint64_t mapId = 0, count = 0;
};

Header readHeader(std::istream& in, const std::string& path) {
    std::array<char, kHeaderBytes> h{};
    in.read(h.data(), h.size());
    const size_t got = size_t(in.gcount());
    if (got < kMagic.size() || std::memcmp(h.data(), kMagic.data(), kMagic.size()) != 0)
        throw Error(path + ": not a vkmesh frame store (wrong magic; the file starts with \"VKFRAMES\")");
    if (got < kHeaderBytes)
        throw Error(path + ": truncated: " + std::to_string(got) + " bytes, shorter than the " + std::to_string(kHeaderBytes) + "-byte header");
    const uint32_t version = readAt<uint32_t>(h.data() + 8);
    if (version != kVersion)
        throw Error(path + ": frame store format version " + std::to_string(version) + " is not supported (this build of vkmesh reads version " +
                    std::to_string(kVersion) + (version > kVersion ? "; use a newer vkmesh)" : "; the file is corrupt)"));
    return {readAt<uint64_t>(h.data() + 12), readAt<uint64_t>(h.data() + 20)};
}

std::ifstream openForReading(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path + ": cannot open the frame store file");
    return in;
}

// Each store spills into a folder of its own inside the spill folder, so that stores sharing a spill folder
// (in one process or several) never touch each other's files.
fs::path makeOwnFolder(const fs::path& parent) {
    static std::atomic<unsigned> counter{0};
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) throw Error("frame store: cannot create the spill folder " + parent.string() + ": " + ec.message());
    for (;;) {
        const fs::path dir = parent / ("vkmesh-frames-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
        if (fs::create_directory(dir, ec)) return dir;
        if (ec) throw Error("frame store: cannot create " + dir.string() + ": " + ec.message());
    }
}

}  // namespace

FrameStore::FrameStore(FrameStoreOptions options) : options_(std::move(options)) {}

FrameStore::~FrameStore() { removeSpillFolder(); }

FrameStore::FrameStore(FrameStore&& other) noexcept
    : options_(std::move(other.options_)),
      frames_(std::exchange(other.frames_, {})),
      bytesInMemory_(std::exchange(other.bytesInMemory_, 0)),
      bytesOnDisk_(std::exchange(other.bytesOnDisk_, 0)),
      rawBytes_(std::exchange(other.rawBytes_, 0)),
      spillDir_(std::exchange(other.spillDir_, {})) {}

FrameStore& FrameStore::operator=(FrameStore&& other) noexcept {
    if (this != &other) {
        removeSpillFolder();
        options_ = std::move(other.options_);
        frames_ = std::exchange(other.frames_, {});
        bytesInMemory_ = std::exchange(other.bytesInMemory_, 0);
        bytesOnDisk_ = std::exchange(other.bytesOnDisk_, 0);
        rawBytes_ = std::exchange(other.rawBytes_, 0);
        spillDir_ = std::exchange(other.spillDir_, {});
    }
    return *this;
}

void FrameStore::removeSpillFolder() noexcept {
    if (spillDir_.empty()) return;
    std::error_code ec;  // a file already gone, or a folder the user removed, is no reason to fail
    fs::remove_all(spillDir_, ec);
    spillDir_.clear();
}

void FrameStore::add(const StoredFrame& frame) {
    const std::string what = "frame store: frame " + std::to_string(frame.index);
    if (frames_.count(frame.index)) throw Error(what + " is already stored");
    const DepthImage& d = frame.depth;
    if (!sizeAllowed(d.width, d.height))
        throw Error(what + ": depth image size " + sizeText(d.width, d.height) + " is empty or larger than 16384 per side / 64 Mpixel");
    const size_t pixels = size_t(d.width) * size_t(d.height);
    if (d.meters.size() != pixels)
        throw Error(what + ": the depth image has " + std::to_string(d.meters.size()) + " samples, " + sizeText(d.width, d.height) +
                    " needs " + std::to_string(pixels));
    if (frame.intrinsics.width != d.width || frame.intrinsics.height != d.height)
        throw Error(what + ": the intrinsics are for " + sizeText(frame.intrinsics.width, frame.intrinsics.height) +
                    ", the depth image is " + sizeText(d.width, d.height));
    const ColorImage& c = frame.color;
    if (!c.empty() && (c.width != d.width || c.height != d.height || c.rgb.size() != 3 * pixels))
        throw Error(what + ": the colour image (" + sizeText(c.width, c.height) + ", " + std::to_string(c.rgb.size()) +
                    " bytes) is not registered to the " + sizeText(d.width, d.height) + " depth image (" + std::to_string(3 * pixels) +
                    " bytes)");
    if (!finite(frame.pose)) throw Error(what + ": the pose is not finite");

    Entry e;
    e.timestamp = frame.timestamp;
    e.intrinsics = frame.intrinsics;
    e.pose = frame.pose;
    e.payload = compress(d.meters.data(), 4 * pixels, options_.zstdLevel);
    e.depthBytes = uint32_t(e.payload.size());
    if (!c.empty()) {
        const std::vector<uint8_t> planes = colorToPlanes(c);
        e.payload += compress(planes.data(), planes.size(), options_.zstdLevel);
        e.colorBytes = uint32_t(e.payload.size() - e.depthBytes);
    }
    e.payloadCrc = map::crc32(e.payload.data(), e.payload.size());
    insert(frame.index, std::move(e));
}

void FrameStore::insert(uint32_t index, Entry&& e) {
    const size_t bytes = e.payloadBytes();
    if (bytesInMemory_ + bytes <= options_.memoryBudgetBytes) {
        bytesInMemory_ += bytes;
    } else if (options_.spillFolder.empty()) {
        const size_t inMemory = size_t(std::count_if(frames_.begin(), frames_.end(), [](const auto& f) { return !f.second.spilled; }));
        throw Error("frame store: frame " + std::to_string(index) + " (" + std::to_string(bytes) + " compressed bytes) does not fit the memory budget of " +
                    std::to_string(options_.memoryBudgetBytes) + " bytes, " + std::to_string(bytesInMemory_) + " of which hold " +
                    std::to_string(inMemory) + " frames (" + std::to_string(frames_.size()) +
                    " stored), and there is no spill folder (FrameStoreOptions::spillFolder)");
    } else {
        if (spillDir_.empty()) spillDir_ = makeOwnFolder(options_.spillFolder);
        const fs::path file = spillFile(index);
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out.write(e.payload.data(), std::streamsize(bytes));
        out.close();
        if (!out) throw Error("frame store: cannot write the spill file " + file.string() + " of frame " + std::to_string(index) + " (disk full?)");
        std::string().swap(e.payload);
        e.spilled = true;
        bytesOnDisk_ += bytes;
    }
    rawBytes_ += size_t(e.intrinsics.width) * size_t(e.intrinsics.height) * (e.colorBytes ? 7 : 4);
    frames_.emplace(index, std::move(e));
}

fs::path FrameStore::spillFile(uint32_t index) const { return spillDir_ / ("frame-" + std::to_string(index) + ".zst"); }

std::string FrameStore::payloadOf(uint32_t index, const Entry& e) const {
    if (!e.spilled) return e.payload;
    const fs::path file = spillFile(index);
    const std::string what = "frame store: spilled frame " + std::to_string(index) + ": " + file.string();
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error(what + ": cannot open");
    std::string payload(e.payloadBytes() + 1, '\0');  // one byte more: a longer file is caught too
    in.read(payload.data(), std::streamsize(payload.size()));
    if (size_t(in.gcount()) != e.payloadBytes())
        throw Error(what + " is not the " + std::to_string(e.payloadBytes()) + " bytes written (changed since it was written)");
    payload.pop_back();
    if (map::crc32(payload.data(), payload.size()) != e.payloadCrc) throw Error(what + ": CRC mismatch (changed since it was written)");
    return payload;
}

const FrameStore::Entry& FrameStore::entry(uint32_t index) const {
    const auto it = frames_.find(index);
    if (it == frames_.end()) throw Error("frame store: no frame " + std::to_string(index) + " (" + std::to_string(frames_.size()) + " frames stored)");
    return it->second;
}

bool FrameStore::contains(uint32_t index) const { return frames_.count(index) != 0; }

StoredFrame FrameStore::get(uint32_t index) const {
    const Entry& e = entry(index);
    const std::string payload = payloadOf(index, e);
    const std::string_view view(payload);
    StoredFrame f;
    f.index = index;
    f.timestamp = e.timestamp;
    f.intrinsics = e.intrinsics;
    f.pose = e.pose;
    const int w = e.intrinsics.width, h = e.intrinsics.height;
    const size_t pixels = size_t(w) * size_t(h);
    const std::string what = "frame store: frame " + std::to_string(index);

    f.depth.width = w, f.depth.height = h;
    f.depth.meters.resize(pixels);
    if (const std::string err = decompress(view.substr(0, e.depthBytes), f.depth.meters.data(), 4 * pixels); !err.empty())
        throw Error(what + ": corrupt depth payload (" + err + ")");
    if (e.colorBytes) {
        std::vector<uint8_t> planes(3 * pixels);
        if (const std::string err = decompress(view.substr(e.depthBytes), planes.data(), planes.size()); !err.empty())
            throw Error(what + ": corrupt colour payload (" + err + ")");
        f.color.width = w, f.color.height = h;
        f.color.rgb.resize(3 * pixels);
        planesToColor(planes, f.color);
    }
    return f;
}

const Pose& FrameStore::pose(uint32_t index) const { return entry(index).pose; }

double FrameStore::timestamp(uint32_t index) const { return entry(index).timestamp; }

void FrameStore::setPose(uint32_t index, const Pose& pose) {
    entry(index);  // throws if unknown
    if (!finite(pose)) throw Error("frame store: frame " + std::to_string(index) + ": the new pose is not finite");
    frames_.at(index).pose = pose;
}

void FrameStore::absorb(FrameStore&& other, uint32_t indexOffset) {
    if (&other == this) throw Error("frame store: a store cannot absorb itself");
    for (const auto& [index, e] : other.frames_) {
        if (uint64_t(index) + indexOffset > UINT32_MAX)
            throw Error("frame store: frame " + std::to_string(index) + " moved by " + std::to_string(indexOffset) + " passes the largest index");
        if (frames_.count(index + indexOffset))
            throw Error("frame store: frame " + std::to_string(index + indexOffset) + " is in both stores");
    }
    for (auto& [index, e] : other.frames_) {
        if (e.spilled) {
            e.payload = other.payloadOf(index, e);
            e.spilled = false;
        }
        insert(index + indexOffset, std::move(e));
    }
    other.frames_.clear();
    other.bytesInMemory_ = other.bytesOnDisk_ = other.rawBytes_ = 0;
    other.removeSpillFolder();
}

std::vector<uint32_t> FrameStore::indices() const {
    std::vector<uint32_t> out;
    out.reserve(frames_.size());
    for (const auto& [index, e] : frames_) out.push_back(index);
    return out;
}

size_t FrameStore::size() const { return frames_.size(); }

FrameStoreStats FrameStore::stats() const {
    FrameStoreStats s;
    s.frames = frames_.size();
    for (const auto& [index, e] : frames_) (e.spilled ? s.framesSpilled : s.framesInMemory)++;
    s.rawBytes = rawBytes_;
    s.bytesInMemory = bytesInMemory_;
    s.bytesOnDisk = bytesOnDisk_;
    s.compressedBytes = bytesInMemory_ + bytesOnDisk_;
    return s;
}

void FrameStore::save(const std::string& path, uint64_t mapId) const {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw Error("frame store: cannot write " + tmp);
        Writer h;
        h.bytes(kMagic.data(), kMagic.size());
        h.u32(kVersion);
        h.u64(mapId);
        h.u64(frames_.size());
        out.write(h.out.data(), std::streamsize(h.out.size()));
        for (const auto& [index, e] : frames_) {
            Writer r;
            r.out = recordFields(index, e.timestamp, e.intrinsics, e.pose, e.depthBytes, e.colorBytes);
            const std::string payload = payloadOf(index, e);
            r.u32(map::crc32(payload.data(), payload.size(), map::crc32(r.out.data(), r.out.size())));
            out.write(r.out.data(), std::streamsize(r.out.size()));
            out.write(payload.data(), std::streamsize(payload.size()));
        }
        out.close();
        if (!out) throw Error("frame store: cannot write " + tmp + " (disk full?)");
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw Error("frame store: cannot rename " + tmp + " to " + path + ": " + ec.message());
}

uint64_t FrameStore::mapIdOf(const std::string& path) {
    std::ifstream in = openForReading(path);
    return readHeader(in, path).mapId;
}

FrameStore FrameStore::load(const std::string& path, uint64_t expectedMapId, FrameStoreOptions options) {
    std::ifstream in = openForReading(path);
    std::error_code ec;
    const uint64_t fileBytes = fs::file_size(path, ec);
    if (ec) throw Error(path + ": cannot read the frame store file: " + ec.message());
    const Header header = readHeader(in, path);
    if (header.mapId != expectedMapId)
        throw Error(path + ": the frame store belongs to another map (map id " + std::to_string(header.mapId) + ", this map's is " +
                    std::to_string(expectedMapId) + ")");

    FrameStore store(std::move(options));
    uint64_t offset = kHeaderBytes;
    std::array<char, kRecordHeaderBytes> rh{};
    std::vector<uint8_t> scratch;
    for (uint64_t k = 0; k < header.count; ++k) {
        const std::string record = path + ": frame record " + std::to_string(k) + " of " + std::to_string(header.count);
        if (fileBytes - offset < kRecordHeaderBytes)
            throw Error(record + " is truncated: its header needs " + std::to_string(kRecordHeaderBytes) + " bytes, " +
                        std::to_string(fileBytes - offset) + " are left");
        in.read(rh.data(), rh.size());
        if (size_t(in.gcount()) != rh.size()) throw Error(record + ": read error");
        offset += kRecordHeaderBytes;
        const RecordFields f = parseRecordFields(rh.data());
        const std::string frame = record + " (frame " + std::to_string(f.index) + ")";
        const uint64_t payloadBytes = uint64_t(f.depthBytes) + f.colorBytes;
        if (fileBytes - offset < payloadBytes)
            throw Error(frame + " is truncated: its payload needs " + std::to_string(payloadBytes) + " bytes, " +
                        std::to_string(fileBytes - offset) + " are left");
        Entry e;
        e.payload.resize(payloadBytes);
        in.read(e.payload.data(), std::streamsize(payloadBytes));
        if (uint64_t(in.gcount()) != payloadBytes) throw Error(frame + ": read error");
        offset += payloadBytes;
        // A fuzzer cannot forge checksums: under the fuzz targets (only) they are not checked, so that it reaches
        // the checks behind them (core/fuzzing.h).
        const bool checkSums = !fuzzing::active();
        if (checkSums &&
            map::crc32(e.payload.data(), e.payload.size(), map::crc32(rh.data(), kRecordFieldBytes)) != readAt<uint32_t>(rh.data() + kRecordFieldBytes))
            throw Error(frame + ": CRC mismatch (the file is corrupt)");

        // The CRC matched: what follows catches a file that was not written by save().
        if (!store.frames_.empty() && f.index <= store.frames_.rbegin()->first)
            throw Error(frame + ": the frame indices are not strictly ascending");
        if (!sizeAllowed(f.intrinsics.width, f.intrinsics.height))
            throw Error(frame + ": image size " + sizeText(f.intrinsics.width, f.intrinsics.height) + " is empty or larger than 16384 per side / 64 Mpixel");
        if (!finite(f.pose)) throw Error(frame + ": the pose is not finite");
        // Every zstd frame is decoded once here, so that a frame that cannot be recovered is found now rather than when it is
        // needed for de-integration.
        const std::string_view view(e.payload);
        const size_t pixels = size_t(f.intrinsics.width) * size_t(f.intrinsics.height);
        scratch.resize(4 * pixels);
        if (const std::string err = decompress(view.substr(0, f.depthBytes), scratch.data(), 4 * pixels); !err.empty())
            throw Error(frame + ": corrupt depth payload (" + err + ")");
        if (f.colorBytes) {
            if (const std::string err = decompress(view.substr(f.depthBytes), scratch.data(), 3 * pixels); !err.empty())
                throw Error(frame + ": corrupt colour payload (" + err + ")");
        }
        e.timestamp = f.timestamp;
        e.intrinsics = f.intrinsics;
        e.pose = f.pose;
        e.depthBytes = f.depthBytes;
        e.colorBytes = f.colorBytes;
        e.payloadCrc = map::crc32(e.payload.data(), e.payload.size());
        try {
            store.insert(f.index, std::move(e));
        } catch (const Error& err) {
            throw Error(path + ": " + err.what());
        }
    }
    if (offset != fileBytes)
        throw Error(path + ": " + std::to_string(fileBytes - offset) + " bytes of trailing garbage after the " + std::to_string(header.count) +
                    " frame records");
    return store;
}

}  // namespace vkmesh
