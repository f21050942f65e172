// Binary glTF (io/gltf.h), mesh files by extension (io/mesh_file.h) and simplification (io/mesh_simplify.h):
// a .glb reads back equal to the PLY of the same mesh, passes the Khronos glTF Validator, and bad files are
// errors naming the file; simplification keeps about the asked fraction and reports an honest error.
#include "eval/evaluate.h"
#include "io/gltf.h"
#include "io/mesh_file.h"
#include "io/mesh_simplify.h"
#include "io/ply.h"

#include "test_support.h"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <tuple>

using namespace vkmesh;
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

// A wavy 1 m x 1 m height field of n x n quads (2 (n-1)^2 triangles sharing their vertices), coloured by position
// so that every byte value 0..255 occurs in every channel, with unit normals and ages.
Mesh wavyField(int n) {
    Mesh m;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const float x = float(i) / float(n - 1), y = float(j) / float(n - 1);
            const float z = 0.05f * std::sin(6 * x) * std::cos(4 * y);
            m.positions.emplace_back(x, y, z);
            // The gradient of z gives the normal (-dz/dx, -dz/dy, 1).
            m.normals.push_back(Eigen::Vector3f(-0.3f * std::cos(6 * x) * std::cos(4 * y), 0.2f * std::sin(6 * x) * std::sin(4 * y), 1).normalized());
            const size_t k = m.positions.size() - 1;
            m.colors.push_back({uint8_t(k % 256), uint8_t((k / 7) % 256), uint8_t(255 - k % 256)});
            m.vertexAge.push_back(uint32_t(k * 13 % 100000));
        }
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const uint32_t a = uint32_t(j * n + i), b = a + 1, c = a + uint32_t(n), d = c + 1;
            m.triangles.push_back({a, b, d});
            m.triangles.push_back({a, d, c});
        }
    return m;
}

// Runs scripts/gltf_validate.js (the Khronos glTF Validator under node) on `files`: its exit code (77: the
// validator is not installed; -1: node is not there) and what it printed.
std::pair<int, std::string> khronosValidate(const std::vector<fs::path>& files, const fs::path& log) {
    if (std::system("command -v node >/dev/null 2>&1") != 0) return {-1, ""};
    std::string cmd = "node " + (fs::path(VKMESH_SOURCE_DIR) / "scripts" / "gltf_validate.js").string();
    for (const auto& f : files) cmd += " '" + f.string() + "'";
    const int status = std::system((cmd + " >'" + log.string() + "' 2>&1").c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -2, slurp(log)};
}

TEST(Gltf, ReadsBackEqualToThePlyOfTheSameMesh) {
    const fs::path dir = test::makeTempDir("gltf_roundtrip");
    Mesh mesh = wavyField(40);   // 1600 vertices: every byte value in every colour channel
    // Normals glTF would reject, which writeGlb must repair: not unit length, zero, and not finite.
    mesh.normals[3] *= 7.0f;
    mesh.normals[5] = Eigen::Vector3f::Zero();
    mesh.normals[9] = Eigen::Vector3f(std::numeric_limits<float>::quiet_NaN(), 0, 1);
    writePly(dir / "m.ply", mesh);
    writeGlb(dir / "m.glb", mesh);
    const Mesh ply = readPly(dir / "m.ply");
    const Mesh glb = readGlb(dir / "m.glb");
    ASSERT_EQ(glb.positions.size(), ply.positions.size());
    ASSERT_EQ(glb.colors.size(), ply.colors.size());
    ASSERT_EQ(glb.normals.size(), ply.normals.size());
    ASSERT_EQ(glb.vertexAge.size(), ply.vertexAge.size());
    ASSERT_EQ(glb.triangles.size(), ply.triangles.size());
    for (size_t i = 0; i < ply.positions.size(); ++i) {
        EXPECT_EQ(glb.positions[i], ply.positions[i]) << i;
        // sRGB bytes -> 16-bit linear -> sRGB bytes: exactly the bytes written.
        EXPECT_EQ(glb.colors[i], ply.colors[i]) << i;
        EXPECT_EQ(glb.vertexAge[i], ply.vertexAge[i]) << i;
        EXPECT_NEAR(glb.normals[i].norm(), 1.0f, 1e-6f) << i;
        if (i != 5 && i != 9) {
            EXPECT_LT((glb.normals[i] - ply.normals[i].normalized()).norm(), 1e-6f) << i;
        }
    }
    // The repaired normals are their vertices' face normals: near +Z on this gentle field.
    EXPECT_GT(glb.normals[5].z(), 0.9f);
    EXPECT_GT(glb.normals[9].z(), 0.9f);
    for (size_t t = 0; t < ply.triangles.size(); ++t) EXPECT_EQ(glb.triangles[t], ply.triangles[t]) << t;
    // Indices are 32 bit however few the vertices, and asset.generator names vkmesh.
    const std::string bytes = slurp(dir / "m.glb");
    EXPECT_NE(bytes.find("\"generator\":\"vkmesh\""), std::string::npos);
    EXPECT_NE(bytes.find("\"componentType\":5125"), std::string::npos);   // UNSIGNED_INT
    fs::remove_all(dir);
}

TEST(Gltf, PointCloudAndEmptyMesh) {
    const fs::path dir = test::makeTempDir("gltf_points");
    Mesh cloud = wavyField(10);
    cloud.triangles.clear();
    writeGlb(dir / "cloud.glb", cloud);
    const Mesh back = readGlb(dir / "cloud.glb");
    EXPECT_TRUE(back.triangles.empty());
    ASSERT_EQ(back.positions.size(), cloud.positions.size());
    for (size_t i = 0; i < cloud.positions.size(); ++i) {
        EXPECT_EQ(back.positions[i], cloud.positions[i]);
        EXPECT_EQ(back.colors[i], cloud.colors[i]);
    }
    EXPECT_NE(slurp(dir / "cloud.glb").find("\"mode\":0"), std::string::npos);   // POINTS
    // Without colours, normals or ages: only POSITION.
    Mesh bare = wavyField(5);
    bare.colors.clear(), bare.normals.clear(), bare.vertexAge.clear();
    writeGlb(dir / "bare.glb", bare);
    const Mesh bareBack = readGlb(dir / "bare.glb");
    EXPECT_TRUE(bareBack.colors.empty() && bareBack.normals.empty() && bareBack.vertexAge.empty());
    EXPECT_EQ(bareBack.triangles, bare.triangles);
    // An empty mesh is a valid file holding an empty scene, and reads back empty.
    writeGlb(dir / "empty.glb", Mesh{});
    const Mesh empty = readGlb(dir / "empty.glb");
    EXPECT_TRUE(empty.positions.empty() && empty.triangles.empty() && empty.colors.empty());
    fs::remove_all(dir);
}

TEST(Gltf, BadFilesAndMeshesAreErrorsNamingTheFile) {
    const fs::path dir = test::makeTempDir("gltf_bad");
    const fs::path good = dir / "good.glb";
    writeGlb(good, wavyField(6));
    const std::string bytes = slurp(good);
    auto expectError = [&](const std::string& name, const std::string& data, const std::string& what) {
        const fs::path p = dir / name;
        test::writeBytes(p, data);
        const std::string message = test::errorMessageOf([&] { readGlb(p); });
        EXPECT_NE(message.find(p.string()), std::string::npos) << message;
        EXPECT_NE(message.find(what), std::string::npos) << name << ": " << message;
    };
    expectError("empty.glb", "", "truncated");
    expectError("header.glb", bytes.substr(0, 12), "truncated");
    expectError("half.glb", bytes.substr(0, bytes.size() / 2), "truncated");
    expectError("text.glb", "{\"asset\":{\"version\":\"2.0\"}}                ", "magic");
    std::string version = bytes;
    version[4] = 1;
    expectError("version.glb", version, "version 1");
    std::string zero = bytes;   // a header length of 0 (found by fuzz_glb: it once wrapped around below 20)
    std::fill(zero.begin() + 8, zero.begin() + 12, '\0');
    expectError("zero_length.glb", zero, "less than a GLB header");
    std::string json = bytes;
    json[21] = '[';   // the JSON chunk's second character: no longer a JSON object
    expectError("json.glb", json, "not valid glTF");
    EXPECT_NE(test::errorMessageOf([&] { readGlb(dir / "missing.glb"); }).find("missing.glb"), std::string::npos);

    // Every truncation and 2000 random byte changes: an Error or a consistent mesh, never a crash.
    for (size_t n = 0; n < bytes.size(); n += 7) {
        try {
            parseGlb(std::string_view(bytes).substr(0, n), "cut.glb");
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("cut.glb"), std::string::npos) << e.what();
        }
    }
    std::mt19937 rng(5);
    for (int trial = 0; trial < 2000; ++trial) {
        std::string mutated = bytes;
        for (int k = 0; k < 3; ++k) mutated[rng() % mutated.size()] = char(rng());
        try {
            const Mesh m = parseGlb(mutated, "mutated.glb");
            for (const auto& t : m.triangles)
                for (uint32_t v : t) ASSERT_LT(v, m.positions.size());
            ASSERT_TRUE(m.colors.empty() || m.colors.size() == m.positions.size());
        } catch (const Error&) {
        }
    }

    // Meshes that cannot be written say why, naming the file.
    Mesh inconsistent = wavyField(3);
    inconsistent.colors.pop_back();
    const fs::path out = dir / "out.glb";
    EXPECT_NE(test::errorMessageOf([&] { writeGlb(out, inconsistent); }).find("colours"), std::string::npos);
    Mesh nan = wavyField(3);
    nan.positions[4].x() = std::numeric_limits<float>::infinity();
    const std::string message = test::errorMessageOf([&] { writeGlb(out, nan); });
    EXPECT_NE(message.find(out.string()), std::string::npos) << message;
    EXPECT_NE(message.find("vertex 4"), std::string::npos) << message;
    EXPECT_NE(test::errorMessageOf([&] { writeGlb(dir / "no_such_dir" / "m.glb", wavyField(3)); }).find("no_such_dir"), std::string::npos);
    fs::remove_all(dir);
}

TEST(Gltf, KhronosValidatorFindsNoErrorsOrWarnings) {
    const fs::path dir = test::makeTempDir("gltf_validator");
    Mesh mesh = wavyField(30);
    mesh.normals[2] = Eigen::Vector3f::Zero();   // repaired on writing
    Mesh cloud = wavyField(8);
    cloud.triangles.clear();
    Mesh bare = wavyField(4);
    bare.colors.clear(), bare.normals.clear(), bare.vertexAge.clear();
    writeGlb(dir / "mesh.glb", mesh);
    writeGlb(dir / "cloud.glb", cloud);
    writeGlb(dir / "bare.glb", bare);
    writeGlb(dir / "empty.glb", Mesh{});
    writeMesh(dir / "simplified.glb", simplifyMesh(mesh, 0.3));
    const auto [code, report] = khronosValidate({dir / "mesh.glb", dir / "cloud.glb", dir / "bare.glb", dir / "empty.glb",
                                                 dir / "simplified.glb"},
                                                dir / "validator.log");
    if (code == -1) GTEST_SKIP() << "node is not installed (apt-get install nodejs npm; npm install -g gltf-validator)";
    if (code == 77) GTEST_SKIP() << "the Khronos glTF Validator is not installed: npm install -g gltf-validator "
                                    "(scripts/install_deps.sh installs it when npm is there)";
    EXPECT_EQ(code, 0) << report;
    std::cout << report;
    fs::remove_all(dir);
}

TEST(MeshFile, WritesByExtensionAndRejectsUnknownOnes) {
    const fs::path dir = test::makeTempDir("mesh_file");
    const Mesh mesh = wavyField(4);
    writeMesh(dir / "a.ply", mesh);
    writeMesh(dir / "a.obj", mesh);
    writeMesh(dir / "a.GLB", mesh);
    writeMesh(dir / "noextension", mesh);   // PLY, as before there were several formats (e.g. -o /dev/null)
    EXPECT_EQ(slurp(dir / "a.ply").substr(0, 4), "ply\n");
    EXPECT_EQ(slurp(dir / "noextension").substr(0, 4), "ply\n");
    EXPECT_NE(slurp(dir / "a.obj").find("\nf "), std::string::npos);
    EXPECT_EQ(slurp(dir / "a.GLB").substr(0, 4), "glTF");
    EXPECT_EQ(readMesh(dir / "a.GLB").triangles, mesh.triangles);
    EXPECT_EQ(readMesh(dir / "a.ply").triangles, mesh.triangles);
    for (const char* name : {"a.gltf", "a.stl", "a.mesh"}) {
        const std::string message = test::errorMessageOf([&] { writeMesh(dir / name, mesh); });
        EXPECT_NE(message.find((dir / name).string()), std::string::npos) << message;
        for (const char* ext : {".ply", ".obj", ".glb"}) EXPECT_NE(message.find(ext), std::string::npos) << message;
        EXPECT_FALSE(fs::exists(dir / name));
    }
    fs::remove_all(dir);
}

// The largest distance from the surface of `simple` (sampled every `spacing`) to the surface of wavyField(n): the
// height difference to the original's triangle above or below each sample, exact for this height field (and at
// most 5% more than the distance along the normal: its slopes stay under 0.3).
double largestDeviation(const Mesh& simple, const Mesh& original, int n, double spacing) {
    double largest = 0;
    for (const Eigen::Vector3f& p : eval::sampleByArea(simple, spacing, 1)) {
        const double gx = std::clamp(double(p.x()) * (n - 1), 0.0, n - 1.000001), gy = std::clamp(double(p.y()) * (n - 1), 0.0, n - 1.000001);
        const int i = int(gx), j = int(gy);
        const double u = gx - i, v = gy - j;
        auto z = [&](int di, int dj) { return double(original.positions[size_t((j + dj) * n + i + di)].z()); };
        // The cell's triangles as wavyField makes them: (a, b, d) below the diagonal a-d, (a, d, c) above it.
        const double height = u >= v ? z(0, 0) + u * (z(1, 0) - z(0, 0)) + v * (z(1, 1) - z(1, 0))
                                     : z(0, 0) + v * (z(0, 1) - z(0, 0)) + u * (z(1, 1) - z(0, 1));
        largest = std::max(largest, std::abs(double(p.z()) - height));
    }
    return largest;
}

TEST(Simplify, KeepsAboutTheRatioWithAnHonestErrorAndTheColours) {
    const Mesh mesh = wavyField(120);   // 28322 triangles
    for (double ratio : {0.5, 0.25, 0.1}) {
        SimplifyReport report;
        const Mesh simple = simplifyMesh(mesh, ratio, &report);
        SCOPED_TRACE("ratio " + std::to_string(ratio));
        EXPECT_EQ(report.trianglesBefore, mesh.triangles.size());
        EXPECT_EQ(report.trianglesAfter, simple.triangles.size());
        EXPECT_LE(double(simple.triangles.size()), ratio * double(mesh.triangles.size()));
        EXPECT_GE(double(simple.triangles.size()), 0.9 * ratio * double(mesh.triangles.size()));
        // Every kept vertex is an original vertex with its own colour, normal and age; none is unreferenced.
        std::map<std::tuple<float, float, float>, size_t> original;
        for (size_t i = 0; i < mesh.positions.size(); ++i)
            original[{mesh.positions[i].x(), mesh.positions[i].y(), mesh.positions[i].z()}] = i;
        ASSERT_EQ(simple.colors.size(), simple.positions.size());
        ASSERT_EQ(simple.normals.size(), simple.positions.size());
        std::vector<bool> used(simple.positions.size(), false);
        for (const auto& t : simple.triangles)
            for (uint32_t v : t) used[v] = true;
        EXPECT_EQ(std::count(used.begin(), used.end(), false), 0);
        for (size_t i = 0; i < simple.positions.size(); ++i) {
            auto it = original.find({simple.positions[i].x(), simple.positions[i].y(), simple.positions[i].z()});
            ASSERT_NE(it, original.end()) << i;
            EXPECT_EQ(simple.colors[i], mesh.colors[it->second]);
            EXPECT_EQ(simple.normals[i], mesh.normals[it->second]);
            EXPECT_EQ(simple.vertexAge[i], mesh.vertexAge[it->second]);
        }
        // The reported error against the largest deviation measured independently. meshoptimizer's error is a
        // quadric estimate, an area-weighted mean of squared distances to the merged triangles' planes at the kept
        // vertices, not a maximum: on this field the largest deviation is 2.5 to 5.5 times the reported error
        // (docs/MESH_FILES.md). Held here: reported below measured, and measured within a factor of 8 of it.
        const double measured = largestDeviation(simple, mesh, 120, 0.002);
        std::cout << "ratio " << ratio << ": " << simple.triangles.size() << " of " << mesh.triangles.size() << " triangles, reported "
                  << 1000 * report.errorMetres << " mm, largest deviation measured " << 1000 * measured << " mm\n";
        EXPECT_GT(report.errorMetres, 0);
        EXPECT_LE(report.errorMetres, measured);
        EXPECT_LE(measured, 8 * report.errorMetres);
    }
}

TEST(Simplify, WeldsTriangleSoupsAndLeavesPointCloudsAlone) {
    const Mesh mesh = wavyField(40);
    Mesh soup;   // what --mode baseline exports: three vertices of its own per triangle
    for (const auto& t : mesh.triangles) {
        const uint32_t first = uint32_t(soup.positions.size());
        for (uint32_t v : t) {
            soup.positions.push_back(mesh.positions[v]);
            soup.colors.push_back(mesh.colors[v]);
        }
        soup.triangles.push_back({first, first + 1, first + 2});
    }
    SimplifyReport report;
    const Mesh simple = simplifyMesh(soup, 0.25, &report);
    EXPECT_LE(report.trianglesAfter, soup.triangles.size() / 4);
    EXPECT_GE(report.trianglesAfter, soup.triangles.size() / 5);
    EXPECT_LE(simple.positions.size(), mesh.positions.size());   // shared again
    Mesh cloud = mesh;
    cloud.triangles.clear();
    const Mesh same = simplifyMesh(cloud, 0.5, &report);
    EXPECT_EQ(same.positions, cloud.positions);
    EXPECT_EQ(report.trianglesAfter, 0u);
}

TEST(Simplify, RatioOutsideZeroToOneIsAnErrorNamingIt) {
    const Mesh mesh = wavyField(4);
    for (double bad : {0.0, -0.5, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
        const std::string message = test::errorMessageOf([&] { simplifyMesh(mesh, bad); });
        EXPECT_NE(message.find("(0, 1]"), std::string::npos) << message;
    }
    EXPECT_NE(test::errorMessageOf([&] { checkSimplifyRatio(1.5, "--simplify"); }).find("--simplify 1.5"), std::string::npos);
    EXPECT_EQ(simplifyMesh(mesh, 1.0).triangles.size(), mesh.triangles.size());
}

}  // namespace
