// The frame store (core/frame_store.h): every frame comes back bit for bit, from memory, from its spill file and
// from a saved file; the budget is kept; every kind of bad file or bad call is a vkmesh::Error naming the
// path, the frame and the problem.
#include "core/frame_store.h"
#include "core/map_format.h"  // map::crc32, to forge a file whose CRC is right but whose zstd payload is not
#include "test_support.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace vkmesh;
using test::errorMessageOf;

namespace {

Intrinsics intrinsicsFor(int w, int h) { return {517.3f * w / 640, 516.5f * h / 480, 318.6f * w / 640, 255.3f * h / 480, w, h}; }

Pose poseAt(uint32_t i) {
    Pose T = Pose::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.3 * i + 0.1, Eigen::Vector3d(1, 2, -3).normalized()).toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(0.123456789 * i, -1.0 / 3.0, 2.5e-3 * i);
    return T;
}

// A depth image as a Kinect v1 gives it: a slanted wall 1.2-2.6 m away, noisy (~1.2 mm z^2), snapped to the
// sensor's disparity steps (1/8 pixel at a 580 px focal length and 7.5 cm baseline: z = 348 / disparity, steps of
// 3-19 mm here), stored as TUM's PNGs do (uint16 / 5000, io/datasets/image_decoding.cpp), with a hole where
// nothing was measured and 2 % dropped pixels.
DepthImage kinectLikeDepth(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    DepthImage d{w, h, std::vector<float>(size_t(w) * h)};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double z = 1.2 + 1.0 * x / w + 0.4 * y / h;
            const double measured = 348.0 / std::round(348.0 / (z + 0.0012 * z * z * noise(rng)));
            const bool hole = (x > w / 2 && x < w / 2 + w / 8 && y > h / 3 && y < h / 2) || unit(rng) < 0.02;
            d.meters[size_t(y) * w + x] = hole ? 0.0f : float(std::round(measured * 5000.0) / 5000.0);
        }
    return d;
}

ColorImage randomColor(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    ColorImage c{w, h, std::vector<uint8_t>(size_t(w) * h * 3)};
    for (uint8_t& v : c.rgb) v = uint8_t(rng());
    return c;
}

StoredFrame makeFrame(uint32_t index, int w, int h, bool withColor = true) {
    StoredFrame f;
    f.index = index;
    f.timestamp = 1305031229.528784 + 0.0333 * index;
    f.intrinsics = intrinsicsFor(w, h);
    f.pose = poseAt(index);
    f.depth = kinectLikeDepth(w, h, 100 + index);
    if (withColor) f.color = randomColor(w, h, 200 + index);
    return f;
}

// Bit for bit: float == would let -0 pass for 0 and fail NaN against itself.
void expectSameFrame(const StoredFrame& got, const StoredFrame& want) {
    EXPECT_EQ(got.index, want.index);
    EXPECT_EQ(std::bit_cast<uint64_t>(got.timestamp), std::bit_cast<uint64_t>(want.timestamp)) << got.index;
    EXPECT_EQ(std::memcmp(&got.intrinsics, &want.intrinsics, sizeof(Intrinsics)), 0) << got.index;
    EXPECT_EQ(std::memcmp(got.pose.data(), want.pose.data(), sizeof(double) * 16), 0) << got.index;
    ASSERT_EQ(got.depth.width, want.depth.width);
    ASSERT_EQ(got.depth.height, want.depth.height);
    ASSERT_EQ(got.depth.meters.size(), want.depth.meters.size());
    EXPECT_EQ(std::memcmp(got.depth.meters.data(), want.depth.meters.data(), 4 * want.depth.meters.size()), 0) << got.index;
    EXPECT_EQ(got.color.empty(), want.color.empty()) << got.index;
    if (!want.color.empty()) {
        EXPECT_EQ(got.color.width, want.color.width);
        EXPECT_EQ(got.color.height, want.color.height);
        EXPECT_EQ(got.color.rgb, want.color.rgb) << got.index;
    }
}

constexpr size_t kHeaderBytes = 28, kRecordHeaderBytes = 176;

// Where each record of a saved file starts, and the end of the last one.
std::vector<size_t> recordOffsets(const std::string& file) {
    std::vector<size_t> out;
    uint64_t count;
    std::memcpy(&count, file.data() + 20, 8);
    size_t at = kHeaderBytes;
    for (uint64_t k = 0; k <= count; ++k) {
        out.push_back(at);
        if (k == count) break;
        uint32_t depthBytes, colorBytes;
        std::memcpy(&depthBytes, file.data() + at + 164, 4);
        std::memcpy(&colorBytes, file.data() + at + 168, 4);
        at += kRecordHeaderBytes + depthBytes + colorBytes;
    }
    return out;
}

std::string readBytes(const fs::path& path) { return test::readText(path); }

// Three small frames (the middle one without colour), saved as map 77.
struct SavedStore {
    fs::path dir, file;
    std::vector<StoredFrame> frames;
    std::string bytes;
};
SavedStore savedStore(const std::string& tag) {
    SavedStore s;
    s.dir = test::makeTempDir(tag);
    s.file = s.dir / "frames.vkframes";
    FrameStore store;
    for (uint32_t i : {3u, 7u, 8u}) {
        s.frames.push_back(makeFrame(i, 64, 48, i != 7));
        store.add(s.frames.back());
    }
    store.save(s.file.string(), 77);
    s.bytes = readBytes(s.file);
    return s;
}

}  // namespace

TEST(FrameStore, RoundTripIsBitExact) {
    FrameStore store;
    const StoredFrame withColor = makeFrame(5, 640, 480);
    const StoredFrame depthOnly = makeFrame(2, 640, 480, false);
    store.add(withColor);
    store.add(depthOnly);
    EXPECT_EQ(store.size(), 2u);
    EXPECT_TRUE(store.contains(5));
    EXPECT_FALSE(store.contains(3));
    EXPECT_EQ(store.indices(), (std::vector<uint32_t>{2, 5}));
    expectSameFrame(store.get(5), withColor);
    expectSameFrame(store.get(2), depthOnly);
    EXPECT_EQ(store.pose(5), withColor.pose);
    EXPECT_EQ(store.timestamp(2), depthOnly.timestamp);
}

TEST(FrameStore, EveryFloatBitPatternSurvives) {
    // Signed zeros, denormals, infinities, NaNs with payloads, extremes, and random bit patterns whose row deltas
    // wrap around 2^32.
    std::vector<float> special = {0.0f, -0.0f, std::numeric_limits<float>::denorm_min(), -std::numeric_limits<float>::denorm_min(),
                                  std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                                  std::bit_cast<float>(0x7fc00001u), std::bit_cast<float>(0xffbfffffu), std::numeric_limits<float>::max(),
                                  std::numeric_limits<float>::lowest(), 1.0f, 65.535f};
    std::mt19937 rng(9);
    while (special.size() < 7 * 5) special.push_back(std::bit_cast<float>(uint32_t(rng())));
    StoredFrame f;
    f.index = 0;
    f.intrinsics = intrinsicsFor(7, 5);
    f.depth = {7, 5, special};
    f.color = randomColor(7, 5, 1);
    FrameStore store;
    store.add(f);
    expectSameFrame(store.get(0), f);
}

TEST(FrameStore, CompressesRealisticDepth) {
    FrameStore store;
    store.add(makeFrame(0, 640, 480, false));
    const FrameStoreStats s = store.stats();
    EXPECT_EQ(s.rawBytes, 640u * 480 * 4);
    EXPECT_EQ(s.compressedBytes, s.bytesInMemory);
    std::cout << "[ INFO     ] 640x480 Kinect-like depth: " << s.rawBytes << " raw bytes, " << s.compressedBytes << " compressed ("
              << 100.0 * double(s.compressedBytes) / double(s.rawBytes) << " %)\n";
    // ~14 % here; real frames 9-10 % (tum_fr1_rpy, iclnuim_office_traj0 at level 3: bench/frame_store_bytes.cpp).
    EXPECT_LT(s.compressedBytes, s.rawBytes / 4);
}

TEST(FrameStore, SpillsPastTheBudgetAndReadsBack) {
    const fs::path spill = test::makeTempDir("frame_store_spill");
    std::vector<StoredFrame> frames;
    for (uint32_t i = 0; i < 5; ++i) frames.push_back(makeFrame(i, 160, 120, i % 2 == 0));
    FrameStoreStats s;
    {
        FrameStore probe;
        probe.add(frames[0]);
        FrameStoreOptions options;
        options.memoryBudgetBytes = 2 * probe.stats().compressedBytes;  // two frames, no more
        options.spillFolder = spill.string();
        FrameStore store(options);
        for (const StoredFrame& f : frames) store.add(f);
        s = store.stats();
        EXPECT_EQ(s.frames, 5u);
        EXPECT_GE(s.framesInMemory, 2u);
        EXPECT_GE(s.framesSpilled, 1u);
        EXPECT_EQ(s.framesInMemory + s.framesSpilled, 5u);
        EXPECT_LE(s.bytesInMemory, options.memoryBudgetBytes);
        EXPECT_GT(s.bytesOnDisk, 0u);
        EXPECT_EQ(s.compressedBytes, s.bytesInMemory + s.bytesOnDisk);
        size_t files = 0, fileBytes = 0;
        for (const auto& e : fs::recursive_directory_iterator(spill))
            if (e.is_regular_file()) ++files, fileBytes += e.file_size();
        EXPECT_EQ(files, s.framesSpilled);
        EXPECT_EQ(fileBytes, s.bytesOnDisk);
        for (const StoredFrame& f : frames) expectSameFrame(store.get(f.index), f);

        // A store moved from keeps nothing and removes nothing; the one moved to still reads its spill files.
        FrameStore moved = std::move(store);
        for (const StoredFrame& f : frames) expectSameFrame(moved.get(f.index), f);
    }
    // The store owns its spill files: gone with it, and the folder given is left (empty).
    EXPECT_TRUE(fs::exists(spill));
    EXPECT_TRUE(fs::is_empty(spill));
}

TEST(FrameStore, ChangedSpillFileIsAnError) {
    const fs::path spill = test::makeTempDir("frame_store_spill_changed");
    FrameStoreOptions options;
    options.memoryBudgetBytes = 0;
    options.spillFolder = spill.string();
    FrameStore store(options);
    store.add(makeFrame(4, 64, 48));
    fs::path file;
    for (const auto& e : fs::recursive_directory_iterator(spill))
        if (e.is_regular_file()) file = e.path();
    ASSERT_FALSE(file.empty());
    std::string bytes = readBytes(file);
    bytes[bytes.size() / 2] ^= 0x10;
    test::writeBytes(file, bytes);
    const std::string msg = errorMessageOf([&] { store.get(4); });
    EXPECT_NE(msg.find("spilled frame 4"), std::string::npos) << msg;
    EXPECT_NE(msg.find("CRC mismatch"), std::string::npos) << msg;
}

TEST(FrameStore, OverBudgetWithoutSpillFolderIsAnError) {
    std::vector<StoredFrame> frames;
    for (uint32_t i = 0; i < 5; ++i) frames.push_back(makeFrame(i, 64, 48, false));
    FrameStore probe;
    for (const StoredFrame& f : frames) probe.add(f);
    FrameStoreOptions options;
    options.memoryBudgetBytes = probe.stats().compressedBytes - 1;  // all but the last frame fit
    FrameStore store(options);
    for (size_t i = 0; i + 1 < frames.size(); ++i) store.add(frames[i]);
    const std::string msg = errorMessageOf([&] { store.add(frames.back()); });
    EXPECT_NE(msg.find("frame 4 "), std::string::npos) << msg;
    EXPECT_NE(msg.find("memory budget of " + std::to_string(options.memoryBudgetBytes) + " bytes"), std::string::npos) << msg;
    EXPECT_NE(msg.find("hold 4 frames"), std::string::npos) << msg;
    EXPECT_NE(msg.find("no spill folder"), std::string::npos) << msg;
    // Nothing dropped or half-added: the frames accepted are there, the refused one is not.
    EXPECT_EQ(store.indices(), (std::vector<uint32_t>{0, 1, 2, 3}));
    EXPECT_EQ(store.stats().rawBytes, 4u * 64 * 48 * 4);
    for (size_t i = 0; i + 1 < frames.size(); ++i) expectSameFrame(store.get(uint32_t(i)), frames[i]);
}

TEST(FrameStore, BadFramesAreErrors) {
    FrameStore store;
    store.add(makeFrame(1, 32, 24));
    EXPECT_NE(errorMessageOf([&] { store.add(makeFrame(1, 32, 24)); }).find("frame 1 is already stored"), std::string::npos);

    StoredFrame f = makeFrame(2, 32, 24);
    f.depth.meters.pop_back();
    EXPECT_NE(errorMessageOf([&] { store.add(f); }).find("767 samples, 32x24 needs 768"), std::string::npos);
    f = makeFrame(2, 32, 24);
    f.color = randomColor(16, 12, 0);
    EXPECT_NE(errorMessageOf([&] { store.add(f); }).find("not registered"), std::string::npos);
    f = makeFrame(2, 32, 24);
    f.intrinsics.width = 640;
    EXPECT_NE(errorMessageOf([&] { store.add(f); }).find("intrinsics are for 640x24"), std::string::npos);
    f = makeFrame(2, 32, 24);
    f.pose(1, 3) = std::nan("");
    EXPECT_NE(errorMessageOf([&] { store.add(f); }).find("pose is not finite"), std::string::npos);
    f = makeFrame(2, 32, 24);
    f.depth = {}, f.color = {}, f.intrinsics.width = f.intrinsics.height = 0;
    EXPECT_NE(errorMessageOf([&] { store.add(f); }).find("size 0x0 is empty"), std::string::npos);
    EXPECT_EQ(store.size(), 1u);
}

TEST(FrameStore, UnknownIndexIsAnErrorNamingIt) {
    FrameStore store;
    store.add(makeFrame(1, 32, 24));
    for (const std::string& msg : {errorMessageOf([&] { store.get(42); }), errorMessageOf([&] { store.pose(42); }),
                                   errorMessageOf([&] { store.timestamp(42); }), errorMessageOf([&] { store.setPose(42, Pose::Identity()); })})
        EXPECT_NE(msg.find("no frame 42"), std::string::npos) << msg;
}

TEST(FrameStore, SetPoseChangesThePoseOnly) {
    const fs::path dir = test::makeTempDir("frame_store_setpose");
    FrameStore store;
    const StoredFrame f = makeFrame(3, 64, 48);
    store.add(f);
    const Pose corrected = poseAt(11);
    store.setPose(3, corrected);
    EXPECT_EQ(store.pose(3), corrected);
    StoredFrame want = f;
    want.pose = corrected;
    expectSameFrame(store.get(3), want);
    Pose bad = corrected;
    bad(0, 0) = std::numeric_limits<double>::infinity();
    EXPECT_NE(errorMessageOf([&] { store.setPose(3, bad); }).find("not finite"), std::string::npos);
    EXPECT_EQ(store.pose(3), corrected);
    // ... and is what is saved.
    store.save((dir / "f.vkframes").string(), 1);
    expectSameFrame(FrameStore::load((dir / "f.vkframes").string(), 1).get(3), want);
}

TEST(FrameStore, SaveThenLoadRoundTrips) {
    const SavedStore s = savedStore("frame_store_save");
    EXPECT_EQ(FrameStore::mapIdOf(s.file.string()), 77u);
    EXPECT_FALSE(fs::exists(s.file.string() + ".tmp"));
    const FrameStore back = FrameStore::load(s.file.string(), 77);
    EXPECT_EQ(back.indices(), (std::vector<uint32_t>{3, 7, 8}));
    for (const StoredFrame& f : s.frames) expectSameFrame(back.get(f.index), f);

    // Loaded into a small budget: the frames past it spill, and all come back the same.
    FrameStoreOptions options;
    options.memoryBudgetBytes = 1;
    options.spillFolder = (s.dir / "spill").string();
    const FrameStore spilled = FrameStore::load(s.file.string(), 77, options);
    EXPECT_EQ(spilled.stats().framesSpilled, 3u);
    for (const StoredFrame& f : s.frames) expectSameFrame(spilled.get(f.index), f);
    // Saved again from spill files, the file is the same to the byte.
    spilled.save((s.dir / "again.vkframes").string(), 77);
    EXPECT_EQ(readBytes(s.dir / "again.vkframes"), s.bytes);

    // An empty store saves and loads too.
    FrameStore().save((s.dir / "empty.vkframes").string(), 5);
    EXPECT_EQ(FrameStore::load((s.dir / "empty.vkframes").string(), 5).size(), 0u);
}

TEST(FrameStore, FileOfAnotherMapIsAnError) {
    const SavedStore s = savedStore("frame_store_other_map");
    const std::string msg = errorMessageOf([&] { FrameStore::load(s.file.string(), 78); });
    EXPECT_NE(msg.find(s.file.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("belongs to another map (map id 77"), std::string::npos) << msg;
}

TEST(FrameStore, TruncatedFileIsAnErrorNamingTheRecord) {
    const SavedStore s = savedStore("frame_store_truncated");
    const std::vector<size_t> at = recordOffsets(s.bytes);
    ASSERT_EQ(at.back(), s.bytes.size());
    struct Cut {
        size_t size;
        std::string expect;
    };
    const std::vector<Cut> cuts = {
        {5, "wrong magic"},
        {20, "shorter than the 28-byte header"},
        {at[0] + 100, "frame record 0 of 3 is truncated: its header needs 176 bytes, 100 are left"},
        {at[1] + kRecordHeaderBytes + 10, "frame record 1 of 3 (frame 7) is truncated: its payload needs"},
        {at[3] - 1, "frame record 2 of 3 (frame 8) is truncated"},
    };
    for (const Cut& c : cuts) {
        const fs::path file = s.dir / ("cut" + std::to_string(c.size));
        test::writeBytes(file, s.bytes.substr(0, c.size));
        const std::string msg = errorMessageOf([&] { FrameStore::load(file.string(), 77); });
        EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
        EXPECT_NE(msg.find(c.expect), std::string::npos) << c.size << ": " << msg;
    }
    test::writeBytes(s.dir / "longer", s.bytes + "xyz");
    EXPECT_NE(errorMessageOf([&] { FrameStore::load((s.dir / "longer").string(), 77); }).find("3 bytes of trailing garbage"),
              std::string::npos);
}

TEST(FrameStore, FlippedByteIsACrcMismatch) {
    const SavedStore s = savedStore("frame_store_flipped");
    const std::vector<size_t> at = recordOffsets(s.bytes);
    // In a payload, in a pose, in a timestamp: each caught by its record's CRC.
    for (const size_t offset : {at[1] + kRecordHeaderBytes + 40, at[2] + 36 + 8 * 3, at[0] + 4}) {
        std::string bytes = s.bytes;
        bytes[offset] ^= 0x04;
        const fs::path file = s.dir / ("flip" + std::to_string(offset));
        test::writeBytes(file, bytes);
        const std::string msg = errorMessageOf([&] { FrameStore::load(file.string(), 77); });
        const size_t record = offset < at[1] ? 0 : offset < at[2] ? 1 : 2;
        EXPECT_NE(msg.find("frame record " + std::to_string(record) + " of 3"), std::string::npos) << msg;
        EXPECT_NE(msg.find("CRC mismatch"), std::string::npos) << msg;
    }
}

TEST(FrameStore, BadHeaderOrPayloadIsAnError) {
    const SavedStore s = savedStore("frame_store_bad");
    const auto loadError = [&](const std::string& name, const std::string& bytes) {
        const fs::path file = s.dir / name;
        test::writeBytes(file, bytes);
        const std::string msg = errorMessageOf([&] { FrameStore::load(file.string(), 77); });
        EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
        return msg;
    };
    std::string bytes = s.bytes;
    bytes[0] = 'X';
    EXPECT_NE(loadError("magic", bytes).find("not a vkmesh frame store"), std::string::npos);
    bytes = s.bytes;
    bytes[8] = 2;
    EXPECT_NE(loadError("version", bytes).find("version 2 is not supported"), std::string::npos);
    EXPECT_NE(errorMessageOf([&] { FrameStore::mapIdOf((s.dir / "version").string()); }).find("version 2"), std::string::npos);
    EXPECT_NE(errorMessageOf([&] { FrameStore::load((s.dir / "missing").string(), 77); }).find("cannot open"), std::string::npos);

    // A payload that is not what it claims, under a CRC that matches (a file not written by save()).
    const std::vector<size_t> at = recordOffsets(s.bytes);
    bytes = s.bytes;
    bytes[at[1] + kRecordHeaderBytes] ^= 0xFF;  // the first byte of the depth's zstd magic
    const size_t payload = at[2] - at[1] - kRecordHeaderBytes;
    const uint32_t crc = map::crc32(bytes.data() + at[1] + kRecordHeaderBytes, payload, map::crc32(bytes.data() + at[1], kRecordHeaderBytes - 4));
    std::memcpy(bytes.data() + at[1] + kRecordHeaderBytes - 4, &crc, 4);
    const std::string msg = loadError("zstd", bytes);
    EXPECT_NE(msg.find("frame record 1 of 3 (frame 7): corrupt depth payload"), std::string::npos) << msg;
}
