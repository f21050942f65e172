// Tests of PLY read/write and OBJ write.
#include "io/ply.h"

#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>

using namespace vkmesh;
namespace fs = std::filesystem;

namespace {

Mesh makeMesh(size_t nv, size_t nt, bool normals, bool age, unsigned seed = 7) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-10.0f, 10.0f);
    Mesh m;
    for (size_t i = 0; i < nv; ++i) {
        m.positions.emplace_back(u(rng), u(rng), u(rng));
        if (normals) m.normals.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
        if (age) m.vertexAge.push_back(uint32_t(rng()));
    }
    for (size_t i = 0; i < nt; ++i)
        m.triangles.push_back({uint32_t(rng() % nv), uint32_t(rng() % nv), uint32_t(rng() % nv)});
    if (age && nv > 1) m.vertexAge[1] = std::numeric_limits<uint32_t>::max();   // the largest age survives
    return m;
}

void expectSame(const Mesh& a, const Mesh& b) {
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(a.normals.size(), b.normals.size());
    ASSERT_EQ(a.vertexAge.size(), b.vertexAge.size());
    ASSERT_EQ(a.colors.size(), b.colors.size());
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    for (size_t i = 0; i < a.colors.size(); ++i) EXPECT_EQ(a.colors[i], b.colors[i]) << i;
    for (size_t i = 0; i < a.positions.size(); ++i) EXPECT_EQ(a.positions[i], b.positions[i]) << i;
    for (size_t i = 0; i < a.normals.size(); ++i) EXPECT_EQ(a.normals[i], b.normals[i]) << i;
    for (size_t i = 0; i < a.vertexAge.size(); ++i) EXPECT_EQ(a.vertexAge[i], b.vertexAge[i]) << i;
    for (size_t i = 0; i < a.triangles.size(); ++i) EXPECT_EQ(a.triangles[i], b.triangles[i]) << i;
}

std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

void spit(const fs::path& p, const std::string& s) {
    std::ofstream f(p, std::ios::binary);
    f.write(s.data(), std::streamsize(s.size()));
}

// Runs f, expects an Error whose message contains every one of `needles`.
template <typename F>
void expectError(F&& f, std::initializer_list<std::string> needles) {
    try {
        f();
        ADD_FAILURE() << "no vkmesh::Error thrown";
    } catch (const Error& e) {
        for (const auto& n : needles) EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what() << " lacks " << n;
    }
}

class PlyTest : public ::testing::Test {
protected:
    void SetUp() override { dir = test::makeTempDir("ply"); }
    void TearDown() override {
        if (!HasFailure()) fs::remove_all(dir);
    }
    fs::path dir;
};

}  // namespace

TEST_F(PlyTest, BinaryRoundTripAllVariants) {
    for (int variant = 0; variant < 4; ++variant) {
        const bool normals = variant & 1, age = variant & 2;
        const Mesh m = makeMesh(1000, 1700, normals, age, unsigned(variant));
        const fs::path p = dir / ("mesh" + std::to_string(variant) + ".ply");
        writePly(p, m);
        // Exact size: header + per-vertex payload + 13 bytes per triangle.
        const std::string bytes = slurp(p);
        const size_t header = bytes.find("end_header\n") + std::strlen("end_header\n");
        EXPECT_EQ(bytes.size() - header, 1000 * (12 + (normals ? 12 : 0) + (age ? 4 : 0)) + 1700 * 13u);
        SCOPED_TRACE("variant " + std::to_string(variant));
        expectSame(m, readPly(p));
    }
}

TEST_F(PlyTest, EmptyMeshAndPointCloudRoundTrip) {
    writePly(dir / "empty.ply", Mesh{});
    expectSame(Mesh{}, readPly(dir / "empty.ply"));
    const Mesh cloud = makeMesh(50, 0, true, false);
    writePly(dir / "cloud.ply", cloud);
    expectSame(cloud, readPly(dir / "cloud.ply"));
}

TEST_F(PlyTest, HeaderIsBinaryLittleEndianWithExpectedProperties) {
    const fs::path p = dir / "h.ply";
    writePly(p, makeMesh(4, 2, true, true));
    const std::string bytes = slurp(p);
    const std::string start = "ply\nformat binary_little_endian 1.0\n";
    ASSERT_GE(bytes.size(), start.size());
    EXPECT_EQ(bytes.substr(0, start.size()), start);
    const std::string header = bytes.substr(0, bytes.find("end_header\n") + 11);
    EXPECT_NE(header.find("element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                          "property float nx\nproperty float ny\nproperty float nz\nproperty uint age\n"
                          "element face 2\nproperty list uchar uint vertex_indices\nend_header\n"),
              std::string::npos)
        << header;
    // Little endian payload: the first float is x of vertex 0.
    const Mesh m = makeMesh(4, 2, true, true);
    float x;
    std::memcpy(&x, bytes.data() + header.size(), 4);
    EXPECT_EQ(x, m.positions[0].x());

    writePly(p, makeMesh(4, 2, false, false));
    const std::string plain = slurp(p);
    EXPECT_EQ(plain.find("nx"), std::string::npos);
    EXPECT_EQ(plain.find("age"), std::string::npos);
}

TEST_F(PlyTest, AsciiPointCloudWithDoublesNormalsAndUnknownProperties) {
    const fs::path p = dir / "gt.ply";
    spit(p,
         "ply\r\n"
         "format ascii 1.0\n"
         "comment ground truth\n"
         "obj_info scanner\n"
         "element vertex 3\n"
         "property double x\nproperty double y\nproperty double z\n"
         "property float nx\nproperty float ny\nproperty float nz\n"
         "property uchar red\nproperty uchar green\nproperty uchar blue\n"
         "property list uchar int extra\n"
         "end_header\n"
         "1.5 -2.25 3e-1 0 0 1 255 0 12 2 7 8\n"
         "  -1 +2 3   1 0 0 1 2 3 0\n"
         "0.125 0.25 0.5 0 1 0 9 9 9 1 -4\n");
    const Mesh m = readPly(p);
    ASSERT_EQ(m.positions.size(), 3u);
    ASSERT_EQ(m.normals.size(), 3u);
    EXPECT_TRUE(m.vertexAge.empty());
    EXPECT_TRUE(m.triangles.empty());
    EXPECT_EQ(m.positions[0], Eigen::Vector3f(1.5f, -2.25f, 0.3f));
    EXPECT_EQ(m.positions[1], Eigen::Vector3f(-1.0f, 2.0f, 3.0f));
    EXPECT_EQ(m.positions[2], Eigen::Vector3f(0.125f, 0.25f, 0.5f));
    EXPECT_EQ(m.normals[0], Eigen::Vector3f(0, 0, 1));
    EXPECT_EQ(m.normals[2], Eigen::Vector3f(0, 1, 0));
    ASSERT_EQ(m.colors.size(), 3u);
    EXPECT_EQ(m.colors[0], (std::array<uint8_t, 3>{255, 0, 12}));
    EXPECT_EQ(m.colors[1], (std::array<uint8_t, 3>{1, 2, 3}));
}

TEST_F(PlyTest, AsciiMeshWithPolygonsIsFanTriangulated) {
    const fs::path p = dir / "quad.ply";
    spit(p,
         "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
         "property int age\n"
         "element face 2\nproperty list uchar int vertex_index\nproperty uchar flags\n"
         "end_header\n"
         "0 0 0 5\n1 0 0 6\n1 1 0 7\n0 1 0 8\n2 2 2 9\n"
         "4 0 1 2 3 1\n3 2 4 3 0\n");
    const Mesh m = readPly(p);
    ASSERT_EQ(m.triangles.size(), 3u);
    EXPECT_EQ(m.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
    EXPECT_EQ(m.triangles[1], (std::array<uint32_t, 3>{0, 2, 3}));
    EXPECT_EQ(m.triangles[2], (std::array<uint32_t, 3>{2, 4, 3}));
    ASSERT_EQ(m.vertexAge.size(), 5u);
    EXPECT_EQ(m.vertexAge[4], 9u);
    EXPECT_TRUE(m.normals.empty());
}

TEST_F(PlyTest, BinaryPointCloudDoublesBigEndianAndExtraElements) {
    // Big-endian doubles with an unknown float property and an unknown element after the vertices.
    auto be = [](auto v) {
        std::string s(sizeof(v), '\0');
        std::memcpy(s.data(), &v, sizeof(v));
        if constexpr (std::endian::native == std::endian::little) std::reverse(s.begin(), s.end());
        return s;
    };
    std::string body;
    for (int i = 0; i < 4; ++i) {
        body += be(double(i) + 0.5) + be(double(-i)) + be(double(i) * 1e-3);
        body += be(float(42.0f));  // "confidence"
    }
    body += be(int32_t(1)) + be(int32_t(2));  // one "edge" entry
    spit(dir / "be.ply", "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
                         "property double z\nproperty float confidence\nelement edge 1\nproperty int vertex1\n"
                         "property int vertex2\nend_header\n" + body);
    const Mesh m = readPly(dir / "be.ply");
    ASSERT_EQ(m.positions.size(), 4u);
    EXPECT_TRUE(m.normals.empty());
    for (int i = 0; i < 4; ++i)
        EXPECT_EQ(m.positions[i], Eigen::Vector3d(i + 0.5, -i, i * 1e-3).cast<float>()) << i;
}

TEST_F(PlyTest, TruncatedFileIsAnErrorNamingThePath) {
    const fs::path p = dir / "trunc.ply";
    writePly(p, makeMesh(100, 100, true, true));
    const std::string full = slurp(p);
    for (size_t cut : {size_t(1), size_t(7), size_t(13 * 100), full.size() - full.find("end_header") - 11}) {
        spit(p, full.substr(0, full.size() - cut));
        expectError([&] { readPly(p); }, {p.string(), "truncated"});
    }
    // Header cut short.
    spit(p, full.substr(0, 40));
    expectError([&] { readPly(p); }, {p.string(), "end_header"});
    // Ascii cut short.
    spit(p, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
            "end_header\n1 2 3\n4 5\n");
    expectError([&] { readPly(p); }, {p.string(), "truncated"});
}

TEST_F(PlyTest, CorruptAndUnsupportedFilesAreErrors) {
    const fs::path p = dir / "bad.ply";
    expectError([&] { readPly(dir / "missing.ply"); }, {(dir / "missing.ply").string(), "cannot open"});
    spit(p, "OFF\n3 1 0\n");
    expectError([&] { readPly(p); }, {p.string(), "not a PLY"});
    spit(p, "ply\nformat binary_middle_endian 1.0\nelement vertex 0\nproperty float x\nend_header\n");
    expectError([&] { readPly(p); }, {p.string(), "unsupported format"});
    spit(p, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
            "property int128 w\nend_header\n1 2 3 4\n");
    expectError([&] { readPly(p); }, {p.string(), "int128"});
    spit(p, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
            "end_header\n1 two 3\n");
    expectError([&] { readPly(p); }, {p.string(), "'two'"});
    spit(p, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n1 2 3\n3 0 0 1\n");
    expectError([&] { readPly(p); }, {p.string(), "vertex 1"});
    spit(p, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n");
    expectError([&] { readPly(p); }, {p.string(), "x, y, z"});
    // A huge declared count with a tiny body must not try to allocate it.
    spit(p, "ply\nformat binary_little_endian 1.0\nelement vertex 999999999999\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n\x01\x02");
    expectError([&] { readPly(p); }, {p.string(), "truncated"});
}

TEST_F(PlyTest, WritingErrorsNameTheFile) {
    const fs::path p = dir / "no_such_dir" / "out.ply";
    expectError([&] { writePly(p, makeMesh(3, 1, false, false)); }, {p.string(), "cannot open"});
    expectError([&] { writeObj(dir / "no_such_dir" / "out.obj", makeMesh(3, 1, false, false)); },
                {(dir / "no_such_dir" / "out.obj").string()});
    Mesh bad = makeMesh(3, 1, true, false);
    bad.normals.pop_back();
    expectError([&] { writePly(dir / "bad.ply", bad); }, {(dir / "bad.ply").string(), "normals"});
    bad = makeMesh(3, 1, false, false);
    bad.triangles[0][2] = 3;
    expectError([&] { writePly(dir / "bad.ply", bad); }, {(dir / "bad.ply").string(), "vertex 3"});
}

TEST_F(PlyTest, ObjHasOneBasedFacesAndNormals) {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1.5f, 0}};
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    m.triangles = {{0, 1, 2}};
    writeObj(dir / "m.obj", m);
    std::istringstream in(slurp(dir / "m.obj"));
    std::string line;
    std::vector<std::string> lines;
    while (std::getline(in, line))
        if (!line.empty() && line[0] != '#') lines.push_back(line);
    ASSERT_EQ(lines.size(), 7u);
    EXPECT_EQ(lines[0], "v 0 0 0");
    EXPECT_EQ(lines[2], "v 0 1.5 0");
    EXPECT_EQ(lines[3], "vn 0 0 1");
    EXPECT_EQ(lines[6], "f 1//1 2//2 3//3");
    m.normals.clear();
    writeObj(dir / "m.obj", m);
    EXPECT_NE(slurp(dir / "m.obj").find("\nf 1 2 3\n"), std::string::npos);
}

TEST_F(PlyTest, ColorsRoundTripAsUcharRedGreenBlue) {
    Mesh m = makeMesh(300, 500, true, true, 11);
    for (size_t i = 0; i < m.positions.size(); ++i)
        m.colors.push_back({uint8_t(i), uint8_t(255 - i % 256), uint8_t(i * 7)});
    const fs::path p = dir / "c.ply";
    writePly(p, m);
    const std::string bytes = slurp(p);
    const size_t header = bytes.find("end_header\n") + std::strlen("end_header\n");
    // The order Open3D writes too: position, normal, colour (then vkmesh's age).
    EXPECT_NE(bytes.find("property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                         "property uint age\n"),
              std::string::npos);
    EXPECT_EQ(bytes.size() - header, 300 * (12 + 12 + 3 + 4) + 500 * 13u);
    expectSame(m, readPly(p));
    // Without colours nothing is declared.
    writePly(p, makeMesh(3, 1, false, false));
    EXPECT_EQ(slurp(p).find("red"), std::string::npos);
}

TEST_F(PlyTest, Open3DStyleFloatAndDiffuseColorsAreRead) {
    // Open3D writes point clouds with double x y z and uchar colours; PCL and some tools write float
    // colours in 0..1; older scanners write diffuse_red. Out-of-range floats clamp.
    const fs::path p = dir / "o3d.ply";
    spit(p,
         "ply\nformat ascii 1.0\ncomment Created by Open3D\nelement vertex 3\n"
         "property double x\nproperty double y\nproperty double z\n"
         "property float red\nproperty float green\nproperty float blue\nend_header\n"
         "0 0 0 1 0.5 0\n1 0 0 0.2 2.0 -1\n0 1 0 0 0 0.00196\n");
    Mesh m = readPly(p);
    ASSERT_EQ(m.colors.size(), 3u);
    EXPECT_EQ(m.colors[0], (std::array<uint8_t, 3>{255, 128, 0}));
    EXPECT_EQ(m.colors[1], (std::array<uint8_t, 3>{51, 255, 0}));
    EXPECT_EQ(m.colors[2], (std::array<uint8_t, 3>{0, 0, 0}));
    spit(p,
         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
         "property uchar diffuse_red\nproperty uchar diffuse_green\nproperty uchar diffuse_blue\nend_header\n"
         "0 0 0 10 20 30\n");
    m = readPly(p);
    ASSERT_EQ(m.colors.size(), 1u);
    EXPECT_EQ(m.colors[0], (std::array<uint8_t, 3>{10, 20, 30}));
    // Only red and green: no colours rather than a guessed blue.
    spit(p,
         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
         "property uchar red\nproperty uchar green\nend_header\n0 0 0 10 20\n");
    EXPECT_TRUE(readPly(p).colors.empty());
    Mesh bad = makeMesh(3, 1, false, false);
    bad.colors.resize(2);
    expectError([&] { writePly(dir / "bad.ply", bad); }, {(dir / "bad.ply").string(), "colours"});
}

TEST_F(PlyTest, ObjWritesVertexColorsAsFloats) {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1.5f, 0}};
    m.colors = {{255, 0, 0}, {0, 51, 0}, {0, 0, 0}};
    m.triangles = {{0, 1, 2}};
    writeObj(dir / "c.obj", m);
    const std::string text = slurp(dir / "c.obj");
    EXPECT_NE(text.find("\nv 0 0 0 1 0 0\n"), std::string::npos) << text;
    EXPECT_NE(text.find("\nv 1 0 0 0 0.2 0\n"), std::string::npos) << text;
    EXPECT_NE(text.find("\nv 0 1.5 0 0 0 0\n"), std::string::npos) << text;
}
