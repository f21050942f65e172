// Recording containers (ROS 1 bag, MCAP, rosbag2 SQLite) and the message decoders (io/recordings/): fixtures
// written at test time by tests/support/recording_writers.py (ROS 1 through Debian's python3-rosbag; MCAP and
// .db3 written there by the specs, CDR by hand), every message read back and decoded and compared with the
// values the script wrote (fixture_messages() there; the formulas are repeated below). Then hostile input:
// each broken file or message is a vkmesh::Error naming the file and the record, never a crash.
#include "io/recordings/container.h"
#include "io/recordings/messages.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;
using namespace vkmesh;
using namespace vkmesh::io::recording;
using test::errorMessageOf;

namespace {

void expectMentions(const std::string& message, std::initializer_list<std::string> needles) {
    for (const auto& n : needles) EXPECT_NE(message.find(n), std::string::npos) << "'" << n << "' not in: " << message;
}

const std::string kWriter = std::string(VKMESH_SOURCE_DIR) + "/tests/support/recording_writers.py";

// Empty when Debian's python3 has what the writers need, else why not (the tests then skip).
std::string pythonMissing() {
    static const std::string missing = [] {
        int rc = std::system("/usr/bin/python3 -c 'import rosbag, genpy, sensor_msgs.msg, tf2_msgs.msg, "
                             "zstandard, lz4.frame' >/dev/null 2>&1");
        return rc == 0 ? std::string()
                       : std::string("Debian's python3-rosbag, python3-sensor-msgs, python3-tf2-msgs, python3-zstandard "
                                     "or python3-lz4 is missing (scripts/install_deps.sh installs them)");
    }();
    return missing;
}

// The fixture of `kind` written once per test program (the writer takes a second or so per kind).
fs::path fixture(const std::string& kind, const std::string& options = "") {
    static std::mutex mutex;
    static std::map<std::string, fs::path> made;
    static const fs::path dir = test::makeTempDir("recordings");
    std::lock_guard lock(mutex);
    const std::string key = kind + " " + options;
    if (auto it = made.find(key); it != made.end()) return it->second;
    std::string name = kind + (options.empty() ? "" : "_" + std::to_string(made.size()));
    fs::path p = dir / (kind == "db3" ? name + ".db3" : kind == "db3-folder" ? name : name);
    std::string cmd = "/usr/bin/python3 " + kWriter + " fixture " + (kind == "db3-folder" ? "db3" : kind) + " '" +
                      p.string() + "' " + options;
    if (std::system(cmd.c_str()) != 0) ADD_FAILURE() << "failed: " << cmd;
    made[key] = p;
    return p;
}

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// The values recording_writers.py's fixture_messages() writes.
constexpr int kFrames = 6, kW = 8, kH = 6;
uint64_t frameTimeNs(int i) { return 1000000000ull + uint64_t(i) * 33333333ull; }

// Opens `path`, checks the topics, types and counts, decodes every message and compares it with what the
// writer wrote.
void checkFixture(const Container& c, const std::string& encoding) {
    SCOPED_TRACE(c.path().string());
    EXPECT_TRUE(c.warnings().empty()) << c.warnings().front();
    const std::map<std::string, std::pair<std::string, uint64_t>> expected = {
        {"/camera/depth/image_rect_raw", {"sensor_msgs/Image", kFrames}},
        {"/camera/color/image_raw", {"sensor_msgs/Image", kFrames}},
        {"/camera/depth/camera_info", {"sensor_msgs/CameraInfo", kFrames}},
        {"/tf", {"tf2_msgs/TFMessage", kFrames}},
        {"/device/depth_scale", {"std_msgs/Float32", 1}},
        {"/device/frame_count", {"std_msgs/UInt32", 1}},
        {"/device/name", {"std_msgs/String", 1}},
        {"/device/info", {"diagnostic_msgs/KeyValue", 1}},
        {"/extrinsics", {"geometry_msgs/Transform", 1}}};
    ASSERT_EQ(c.connections().size(), expected.size());
    for (size_t i = 0; i < c.connections().size(); ++i) {
        const Connection& k = c.connections()[i];
        EXPECT_EQ(k.id, i);
        auto it = expected.find(k.topic);
        ASSERT_NE(it, expected.end()) << k.topic;
        EXPECT_EQ(k.type, it->second.first) << k.topic;
        EXPECT_EQ(k.messageCount, it->second.second) << k.topic;
        EXPECT_EQ(k.encoding, encoding);
        EXPECT_EQ(k.serialization, encoding == "ros1" ? Serialization::Ros1 : Serialization::Cdr);
    }
    ASSERT_EQ(c.messages().size(), size_t(4 * kFrames + 5));
    std::map<std::string, int> seen;
    uint64_t last = 0;
    for (const MessageRef& m : c.messages()) {
        EXPECT_GE(m.logTimeNs, last);
        last = m.logTimeNs;
        const Connection& k = c.connections().at(m.connection);
        const int i = seen[k.topic]++;
        const uint64_t t = frameTimeNs(i);
        const std::vector<uint8_t> bytes = c.read(m);
        const std::string where = c.describe(m);
        const Serialization s = k.serialization;
        if (k.topic == "/camera/depth/image_rect_raw") {
            EXPECT_EQ(m.logTimeNs, t);
            ImageMessage img = decodeImage(bytes, s, where);
            EXPECT_EQ(img.header.stampNs, t);
            EXPECT_EQ(img.header.frameId, "camera_depth_optical_frame");
            EXPECT_EQ(img.width, uint32_t(kW));
            EXPECT_EQ(img.height, uint32_t(kH));
            EXPECT_EQ(img.encoding, "16UC1");
            EXPECT_FALSE(img.bigEndian);
            EXPECT_EQ(img.step, uint32_t(2 * kW));
            ASSERT_EQ(img.data.size(), size_t(2 * kW * kH));
            for (int y = 0; y < kH; ++y)
                for (int x = 0; x < kW; ++x) {
                    size_t o = size_t(2 * (y * kW + x));
                    ASSERT_EQ(img.data[o] | (img.data[o + 1] << 8), 1000 + 100 * i + 10 * y + x);
                }
        } else if (k.topic == "/camera/color/image_raw") {
            EXPECT_EQ(m.logTimeNs, t + 1000);
            ImageMessage img = decodeImage(bytes, s, where);
            EXPECT_EQ(img.header.stampNs, t + 1000);
            EXPECT_EQ(img.encoding, "rgb8");
            EXPECT_EQ(img.step, uint32_t(3 * kW));
            ASSERT_EQ(img.data.size(), size_t(3 * kW * kH));
            for (size_t b = 0; b < img.data.size(); ++b) ASSERT_EQ(img.data[b], uint8_t((i * 7 + b) & 255));
        } else if (k.topic == "/camera/depth/camera_info") {
            CameraInfoMessage ci = decodeCameraInfo(bytes, s, where);
            EXPECT_EQ(ci.header.stampNs, t);
            EXPECT_EQ(ci.width, uint32_t(kW));
            EXPECT_EQ(ci.height, uint32_t(kH));
            EXPECT_EQ(ci.distortionModel, "plumb_bob");
            EXPECT_EQ(ci.d, (std::vector<double>{0.1, -0.2, 0.001, 0.002, 0.0}));
            EXPECT_EQ(ci.k, (std::array<double, 9>{5.25 + i, 0, 3.5, 0, 5.5, 2.5, 0, 0, 1}));
            EXPECT_EQ(ci.r, (std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
            EXPECT_EQ(ci.p, (std::array<double, 12>{5.25 + i, 0, 3.5, 0, 0, 5.5, 2.5, 0, 0, 0, 1, 0}));
        } else if (k.topic == "/tf") {
            auto tf = decodeTfMessage(bytes, s, where);
            ASSERT_EQ(tf.size(), 2u);
            EXPECT_EQ(tf[0].header.frameId, "world");
            EXPECT_EQ(tf[0].childFrameId, "camera_link");
            EXPECT_EQ(tf[0].header.stampNs, t);
            EXPECT_EQ(tf[0].transform.translation, Eigen::Vector3d(0.1 * i, 0.2, 0.3));
            const double a = 0.1 * i;
            EXPECT_EQ(tf[0].transform.rotation.coeffs(), Eigen::Vector4d(0, 0, std::sin(a / 2), std::cos(a / 2)));
            EXPECT_EQ(tf[1].header.frameId, "camera_link");
            EXPECT_EQ(tf[1].childFrameId, "camera_depth_optical_frame");
            EXPECT_EQ(tf[1].transform.rotation.w(), 0.5);
            EXPECT_EQ(tf[1].transform.rotation.x(), -0.5);
        } else if (k.topic == "/device/depth_scale") {
            EXPECT_EQ(decodeFloat32(bytes, s, where), 0.001f);
        } else if (k.topic == "/device/frame_count") {
            EXPECT_EQ(decodeUInt32(bytes, s, where), uint32_t(kFrames));
        } else if (k.topic == "/device/name") {
            EXPECT_EQ(decodeString(bytes, s, where), "Intel RealSense D435");
        } else if (k.topic == "/device/info") {
            KeyValueMessage kv = decodeKeyValue(bytes, s, where);
            EXPECT_EQ(kv.key, "Serial Number");
            EXPECT_EQ(kv.value, "0123");
        } else if (k.topic == "/extrinsics") {
            TransformMessage tr = decodeTransform(bytes, s, where);
            EXPECT_EQ(tr.translation, Eigen::Vector3d(0.015, 0, 0));
            EXPECT_EQ(tr.rotation.w(), 1.0);
        }
    }
}

// Every message read from several threads at once gives the same bytes as one thread.
void checkConcurrentReads(const Container& c) {
    std::vector<std::vector<uint8_t>> expected;
    for (const auto& m : c.messages()) expected.push_back(c.read(m));
    std::atomic<int> mismatches{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            for (int round = 0; round < 5; ++round)
                for (size_t i = 0; i < c.messages().size(); ++i) {
                    size_t j = (i * 7 + size_t(t) * 5 + size_t(round)) % c.messages().size();
                    if (c.read(c.messages()[j]) != expected[j]) ++mismatches;
                }
        });
    for (auto& th : threads) th.join();
    EXPECT_EQ(mismatches.load(), 0);
}

class Fixtures : public ::testing::TestWithParam<const char*> {};

}  // namespace

// ---------------------------------------------------------------------------------------- well-formed files

TEST_P(Fixtures, EveryMessageDecodesToWhatWasWritten) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    const std::string kind = GetParam();
    fs::path p = fixture(kind);
    const ContainerKind expectedKind = kind.starts_with("ros1") ? ContainerKind::Ros1Bag
                                       : kind.starts_with("mcap") ? ContainerKind::Mcap
                                                                  : ContainerKind::Rosbag2Sqlite;
    EXPECT_EQ(detectContainer(p), expectedKind);
    auto c = openContainer(p);
    EXPECT_EQ(c->path(), p);
    EXPECT_EQ(c->formatName(), kind.starts_with("ros1") ? "ROS 1 bag" : kind.starts_with("mcap") ? "MCAP" : "rosbag2 SQLite");
    checkFixture(*c, kind.starts_with("ros1") ? "ros1" : "cdr");
    checkConcurrentReads(*c);
    // The same from bytes in memory.
    if (expectedKind != ContainerKind::Rosbag2Sqlite) {
        std::string bytes = slurp(p);
        auto m = expectedKind == ContainerKind::Ros1Bag ? openRos1Bag(bytes, "memory.bag") : openMcap(bytes, "memory.mcap");
        checkFixture(*m, kind.starts_with("ros1") ? "ros1" : "cdr");
    }
}

INSTANTIATE_TEST_SUITE_P(Recordings, Fixtures,
                         ::testing::Values("ros1-none", "ros1-bz2", "ros1-lz4", "mcap-none", "mcap-zstd", "mcap-lz4", "db3"),
                         [](const auto& info) {
                             std::string s = info.param;
                             for (char& ch : s)
                                 if (ch == '-') ch = '_';
                             return s;
                         });

TEST(Recordings, IndexingKeepsEachMessagesHeaderBytes) {
    // ROS 1 and MCAP chunks keep each message's first bytes while indexing: the header decoded from them is the
    // one the whole message holds, so a dataset need not read every image twice to pair and pose it.
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    for (const char* kind : {"ros1-bz2", "mcap-zstd"}) {
        auto c = openContainer(fixture(kind));
        size_t images = 0;
        for (const auto& m : c->messages()) {
            const Connection& k = c->connections()[m.connection];
            if (k.type != "sensor_msgs/Image") continue;
            ++images;
            ASSERT_GT(m.headSize, 0u) << kind;
            const auto head = decodeLeadingHeader(std::span(m.head.data(), m.headSize), k.serialization);
            ASSERT_TRUE(head.has_value()) << kind;
            const ImageMessage full = decodeImage(c->read(m), k.serialization, c->describe(m));
            EXPECT_EQ(head->stampNs, full.header.stampNs) << kind;
            EXPECT_EQ(head->frameId, full.header.frameId) << kind;
            // Too few bytes for the header: nothing, not an exception.
            EXPECT_FALSE(decodeLeadingHeader(std::span(m.head.data(), size_t(6)), k.serialization).has_value());
        }
        EXPECT_GT(images, 0u) << kind;
    }
}

TEST(Recordings, SeveralChunksAndUnchunkedMcap) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    // The ROS 1 fixture spans several chunks (chunk_threshold 1024): messages in the same chunk share its offset.
    auto c = openContainer(fixture("ros1-lz4"));
    std::set<uint64_t> chunks;
    for (const auto& m : c->messages()) chunks.insert(m.location[0]);
    EXPECT_GE(chunks.size(), 5u);
    // MCAP without chunks: message records at top level.
    auto u = openContainer(fixture("mcap-none", "chunk_messages=0"));
    checkFixture(*u, "cdr");
    for (const auto& m : u->messages()) EXPECT_EQ(m.location[1], 0u);
    // MCAP chunks with no CRC (0: not checked).
    checkFixture(*openContainer(fixture("mcap-zstd", "crc=0")), "cdr");
}

TEST(Recordings, Rosbag2FolderSplitOverSeveralFiles) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    fs::path dir = fixture("db3-folder", "split=4");
    EXPECT_EQ(detectContainer(dir), ContainerKind::Rosbag2Sqlite);
    auto c = openContainer(dir);
    checkFixture(*c, "cdr");
    std::set<uint64_t> files;
    for (const auto& m : c->messages()) files.insert(m.location[0]);
    EXPECT_EQ(files.size(), 8u);  // 29 messages, 4 a file
    expectMentions(c->describe(c->messages()[3]), {"row ", ".db3"});
    checkConcurrentReads(*c);
}

TEST(Recordings, Rosbag2FolderWithMcapStorage) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    fs::path dir = test::makeTempDir("rosbag2_mcap");
    fs::copy_file(fixture("mcap-zstd"), dir / "rec_0.mcap");
    test::writeBytes(dir / "metadata.yaml", "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n"
                                            "  relative_file_paths:\n    - rec_0.mcap\n");
    EXPECT_EQ(detectContainer(dir), ContainerKind::Mcap);
    checkFixture(*openContainer(dir), "cdr");
}

TEST(Recordings, DescribeNamesTheFileTopicAndRecord) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    auto c = openContainer(fixture("ros1-bz2"));
    const MessageRef& m = c->messages()[2];
    expectMentions(c->describe(m), {"ros1-bz2", "message 2 on /", "chunk at byte " + std::to_string(m.location[0])});
    EXPECT_EQ(detectContainer(fs::path(VKMESH_SOURCE_DIR) / "README.md"), ContainerKind::None);
    EXPECT_EQ(detectContainer(fs::path(VKMESH_SOURCE_DIR) / "no such file"), ContainerKind::None);
}

// -------------------------------------------------------------------------------------------- hostile input

namespace {

// `bytes` with the `n` bytes at the first occurrence of `what` (after `from`) replaced by `with`.
std::string patched(std::string bytes, const std::string& what, const std::string& with, size_t from = 0) {
    size_t p = bytes.find(what, from);
    EXPECT_NE(p, std::string::npos) << what;
    if (p != std::string::npos) bytes.replace(p, what.size(), with);
    return bytes;
}

std::string le32(uint32_t v) { return std::string{char(v), char(v >> 8), char(v >> 16), char(v >> 24)}; }

// Opening `bytes` either fails with an Error naming `name` or gives a container whose messages all read (or
// fail with an Error naming the file): never a crash, never another exception.
void openAndReadAll(const std::function<std::unique_ptr<Container>()>& open, const std::string& name, int& opened) {
    try {
        auto c = open();
        ++opened;
        for (const auto& m : c->messages()) {
            try {
                c->read(m);
            } catch (const Error& e) {
                expectMentions(e.what(), {name});
            }
        }
    } catch (const Error& e) {
        expectMentions(e.what(), {name});
    }
}

}  // namespace

TEST(HostileRecordings, TruncatedRos1Bag) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    const std::string bytes = slurp(fixture("ros1-bz2"));
    // Inside the magic: not a bag.
    expectMentions(errorMessageOf([&] { openRos1Bag(bytes.substr(0, 7), "cut.bag"); }), {"cut.bag", "not a ROS 1 bag"});
    // Inside the bag header record: nothing to read.
    expectMentions(errorMessageOf([&] { openRos1Bag(bytes.substr(0, 200), "cut.bag"); }),
                   {"cut.bag", "record at byte 13", "truncated", "before any complete chunk"});
    // Inside a later chunk: the chunks before it are read, with a warning.
    const size_t secondLastChunk = bytes.rfind("compression=bz2", bytes.rfind("compression=bz2") - 1);
    auto c = openRos1Bag(bytes.substr(0, secondLastChunk + 40), "cut.bag");
    ASSERT_EQ(c->warnings().size(), 1u);
    expectMentions(c->warnings()[0], {"cut.bag", "truncated", "runs past the end"});
    EXPECT_GT(c->messages().size(), 0u);
    EXPECT_LT(c->messages().size(), size_t(4 * kFrames + 5));
    for (const auto& m : c->messages()) c->read(m);
    // The index section cut off (the recorder killed after its last chunk): every message is there.
    auto whole = openRos1Bag(bytes.substr(0, bytes.rfind("compression=bz2") + 2000), "noindex.bag");
    EXPECT_GT(whole->messages().size(), c->messages().size());
    // Cut at every 53rd byte: an Error naming the file or a readable prefix, never anything else.
    int opened = 0;
    for (size_t n = 0; n < bytes.size(); n += 53)
        openAndReadAll([&] { return openRos1Bag(bytes.substr(0, n), "cut.bag"); }, "cut.bag", opened);
    EXPECT_GT(opened, 0);
}

TEST(HostileRecordings, Ros1ChunkSizesAndCompression) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    for (const char* kind : {"ros1-none", "ros1-bz2", "ros1-lz4"}) {
        SCOPED_TRACE(kind);
        const std::string bytes = slurp(fixture(kind));
        const std::string comp = std::string("compression=") + (kind + 5);
        const size_t chunk = bytes.find(comp);
        const size_t size = bytes.find("size=", chunk) + 5;
        // A size one byte off, and a hostile 4 GB size: refused before anything is allocated for it.
        std::string b = bytes;
        uint32_t declared = 0;
        std::memcpy(&declared, bytes.data() + size, 4);
        b.replace(size, 4, le32(declared + 1));
        expectMentions(errorMessageOf([&] { openRos1Bag(b, "size.bag"); }), {"size.bag", "record at byte", "chunk", "declares"});
        b.replace(size, 4, le32(0xFFFFFFF0u));
        expectMentions(errorMessageOf([&] { openRos1Bag(b, "size.bag"); }), {"size.bag", "record at byte", "limit"});
    }
    // An unknown compression.
    std::string b = patched(slurp(fixture("ros1-bz2")), "compression=bz2", "compression=gz2");
    expectMentions(errorMessageOf([&] { openRos1Bag(b, "gzip.bag"); }), {"gzip.bag", "record at byte", "unknown compression 'gz2'"});
    // Corrupt compressed data.
    b = slurp(fixture("ros1-lz4"));
    const size_t chunk = b.find("compression=lz4");
    // The first byte of the chunk's data (after size's value and the data length): the lz4 frame's magic.
    b[b.find("size=", chunk) + 13] ^= 0x5A;
    expectMentions(errorMessageOf([&] { openRos1Bag(b, "corrupt.bag"); }), {"corrupt.bag", "record at byte", "lz4"});
    b = slurp(fixture("ros1-bz2"));
    b[b.find("size=", b.find("compression=bz2")) + 13] ^= 0x5A;
    expectMentions(errorMessageOf([&] { openRos1Bag(b, "corrupt.bag"); }), {"corrupt.bag", "record at byte", "bz2"});
}

TEST(HostileRecordings, Ros1MagicOpsAndLocations) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    const fs::path dir = test::makeTempDir("hostile_bags");
    std::string bytes = slurp(fixture("ros1-none"));
    test::writeBytes(dir / "old.bag", patched(bytes, "#ROSBAG V2.0", "#ROSBAG V1.2"));
    expectMentions(errorMessageOf([&] { openContainer(dir / "old.bag"); }), {"old.bag", "version 1.2"});
    expectMentions(errorMessageOf([&] { openRos1Bag(patched(bytes, "#ROSBAG", "#RASBAG"), "magic.bag"); }),
                   {"magic.bag", "not a ROS 1 bag"});
    test::writeBytes(dir / "text.bag", "hello");
    expectMentions(errorMessageOf([&] { openContainer(dir / "text.bag"); }), {"text.bag", "not a recording"});
    expectMentions(errorMessageOf([&] { openContainer(dir / "missing.bag"); }), {"missing.bag", "no such file"});
    // An unknown op.
    expectMentions(errorMessageOf([&] { openRos1Bag(patched(bytes, std::string("op=\x05", 4), std::string("op=\x09", 4)), "op.bag"); }),
                   {"op.bag", "record at byte", "unknown op 0x09"});
    // A message on a connection the bag never defines.
    std::string conn = patched(bytes, std::string("conn=\x00\x00\x00\x00", 9), std::string("conn=\x63\x00\x00\x00", 9),
                               bytes.find(std::string("op=\x02", 4)) - 20);
    expectMentions(errorMessageOf([&] { openRos1Bag(conn, "conn.bag"); }), {"conn.bag", "connection 99", "does not define"});
    // A message record whose data runs past the end of its (uncompressed) chunk. Its header: op, conn, time
    // fields (8 + 13 + 17 bytes), then the data length.
    std::string past = bytes;
    const size_t op2 = past.find(std::string("op=\x02", 4));
    past.replace(op2 - 4 + 38, 4, le32(0x00FFFFFF));
    expectMentions(errorMessageOf([&] { openRos1Bag(past, "past.bag"); }),
                   {"past.bag", "(chunk), record at", "inside it", "truncated", "the record's data"});
    // An encrypted bag: named as such rather than failing as corrupt chunks.
    auto field = [](const std::string& f) { return le32(uint32_t(f.size())) + f; };
    std::string header = field(std::string("op=\x03", 4)) + field("encryptor=rosbag/AesCbcEncryptor");
    std::string enc = "#ROSBAG V2.0\n" + le32(uint32_t(header.size())) + header + le32(0);
    expectMentions(errorMessageOf([&] { openRos1Bag(enc, "secret.bag"); }), {"secret.bag", "record at byte 13", "encrypted"});
    // A MessageRef pointing past its chunk, or at no chunk.
    auto c = openRos1Bag(bytes, "ok.bag");
    MessageRef m = c->messages()[0];
    m.location[1] = 1u << 30;
    expectMentions(errorMessageOf([&] { c->read(m); }), {"ok.bag", "past the end of its chunk"});
    m.location[1] = 3;  // inside a record
    expectMentions(errorMessageOf([&] { c->read(m); }), {"ok.bag", "chunk at byte"});
    m.location[0] = 5;
    expectMentions(errorMessageOf([&] { c->read(m); }), {"ok.bag", "no chunk or message record starts at that byte"});
}

TEST(HostileRecordings, Mcap) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    const std::string bytes = slurp(fixture("mcap-none"));
    expectMentions(errorMessageOf([&] { openMcap(patched(bytes, "MCAP0", "MCAP9"), "magic.mcap"); }),
                   {"magic.mcap", "not an MCAP file"});
    // Truncated: the messages of complete chunks are kept, with a warning; nothing complete is an Error.
    expectMentions(errorMessageOf([&] { openMcap(bytes.substr(0, 30), "cut.mcap"); }), {"cut.mcap", "truncated"});
    auto c = openMcap(bytes.substr(0, bytes.size() / 2), "cut.mcap");
    ASSERT_EQ(c->warnings().size(), 1u);
    expectMentions(c->warnings()[0], {"cut.mcap", "truncated"});
    EXPECT_GT(c->messages().size(), 0u);
    // Without the footer: all messages, and a warning that the file was not closed.
    auto nf = openMcap(bytes.substr(0, bytes.size() - 8 - 29), "nofooter.mcap");
    EXPECT_EQ(nf->messages().size(), size_t(4 * kFrames + 5));
    ASSERT_EQ(nf->warnings().size(), 1u);
    expectMentions(nf->warnings()[0], {"nofooter.mcap", "no footer"});
    int opened = 0;
    for (const char* kind : {"mcap-none", "mcap-zstd", "mcap-lz4"}) {
        const std::string b = slurp(fixture(kind));
        for (size_t n = 0; n < b.size(); n += 41)
            openAndReadAll([&] { return openMcap(b.substr(0, n), "cut.mcap"); }, "cut.mcap", opened);
    }
    EXPECT_GT(opened, 0);
    std::string zstd = slurp(fixture("mcap-zstd"));
    expectMentions(errorMessageOf([&] { openMcap(patched(zstd, std::string("\x04\x00\x00\x00zstd", 8), std::string("\x04\x00\x00\x00gzip", 8)), "gz.mcap"); }),
                   {"gz.mcap", "record at byte", "unknown compression 'gzip'"});
    // A flipped byte inside an uncompressed chunk's records: its CRC-32 no longer matches.
    std::string crc = bytes;
    size_t rgb = crc.find("rgb8");
    crc[rgb + 40] ^= 1;
    expectMentions(errorMessageOf([&] { openMcap(crc, "crc.mcap"); }), {"crc.mcap", "record at byte", "chunk", "CRC-32"});
    auto ok = openMcap(bytes, "ok.mcap");
    MessageRef m = ok->messages()[0];
    m.location[1] = 1ull << 40;
    expectMentions(errorMessageOf([&] { ok->read(m); }), {"ok.mcap", "past the end of its chunk"});
}

TEST(HostileRecordings, McapChunkSizes) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    for (const char* kind : {"mcap-none", "mcap-zstd", "mcap-lz4"}) {
        SCOPED_TRACE(kind);
        const std::string bytes = slurp(fixture(kind));
        // The first chunk record: opcode 0x06 right after the last schema/channel record before it; found by
        // walking the records from the magic.
        size_t p = 8;
        while (p + 9 <= bytes.size() && bytes[p] != 0x06) {
            uint64_t len = 0;
            std::memcpy(&len, bytes.data() + p + 1, 8);
            p += 9 + len;
        }
        ASSERT_LT(p + 9 + 28, bytes.size());
        const size_t sizeField = p + 9 + 16;
        std::string b = bytes;
        b[sizeField] = char(b[sizeField] + 1);
        expectMentions(errorMessageOf([&] { openMcap(b, "size.mcap"); }),
                       {"size.mcap", "record at byte " + std::to_string(p), "declares"});
        b.replace(sizeField, 8, std::string("\xF0\xFF\xFF\xFF\xFF\x00\x00\x00", 8));
        expectMentions(errorMessageOf([&] { openMcap(b, "size.mcap"); }), {"size.mcap", "record at byte " + std::to_string(p), "limit"});
        // The records' length past the end of the chunk record.
        b = bytes;
        uint32_t compLen = 0;
        std::memcpy(&compLen, bytes.data() + sizeField + 12, 4);
        b.replace(sizeField + 16 + compLen, 8, std::string("\x00\x00\x00\x00\x01\x00\x00\x00", 8));
        expectMentions(errorMessageOf([&] { openMcap(b, "records.mcap"); }), {"records.mcap", "record at byte " + std::to_string(p), "run past"});
    }
}

TEST(HostileRecordings, Rosbag2Sqlite) {
    const fs::path dir = test::makeTempDir("hostile_db3");
    test::writeBytes(dir / "garbage.db3", std::string("SQLite format 3\0", 16) + std::string(2000, 'x'));
    expectMentions(errorMessageOf([&] { openContainer(dir / "garbage.db3"); }), {"garbage.db3"});
    fs::create_directories(dir / "bag");
    test::writeBytes(dir / "bag" / "metadata.yaml", "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n"
                                                    "  relative_file_paths:\n    - bag_0.db3\n");
    expectMentions(errorMessageOf([&] { openContainer(dir / "bag"); }), {"metadata.yaml", "bag_0.db3", "not in the folder"});
    EXPECT_EQ(detectContainer(dir / "bag"), ContainerKind::None);
    fs::create_directories(dir / "plain");
    expectMentions(errorMessageOf([&] { openContainer(dir / "plain"); }), {"plain", "metadata.yaml"});
}

// ------------------------------------------------------------------------------------------ hostile messages

namespace {

// A ROS 1 Image 16UC1 w x h with the given step.
std::vector<uint8_t> ros1Image(uint32_t w, uint32_t h, uint32_t step, uint32_t dataBytes, const std::string& frame = "f") {
    std::string s = le32(1) + le32(2) + le32(3) + le32(uint32_t(frame.size())) + frame + le32(h) + le32(w) + le32(5) +
                    "16UC1" + std::string(1, '\0') + le32(step) + le32(dataBytes) + std::string(dataBytes, '\x07');
    return std::vector<uint8_t>(s.begin(), s.end());
}

// The same in CDR little-endian (frame id with its NUL; fields aligned after the 4-byte header).
std::vector<uint8_t> cdrImage(uint32_t w, uint32_t h, uint32_t step, uint32_t dataBytes) {
    std::string s = std::string("\x00\x01\x00\x00", 4) + le32(2) + le32(3) + le32(2) + std::string("f\0", 2);
    while ((s.size() - 4) % 4) s += '\0';
    s += le32(h) + le32(w) + le32(6) + std::string("16UC1\0", 6);
    s += '\0';  // is_bigendian
    while ((s.size() - 4) % 4) s += '\0';
    s += le32(step) + le32(dataBytes) + std::string(dataBytes, '\x07');
    return std::vector<uint8_t>(s.begin(), s.end());
}

}  // namespace

TEST(HostileMessages, ImagesAndStrings) {
    const std::string where = "rec.bag, message 4 on /depth (chunk at byte 10)";
    // Well-formed, both serialisations.
    EXPECT_EQ(decodeImage(ros1Image(4, 3, 8, 24), Serialization::Ros1, where).data.size(), 24u);
    ImageMessage ci = decodeImage(cdrImage(4, 3, 8, 24), Serialization::Cdr, where);
    EXPECT_EQ(ci.header.frameId, "f");
    EXPECT_EQ(ci.header.stampNs, 2000000003u);
    EXPECT_EQ(ci.step, 8u);
    // step * height more than the data.
    for (auto s : {Serialization::Ros1, Serialization::Cdr}) {
        auto bytes = s == Serialization::Ros1 ? ros1Image(4, 3, 8, 20) : cdrImage(4, 3, 8, 20);
        expectMentions(errorMessageOf([&] { decodeImage(bytes, s, where); }),
                       {where, "sensor_msgs/Image", "step 8 x height 3 = 24 bytes", "holds 20"});
        // step * height overflowing 32 bits is still caught.
        bytes = s == Serialization::Ros1 ? ros1Image(4, 0x10000, 0x10000, 20) : cdrImage(4, 0x10000, 0x10000, 20);
        expectMentions(errorMessageOf([&] { decodeImage(bytes, s, where); }), {where, "4294967296 bytes"});
    }
    // A data length past the end (no allocation of it).
    auto bytes = ros1Image(4, 3, 8, 24);
    bytes.resize(bytes.size() - 10);
    expectMentions(errorMessageOf([&] { decodeImage(bytes, Serialization::Ros1, where); }), {where, "data", "cannot fit"});
    // A string length past the end, both serialisations.
    bytes = ros1Image(4, 3, 8, 24);
    bytes[12] = 0xFF;  // frame_id length
    expectMentions(errorMessageOf([&] { decodeImage(bytes, Serialization::Ros1, where); }), {where, "header.frame_id", "truncated"});
    bytes = cdrImage(4, 3, 8, 24);
    bytes[12] = 0xF0;
    bytes[15] = 0x7F;
    expectMentions(errorMessageOf([&] { decodeImage(bytes, Serialization::Cdr, where); }), {where, "header.frame_id", "truncated"});
    // A CDR string without its NUL.
    bytes = cdrImage(4, 3, 8, 24);
    bytes[17] = 'g';
    expectMentions(errorMessageOf([&] { decodeImage(bytes, Serialization::Cdr, where); }), {where, "NUL"});
    // Trailing garbage (ROS 1: none allowed; CDR: padding only).
    bytes = ros1Image(4, 3, 8, 24);
    bytes.push_back(0);
    expectMentions(errorMessageOf([&] { decodeImage(bytes, Serialization::Ros1, where); }), {where, "trailing"});
    bytes = cdrImage(4, 3, 8, 24);
    bytes.resize(bytes.size() + 3);
    EXPECT_NO_THROW(decodeImage(bytes, Serialization::Cdr, where));
    bytes.resize(bytes.size() + 9);
    expectMentions(errorMessageOf([&] { decodeImage(bytes, Serialization::Cdr, where); }), {where, "trailing"});
    // Encapsulations other than plain CDR.
    bytes = cdrImage(4, 3, 8, 24);
    bytes[1] = 3;
    expectMentions(errorMessageOf([&] { decodeImage(bytes, Serialization::Cdr, where); }), {where, "PL_CDR"});
    bytes[1] = 7;
    expectMentions(errorMessageOf([&] { decodeImage(bytes, Serialization::Cdr, where); }), {where, "XCDR2"});
    expectMentions(errorMessageOf([&] { decodeImage(std::vector<uint8_t>{0, 1}, Serialization::Cdr, where); }),
                   {where, "encapsulation header"});
}

TEST(HostileMessages, CountsAndBigEndianCdr) {
    const std::string where = "rec.mcap, message 1 on /tf";
    // A TFMessage claiming 2^32 - 1 transforms in 8 bytes: refused before allocating.
    std::string s = le32(0xFFFFFFFFu) + le32(0);
    std::vector<uint8_t> b(s.begin(), s.end());
    expectMentions(errorMessageOf([&] { decodeTfMessage(b, Serialization::Ros1, where); }), {where, "4294967295 elements"});
    // CameraInfo with a huge D.
    std::string ci = std::string("\x00\x01\x00\x00", 4) + le32(1) + le32(0) + le32(1) + std::string(1, '\0');
    while ((ci.size() - 4) % 4) ci += '\0';
    ci += le32(480) + le32(640) + le32(1) + std::string(1, '\0');
    while ((ci.size() - 4) % 4) ci += '\0';
    ci += le32(0x20000000);
    b.assign(ci.begin(), ci.end());
    expectMentions(errorMessageOf([&] { decodeCameraInfo(b, Serialization::Cdr, where); }), {where, "D", "cannot fit"});
    // Big-endian CDR: a UInt32 and a Float32.
    b = {0x00, 0x00, 0x00, 0x00, 0x12, 0x34, 0x56, 0x78};
    EXPECT_EQ(decodeUInt32(b, Serialization::Cdr, where), 0x12345678u);
    b = {0x00, 0x00, 0x00, 0x00, 0x3F, 0x80, 0x00, 0x00};
    EXPECT_EQ(decodeFloat32(b, Serialization::Cdr, where), 1.0f);
    // Empty input for every decoder: an Error naming `where`, in both serialisations.
    for (auto ser : {Serialization::Ros1, Serialization::Cdr}) {
        std::vector<uint8_t> e;
        expectMentions(errorMessageOf([&] { decodeImage(e, ser, where); }), {where});
        expectMentions(errorMessageOf([&] { decodeCameraInfo(e, ser, where); }), {where});
        expectMentions(errorMessageOf([&] { decodeTfMessage(e, ser, where); }), {where});
        expectMentions(errorMessageOf([&] { decodeTransform(e, ser, where); }), {where});
        expectMentions(errorMessageOf([&] { decodeFloat32(e, ser, where); }), {where});
        expectMentions(errorMessageOf([&] { decodeUInt32(e, ser, where); }), {where});
        expectMentions(errorMessageOf([&] { decodeString(e, ser, where); }), {where});
        expectMentions(errorMessageOf([&] { decodeKeyValue(e, ser, where); }), {where});
    }
}

// The fuzzers' seeds (fuzz/make_recording_seeds.py) are well-formed: fuzzing starts from files that open.
TEST(Recordings, FuzzSeedsOpen) {
    const fs::path corpus = fs::path(VKMESH_SOURCE_DIR) / "fuzz" / "corpus";
    int n = 0;
    for (const char* target : {"fuzz_ros1_bag", "fuzz_mcap"})
        for (const auto& e : fs::directory_iterator(corpus / target)) {
            SCOPED_TRACE(e.path().string());
            auto c = openContainer(e.path());
            EXPECT_TRUE(c->warnings().empty());
            EXPECT_EQ(c->messages().size(), 2u);
            for (const auto& m : c->messages()) {
                auto bytes = c->read(m);
                const Connection& k = c->connections()[m.connection];
                if (k.type == "sensor_msgs/Image") {
                    EXPECT_EQ(decodeImage(bytes, k.serialization, c->describe(m)).data.size(), 4u);
                }
            }
            ++n;
        }
    EXPECT_EQ(n, 7);
}

// rosbag2 rows that break the format: a topic_id the topics table does not list, a negative timestamp; and a
// topic in another serialisation, which is listed with its encoding (the dataset layer refuses to decode it).
TEST(HostileRecordings, Rosbag2Rows) {
    if (!pythonMissing().empty()) GTEST_SKIP() << pythonMissing();
    const fs::path dir = test::makeTempDir("hostile_db3_rows");
    auto write = [&](const std::string& name, const std::string& rows) {
        fs::path p = dir / name;
        std::string cmd = "/usr/bin/python3 -c \"import sqlite3; d = sqlite3.connect('" + p.string() +
                          "'); d.execute('CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, "
                          "serialization_format TEXT, offered_qos_profiles TEXT)'); d.execute('CREATE TABLE "
                          "messages(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER, data BLOB)'); "
                          "d.execute(\\\"INSERT INTO topics VALUES (1, '/t', 'std_msgs/msg/UInt32', 'json', '')\\\"); " +
                          rows + "; d.commit()\"";
        EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
        return p;
    };
    fs::path ok = write("json.db3", "d.execute(\\\"INSERT INTO messages VALUES (1, 1, 5, x'7b7d')\\\")");
    auto c = openContainer(ok);
    ASSERT_EQ(c->connections().size(), 1u);
    EXPECT_EQ(c->connections()[0].encoding, "json");
    EXPECT_EQ(c->connections()[0].type, "std_msgs/UInt32");
    EXPECT_EQ(c->read(c->messages()[0]), (std::vector<uint8_t>{'{', '}'}));
    MessageRef missing = c->messages()[0];
    missing.location[1] = 99;
    expectMentions(errorMessageOf([&] { c->read(missing); }), {"json.db3", "row 99", "no such row"});
    fs::path topic = write("topic.db3", "d.execute(\\\"INSERT INTO messages VALUES (7, 3, 5, x'00')\\\")");
    expectMentions(errorMessageOf([&] { openContainer(topic); }), {"topic.db3", "row 7", "topic_id 3"});
    fs::path negative = write("negative.db3", "d.execute(\\\"INSERT INTO messages VALUES (8, 1, -5, x'00')\\\")");
    expectMentions(errorMessageOf([&] { openContainer(negative); }), {"negative.db3", "row 8", "negative timestamp"});
}
