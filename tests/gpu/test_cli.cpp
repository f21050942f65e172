// The vkmesh program end to end: a synthetic sequence in, a mesh and stats out; bad input gives a
// clear error (exit code != 0) or, for a single bad frame, a warning and the frame skipped.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

#include <Eigen/Geometry>

#include "core/camera.h"
#include "core/mesh_analysis.h"
#include "io/gltf.h"
#include "io/ply.h"
#include "io/trajectory.h"
#include "test_support.h"

namespace vkmesh {
namespace {

namespace fs = std::filesystem;

using test::CliRun;
using test::readText;
using test::runCli;

// A small synthetic sequence, made once for all the test programs of the build (tests copy it before changing it).
// Coarse ground-truth points: no test here evaluates against them, and the default 5 mm took ~3.5 s to write.
const fs::path& smallSequence() {
    static const fs::path dir = test::sharedSynthSequence("cli_small", "--frames 6 --width 160 --height 120 --gt-spacing 0.05");
    return dir;
}

fs::path copyOfSmallSequence(const std::string& tag) {
    fs::path d = test::makeTempDir(tag);
    fs::copy(smallSequence(), d, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    return d;
}

TEST(Cli, DevicesListsAUsableDevice) {
    CliRun r = runCli("devices");
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("0: "), std::string::npos) << r.out;
}

TEST(Cli, FuseWritesMeshAndStats) {
    fs::path out = test::makeTempDir("cli_fuse");
    CliRun r = runCli("fuse " + smallSequence().string() + " -o " + (out / "mesh.ply").string() + " --stats " +
                   (out / "stats.json").string() + " --voxel 0.04 --validation --analyse-mesh");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err.find("[validation"), std::string::npos) << r.err;
    Mesh mesh = readPly(out / "mesh.ply");
    EXPECT_GT(mesh.triangles.size(), 1000u);
    // The shared-vertex mesh: about half as many vertices as triangles, each with a normal and an age.
    EXPECT_LT(mesh.positions.size(), mesh.triangles.size());
    EXPECT_EQ(mesh.normals.size(), mesh.positions.size());
    ASSERT_EQ(mesh.vertexAge.size(), mesh.positions.size());
    EXPECT_LT(*std::max_element(mesh.vertexAge.begin(), mesh.vertexAge.end()), 6u);
    auto stats = nlohmann::json::parse(readText(out / "stats.json"));
    EXPECT_EQ(stats["frames"]["integrated"], 6);
    EXPECT_EQ(stats["frames"]["skipped"], 0);
    EXPECT_EQ(stats["mesh"]["triangles"], mesh.triangles.size());
    EXPECT_GT(stats["blocks"]["in_use"].get<int>(), 0);
    EXPECT_TRUE(stats["gpu_ms_per_frame"].contains("allocate"));
    EXPECT_TRUE(stats["gpu_ms_per_frame"]["fuse"].contains("median"));
    EXPECT_GT(stats["gpu_pool_bytes"]["voxel sdf"].get<size_t>(), 0u);
    EXPECT_TRUE(stats["gpu_ms_per_frame"].contains("mesh_triangulate"));
    // Refinement is on by default: the mesh differs from the baseline (plain MC, 3 vertices per triangle, on
    // the same TSDF), which it equals with --no-refine (below).
    EXPECT_TRUE(stats["refine"].get<bool>());
    EXPECT_TRUE(stats["mesh"]["analysed"].get<bool>());
    EXPECT_NE(stats["mesh"]["baseline_vertices"].get<size_t>(), 3 * mesh.triangles.size());
    EXPECT_TRUE(stats["mesh"].contains("boundary_edges"));
    EXPECT_TRUE(stats["mesh"].contains("non_manifold_edges"));
    EXPECT_EQ(stats["mesh"]["unreferenced_vertices"], 0);
    EXPECT_EQ(stats["mesh"]["coincident_vertices"], 0);   // one vertex per position, refined too
    EXPECT_EQ(countDuplicatePositions(mesh), 0u);
    EXPECT_EQ(stats["heaps"]["vertices"]["live"], mesh.positions.size());
    // The synthetic sequence has colour: fused by default (4 bytes per cube), on every vertex of the PLY.
    EXPECT_EQ(stats["bytes_per_cube"], 28);
    EXPECT_TRUE(stats["color"]["fused"].get<bool>());
    EXPECT_EQ(stats["color"]["frames_with_color"], 6);
    EXPECT_EQ(mesh.colors.size(), mesh.positions.size());
    // Every vertex lies in the synthetic room (4 x 3 x 2.5 m around the origin, turned 20 degrees).
    for (const auto& p : mesh.positions) ASSERT_LT(p.norm(), 4.0f);

    r = runCli("fuse " + smallSequence().string() + " -o " + (out / "plain.ply").string() + " --stats " +
               (out / "plain.json").string() + " --voxel 0.04 --no-refine --analyse-mesh");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const Mesh plain = readPly(out / "plain.ply");
    stats = nlohmann::json::parse(readText(out / "plain.json"));
    EXPECT_FALSE(stats["refine"].get<bool>());
    EXPECT_EQ(stats["mesh"]["baseline_vertices"].get<size_t>(), 3 * plain.triangles.size());

    // --no-stage-times: no GPU timestamps, so no stage times in --stats or the summary; the same mesh.
    r = runCli("fuse " + smallSequence().string() + " -o " + (out / "untimed.ply").string() + " --stats " +
               (out / "untimed.json").string() + " --voxel 0.04 --no-stage-times");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("GPU stages not timed"), std::string::npos) << r.out;
    stats = nlohmann::json::parse(readText(out / "untimed.json"));
    EXPECT_TRUE(stats["gpu_ms_per_frame"].empty()) << stats["gpu_ms_per_frame"].dump();
    EXPECT_GT(stats["wall_ms_per_frame"]["median"].get<double>(), 0.0);
    // Without --analyse-mesh the analyses are not run: their keys stay, null.
    EXPECT_FALSE(stats["mesh"]["analysed"].get<bool>());
    for (const char* key : {"baseline_vertices", "vertices_vs_baseline", "sliver_triangle_share", "irregular_cube_share", "boundary_edges",
                            "non_manifold_edges", "coincident_vertices"})
        EXPECT_TRUE(stats["mesh"].contains(key) && stats["mesh"][key].is_null()) << key;
    EXPECT_EQ(stats["mesh"]["unreferenced_vertices"], 0);
    // -q without --stats: nothing reads the stage times, so none are recorded (the summary says so).
    r = runCli("fuse " + smallSequence().string() + " -o " + (out / "quiet.ply").string() + " --voxel 0.04 -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("GPU stages not timed: -q without --stats"), std::string::npos) << r.out;
    // Compared as sets of triangles by their corner positions (the export's order is not fixed).
    auto triangleSet = [](const Mesh& m) {
        std::set<std::array<float, 9>> set;
        for (const auto& t : m.triangles) {
            std::array<float, 9> key{};
            for (int j = 0; j < 3; ++j)
                for (int a = 0; a < 3; ++a) key[size_t(3 * j + a)] = m.positions[t[j]][a];
            set.insert(key);
        }
        return set;
    };
    const Mesh untimed = readPly(out / "untimed.ply");
    EXPECT_EQ(untimed.triangles.size(), mesh.triangles.size());
    EXPECT_TRUE(triangleSet(untimed) == triangleSet(mesh));
    EXPECT_TRUE(triangleSet(readPly(out / "quiet.ply")) == triangleSet(mesh));

    // --pass-times: each pass's time by shader name beside the stage times, which still span their passes; the
    // same mesh. Without stage times there is nothing to time the passes against.
    r = runCli("fuse " + smallSequence().string() + " -o " + (out / "passes.ply").string() + " --stats " +
               (out / "passes.json").string() + " --voxel 0.04 --pass-times");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    stats = nlohmann::json::parse(readText(out / "passes.json"));
    const nlohmann::json& passes = stats["gpu_ms_per_pass"];
    const nlohmann::json& stages = stats["gpu_ms_per_frame"];
    ASSERT_TRUE(passes.contains("fuse_depth[1]")) << passes.dump();   // [1]: the integrating specialisation
    for (const char* pass : {"allocate_blocks[1]", "mesh_claim", "mesh_triangulate", "move_vertices"})
        EXPECT_TRUE(passes.contains(pass)) << pass << " in " << passes.dump();
    EXPECT_GT(passes["fuse_depth[1]"]["median"].get<double>(), 0.0);
    // The fuse stage is the one pass and its barrier: the pass cannot take longer than the stage.
    EXPECT_LE(passes["fuse_depth[1]"]["median"].get<double>(), stages["fuse"]["median"].get<double>() * 1.0001);
    double passSum = 0, stageSum = 0;
    for (const auto& [name, s] : passes.items()) passSum += s["median"].get<double>();
    for (const char* stage : {"allocate", "fuse", "mesh_mark", "mesh_claim", "mesh_update", "mesh_triangulate", "mesh_gc"})
        stageSum += stages[stage]["median"].get<double>();
    EXPECT_GT(passSum, 0.5 * stageSum) << "the passes are most of the frame";
    EXPECT_TRUE(triangleSet(readPly(out / "passes.ply")) == triangleSet(mesh));
    r = runCli("fuse " + smallSequence().string() + " -o " + (out / "x.ply").string() + " --pass-times --no-stage-times");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("--pass-times"), std::string::npos) << r.err;
    fs::remove_all(out);
}

// --no-color: depth only, the same geometry, 24 bytes per cube, a PLY without colours; render draws the
// coloured mesh in its colours by default.
TEST(Cli, NoColorFusesDepthOnlyAndRenderUsesTheColours) {
    fs::path out = test::makeTempDir("cli_no_color");
    const std::string common = smallSequence().string() + " --voxel 0.04 --frames 3";
    CliRun grey = runCli("fuse " + common + " --no-color -o " + (out / "grey.ply").string() + " --stats " + (out / "grey.json").string());
    ASSERT_EQ(grey.exitCode, 0) << grey.err;
    CliRun colour = runCli("fuse " + common + " -o " + (out / "colour.ply").string());
    ASSERT_EQ(colour.exitCode, 0) << colour.err;
    auto stats = nlohmann::json::parse(readText(out / "grey.json"));
    EXPECT_EQ(stats["bytes_per_cube"], 24);
    EXPECT_FALSE(stats["color"]["fused"].get<bool>());
    EXPECT_TRUE(stats["color"]["dataset_has_color"].get<bool>());
    const Mesh a = readPly(out / "grey.ply"), b = readPly(out / "colour.ply");
    EXPECT_TRUE(a.colors.empty());
    ASSERT_EQ(b.colors.size(), b.positions.size());
    EXPECT_EQ(canonicalTriangles(a), canonicalTriangles(b));
    if (test::lavapipeCannotDraw().empty()) {
        CliRun rendered = runCli("render " + (out / "colour.ply").string() + " -o " + (out / "colour.png").string() + " --width 64 --height 48");
        ASSERT_EQ(rendered.exitCode, 0) << rendered.err;
        EXPECT_NE(rendered.out.find("auto"), std::string::npos) << rendered.out;
    }
    CliRun bad = runCli("render " + (out / "colour.ply").string() + " -o " + (out / "x.png").string() + " --color purple");
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.err.find("rgb"), std::string::npos) << bad.err;
}

TEST(Cli, BaselineModeWritesATriangleSoup) {
    fs::path out = test::makeTempDir("cli_baseline");
    CliRun r = runCli("fuse " + smallSequence().string() + " -o " + (out / "mesh.ply").string() + " --voxel 0.05 --mode baseline -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    Mesh mesh = readPly(out / "mesh.ply");
    EXPECT_GT(mesh.triangles.size(), 500u);
    EXPECT_EQ(mesh.positions.size(), 3 * mesh.triangles.size());
    fs::remove_all(out);
}

TEST(Cli, ObjOutputByExtension) {
    fs::path out = test::makeTempDir("cli_obj");
    CliRun r = runCli("fuse " + smallSequence().string() + " -o " + (out / "mesh.obj").string() + " --frames 2 --voxel 0.05 -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    std::string obj = readText(out / "mesh.obj");
    EXPECT_NE(obj.find("\nv "), std::string::npos);
    EXPECT_NE(obj.find("\nf "), std::string::npos);
    fs::remove_all(out);
}

// glTF binary out (io/gltf.h): `fuse -o x.glb --simplify 0.5` writes a simplified copy, reports it in --stats (the
// fused mesh's own counts unchanged), and `export` writes a saved map's mesh as .glb, equal to fuse's PLY; an
// extension vkmesh cannot write fails before anything is fused.
TEST(Cli, GlbOutputSimplifiedAndExported) {
    fs::path out = test::makeTempDir("cli_glb");
    const std::string seq = smallSequence().string(), map = (out / "m.vkmap").string();
    CliRun r = runCli("fuse " + seq + " -o " + (out / "half.glb").string() + " --simplify 0.5 --voxel 0.05 --frames 3 -q --save " + map +
                      " --stats " + (out / "stats.json").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("simplified to "), std::string::npos) << r.out;
    const nlohmann::json stats = nlohmann::json::parse(readText(out / "stats.json"));
    const nlohmann::json& s = stats["simplify"];
    const Mesh half = readGlb(out / "half.glb");
    EXPECT_TRUE(s["enabled"].get<bool>());
    EXPECT_EQ(s["ratio"].get<double>(), 0.5);
    EXPECT_EQ(s["triangles_before"].get<size_t>(), stats["mesh"]["triangles"].get<size_t>());
    EXPECT_EQ(s["triangles_after"].get<size_t>(), half.triangles.size());
    EXPECT_LE(half.triangles.size(), stats["mesh"]["triangles"].get<size_t>() / 2);
    EXPECT_GE(half.triangles.size(), stats["mesh"]["triangles"].get<size_t>() * 2 / 5);
    EXPECT_GT(s["error_m"].get<double>(), 0);
    EXPECT_LT(s["error_m"].get<double>(), 0.05);   // under a voxel
    EXPECT_EQ(half.colors.size(), half.positions.size());   // the synthetic room is coloured

    // The saved map's mesh, whole, as .glb and as .ply: the same vertices and triangles.
    CliRun glb = runCli("export " + map + " -o " + (out / "all.glb").string());
    ASSERT_EQ(glb.exitCode, 0) << glb.err;
    CliRun ply = runCli("export " + map + " -o " + (out / "all.ply").string());
    ASSERT_EQ(ply.exitCode, 0) << ply.err;
    // Two exports need not list them in the same order: compared as sets.
    const Mesh a = readGlb(out / "all.glb"), b = readPly(out / "all.ply");
    EXPECT_EQ(b.triangles.size(), stats["mesh"]["triangles"].get<size_t>());
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(a), canonicalTriangles(b), 0), 0u);
    auto coloured = [](const Mesh& m) {
        std::vector<std::tuple<float, float, float, uint8_t, uint8_t, uint8_t>> v;
        for (size_t i = 0; i < m.positions.size(); ++i)
            v.emplace_back(m.positions[i].x(), m.positions[i].y(), m.positions[i].z(), m.colors[i][0], m.colors[i][1], m.colors[i][2]);
        std::sort(v.begin(), v.end());
        return v;
    };
    ASSERT_EQ(a.colors.size(), a.positions.size());
    ASSERT_EQ(b.colors.size(), b.positions.size());
    EXPECT_EQ(coloured(a), coloured(b));
    // The Khronos validator, where it is installed (tests/cpu/test_gltf.cpp skips with a message where it is not).
    if (std::system("node -e \"require(require('child_process').execSync('npm root -g').toString().trim() + '/gltf-validator')\" >/dev/null 2>&1") == 0) {
        const int status = std::system(("node " VKMESH_SOURCE_DIR "/scripts/gltf_validate.js " + (out / "half.glb").string() + " " +
                                        (out / "all.glb").string() + " >" + (out / "validator.log").string() + " 2>&1").c_str());
        EXPECT_EQ(status, 0) << readText(out / "validator.log");
    }

    CliRun stl = runCli("fuse " + seq + " -o " + (out / "mesh.stl").string() + " -q");
    EXPECT_NE(stl.exitCode, 0);
    EXPECT_NE(stl.err.find(".glb"), std::string::npos) << stl.err;
    CliRun ratio = runCli("export " + map + " -o " + (out / "x.glb").string() + " --simplify 1.5");
    EXPECT_NE(ratio.exitCode, 0);
    EXPECT_NE(ratio.err.find("--simplify 1.5"), std::string::npos) << ratio.err;
    fs::remove_all(out);
}

TEST(Cli, RenderEveryWritesPicturesFromTheSensorView) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    fs::path out = test::makeTempDir("cli_render_every");
    CliRun r = runCli("fuse " + smallSequence().string() + " -o " + (out / "mesh.ply").string() + " --voxel 0.05 --render-every 2 " +
                      "--render-dir " + (out / "png").string() + " --render-color age -q --validation");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err.find("validation"), std::string::npos) << r.err;
    for (const char* name : {"frame_000001.png", "frame_000003.png", "frame_000005.png"}) {
        cv::Mat image = cv::imread((out / "png" / name).string(), cv::IMREAD_COLOR);
        ASSERT_FALSE(image.empty()) << name;
        EXPECT_EQ(image.cols, 160);
        EXPECT_EQ(image.rows, 120);
        // The sensor looks at the room: most of the picture is mesh, not background.
        int covered = 0;
        for (int y = 0; y < image.rows; ++y)
            for (int x = 0; x < image.cols; ++x) {
                cv::Vec3b p = image.at<cv::Vec3b>(y, x);
                covered += !(p[0] == 38 && p[1] == 38 && p[2] == 38);
            }
        EXPECT_GT(covered, image.cols * image.rows / 2) << name;
    }
    EXPECT_FALSE(fs::exists(out / "png" / "frame_000000.png"));
    CliRun missingDir = runCli("fuse " + smallSequence().string() + " -o " + (out / "m.ply").string() + " --render-every 2 -q");
    EXPECT_NE(missingDir.exitCode, 0);
    EXPECT_NE(missingDir.err.find("--render-dir"), std::string::npos) << missingDir.err;
    fs::remove_all(out);
}

TEST(Cli, DeltaStreamReplaysToTheSameMesh) {
    fs::path out = test::makeTempDir("cli_deltas");
    CliRun r = runCli("fuse " + smallSequence().string() + " -o " + (out / "mesh.ply").string() + " --voxel 0.05 --deltas " +
                      (out / "mesh.deltas").string() + " -q --validation");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    CliRun replay = runCli("deltas " + (out / "mesh.deltas").string() + " -o " + (out / "replay.ply").string());
    ASSERT_EQ(replay.exitCode, 0) << replay.err;
    Mesh fused = readPly(out / "mesh.ply"), replayed = readPly(out / "replay.ply");
    EXPECT_EQ(replayed.positions.size(), fused.positions.size());
    ASSERT_EQ(replayed.triangles.size(), fused.triangles.size());
    EXPECT_GT(fused.triangles.size(), 1000u);
    // The same triangles, vertex bits and all (the order of the export is not specified).
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(replayed), canonicalTriangles(fused), 0), 0u);
    CliRun partial = runCli("deltas " + (out / "mesh.deltas").string() + " --until-frame 2");
    EXPECT_EQ(partial.exitCode, 0) << partial.err;
    EXPECT_NE(partial.out.find("mesh at frame 2"), std::string::npos) << partial.out;
    CliRun baseline = runCli("fuse " + smallSequence().string() + " -o " + (out / "b.ply").string() + " --mode baseline --deltas " +
                             (out / "b.deltas").string() + " -q");
    EXPECT_NE(baseline.exitCode, 0);
    EXPECT_NE(baseline.err.find("--mode incremental"), std::string::npos) << baseline.err;
    fs::remove_all(out);
}

TEST(Cli, FramesJsonListsPosesAndIntrinsics) {
    fs::path out = test::makeTempDir("cli_frames");
    CliRun r = runCli("frames " + smallSequence().string() + " -o " + (out / "frames.json").string() + " --frames 4");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    auto j = nlohmann::json::parse(readText(out / "frames.json"));
    EXPECT_EQ(j["frames"].size(), 4u);
    EXPECT_EQ(j["intrinsics"]["width"], 160);
    EXPECT_EQ(j["frames"][0]["camera_to_world"].size(), 16u);
    EXPECT_TRUE(fs::exists(j["frames"][0]["depth_path"].get<std::string>()));
    fs::remove_all(out);
}

TEST(Cli, MissingFolderIsAClearError) {
    CliRun r = runCli("fuse /nonexistent/vkmesh_data -o /tmp/x.ply");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("/nonexistent/vkmesh_data"), std::string::npos) << r.err;
}

TEST(Cli, AbsurdVoxelSizeIsAClearError) {
    CliRun r = runCli("fuse " + smallSequence().string() + " -o /tmp/x.ply --voxel 40");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("voxel size"), std::string::npos) << r.err;
}

TEST(Cli, CorruptAndEmptyFramesAreSkippedWithAWarning) {
    fs::path seq = copyOfSmallSequence("cli_bad_frames");
    // Frame 1: not a PNG at all. Frame 2: a valid PNG with no depth anywhere.
    std::ofstream(seq / "depth" / "000001.png") << "this is not a png";
    cv::imwrite((seq / "depth" / "000002.png").string(), cv::Mat(120, 160, CV_16UC1, cv::Scalar(0)));
    fs::path out = test::makeTempDir("cli_bad_out");
    CliRun r = runCli("fuse " + seq.string() + " -o " + (out / "m.ply").string() + " --stats " + (out / "s.json").string() +
                   " --voxel 0.05 -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("000001.png"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("no valid depth"), std::string::npos) << r.err;
    auto stats = nlohmann::json::parse(readText(out / "s.json"));
    EXPECT_EQ(stats["frames"]["integrated"], 4);
    EXPECT_EQ(stats["frames"]["skipped"], 2);
    fs::remove_all(seq);
    fs::remove_all(out);
}

TEST(Cli, AllFramesBadFails) {
    fs::path seq = copyOfSmallSequence("cli_all_bad");
    for (auto& f : fs::directory_iterator(seq / "depth"))
        cv::imwrite(f.path().string(), cv::Mat(120, 160, CV_16UC1, cv::Scalar(0)));
    CliRun r = runCli("fuse " + seq.string() + " -o /tmp/vkmesh_never.ply -q");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("none of the"), std::string::npos) << r.err;
    fs::remove_all(seq);
}

TEST(Cli, NonOrthonormalPoseIsAClearError) {
    fs::path seq = copyOfSmallSequence("cli_bad_pose");
    std::string gt = readText(seq / "groundtruth.txt");
    // The first pose gets a quaternion with a NaN component.
    std::istringstream in(gt);
    std::string line, rewritten;
    bool done = false;
    while (std::getline(in, line)) {
        if (!done && !line.empty() && line[0] != '#') {
            std::istringstream f(line);
            std::string ts;
            f >> ts;
            line = ts + " 0 0 1 nan 0 0 1";
            done = true;
        }
        rewritten += line + "\n";
    }
    std::ofstream(seq / "groundtruth.txt") << rewritten;
    CliRun r = runCli("fuse " + seq.string() + " -o /tmp/vkmesh_never.ply -q");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("groundtruth.txt"), std::string::npos) << r.err;
    fs::remove_all(seq);
}

// Hostile input through the program (issue 5): a bad calibration or frame 0 is exit code 2 with a message
// naming the file and the value, before any GPU work; a bad later frame is a warning and the frame skipped.
TEST(Cli, HostileDatasetsAreClearErrors) {
    fs::path seq = copyOfSmallSequence("cli_hostile");
    const std::string json = readText(seq / "camera.json");
    // camera.json for another image size than the 160x120 frames.
    {
        auto j = nlohmann::json::parse(json);
        j["width"] = 320;
        j["height"] = 240;
        std::ofstream(seq / "camera.json") << j.dump();
        CliRun r = runCli("fuse " + seq.string() + " -o /tmp/vkmesh_never.ply -q");
        EXPECT_EQ(r.exitCode, 2);
        for (const char* needle : {"camera.json", "320x240", "160x120", "000000.png"})
            EXPECT_NE(r.err.find(needle), std::string::npos) << needle << ": " << r.err;
    }
    // A negative focal length.
    {
        auto j = nlohmann::json::parse(json);
        j["fx"] = -100.5;
        std::ofstream(seq / "camera.json") << j.dump();
        CliRun r = runCli("fuse " + seq.string() + " -o /tmp/vkmesh_never.ply -q");
        EXPECT_EQ(r.exitCode, 2);
        EXPECT_NE(r.err.find("camera.json: focal length \"fx\" = -100.5"), std::string::npos) << r.err;
    }
    std::ofstream(seq / "camera.json") << json;
    // Frame 0 an 8-bit PNG: the dataset is rejected, naming the file and its type.
    {
        fs::path f0 = seq / "depth" / "000000.png";
        fs::copy_file(f0, seq / "frame0.bak");
        cv::imwrite(f0.string(), cv::Mat(120, 160, CV_8UC1, cv::Scalar(9)));
        CliRun r = runCli("fuse " + seq.string() + " -o /tmp/vkmesh_never.ply -q");
        EXPECT_EQ(r.exitCode, 2);
        EXPECT_NE(r.err.find("000000.png is 8-bit grayscale"), std::string::npos) << r.err;
        fs::copy_file(seq / "frame0.bak", f0, fs::copy_options::overwrite_existing);
    }
    // A later frame of another size: warned about and skipped, the rest fused.
    {
        cv::imwrite((seq / "depth" / "000003.png").string(), cv::Mat(60, 80, CV_16UC1, cv::Scalar(5000)));
        fs::path out = test::makeTempDir("cli_hostile_out");
        CliRun r = runCli("fuse " + seq.string() + " -o " + (out / "m.ply").string() + " --stats " +
                          (out / "s.json").string() + " --voxel 0.05 -q");
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_NE(r.err.find("000003.png is 80x60 but frame 0"), std::string::npos) << r.err;
        auto stats = nlohmann::json::parse(readText(out / "s.json"));
        EXPECT_EQ(stats["frames"]["skipped"], 1);
        fs::remove_all(out);
    }
    fs::remove_all(seq);
}

// Maps (docs/MAPFILE.md): fuse the first frames and save, continue from the map with the rest: the mesh of
// the uninterrupted run, vertex ages included; `vkmesh export` writes a map's mesh; bad maps are clear errors.
TEST(Cli, SaveLoadAndFirstFrameResumeTheRun) {
    fs::path out = test::makeTempDir("cli_map");
    const std::string seq = smallSequence().string(), map = (out / "first.vkmap").string();
    CliRun whole = runCli("fuse " + seq + " -o " + (out / "whole.ply").string() + " --voxel 0.05 -q --validation");
    ASSERT_EQ(whole.exitCode, 0) << whole.err;
    CliRun first = runCli("fuse " + seq + " --frames 3 -o " + (out / "first.ply").string() + " --voxel 0.05 --save " + map +
                          " --stats " + (out / "first.json").string() + " -q --validation");
    ASSERT_EQ(first.exitCode, 0) << first.err;
    EXPECT_NE(first.out.find("per live block"), std::string::npos) << first.out;
    const nlohmann::json stats = nlohmann::json::parse(readText(out / "first.json"));
    EXPECT_EQ(stats["map"]["bytes"].get<uint64_t>(), fs::file_size(map));
    // The voxel size comes from the map.
    CliRun rest = runCli("fuse " + seq + " --load " + map + " --first-frame 3 -o " + (out / "rest.ply").string() + " -q --validation");
    ASSERT_EQ(rest.exitCode, 0) << rest.err;
    Mesh a = readPly(out / "whole.ply"), b = readPly(out / "rest.ply");
    EXPECT_GT(a.triangles.size(), 1000u);
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(a), canonicalTriangles(b), 0), 0u);
    EXPECT_EQ(a.triangles.size(), b.triangles.size());
    std::sort(a.vertexAge.begin(), a.vertexAge.end());
    std::sort(b.vertexAge.begin(), b.vertexAge.end());
    EXPECT_EQ(a.vertexAge, b.vertexAge);

    CliRun exported = runCli("export " + map + " -o " + (out / "exported.ply").string() + " --validation");
    ASSERT_EQ(exported.exitCode, 0) << exported.err;
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(readPly(out / "first.ply")), canonicalTriangles(readPly(out / "exported.ply")), 0),
              0u);

    CliRun voxel = runCli("fuse " + seq + " --load " + map + " --first-frame 3 -o " + (out / "x.ply").string() + " --voxel 0.04 -q");
    EXPECT_EQ(voxel.exitCode, 2);
    EXPECT_NE(voxel.err.find(map + ": the map was fused with voxel size"), std::string::npos) << voxel.err;
    // The allocation mode is the map's too: a map fused pixel by pixel (--alloc-pixels, the default before tiles)
    // continues pixel by pixel without the option and refuses tiles, naming the options.
    const std::string pixelMap = (out / "pixels.vkmap").string();
    CliRun pixels = runCli("fuse " + seq + " --frames 3 -o " + (out / "x.ply").string() + " --voxel 0.05 --alloc-pixels --save " +
                           pixelMap + " -q");
    ASSERT_EQ(pixels.exitCode, 0) << pixels.err;
    CliRun pixelsRest = runCli("fuse " + seq + " --load " + pixelMap + " --first-frame 3 -o " + (out / "x.ply").string() + " -q");
    EXPECT_EQ(pixelsRest.exitCode, 0) << pixelsRest.err;
    CliRun tilesOnPixels = runCli("fuse " + seq + " --load " + pixelMap + " --first-frame 3 --alloc-tiles -o " +
                                  (out / "x.ply").string() + " -q");
    EXPECT_EQ(tilesOnPixels.exitCode, 2);
    EXPECT_NE(tilesOnPixels.err.find("--alloc-tiles, --alloc-pixels"), std::string::npos) << tilesOnPixels.err;
    CliRun both = runCli("fuse " + seq + " --alloc-tiles --alloc-pixels -o " + (out / "x.ply").string() + " -q");
    EXPECT_NE(both.exitCode, 0);
    EXPECT_NE(both.err.find("--alloc-pixels"), std::string::npos) << both.err;
    test::writeBytes(out / "garbage.vkmap", "not a map at all, just some bytes");
    CliRun garbage = runCli("export " + (out / "garbage.vkmap").string() + " -o " + (out / "x.ply").string());
    EXPECT_EQ(garbage.exitCode, 2);
    EXPECT_NE(garbage.err.find("garbage.vkmap: not a vkmesh map"), std::string::npos) << garbage.err;
    std::string bytes = readText(map);
    test::writeBytes(out / "short.vkmap", bytes.substr(0, bytes.size() / 2));
    CliRun truncated = runCli("fuse " + seq + " --load " + (out / "short.vkmap").string() + " -o " + (out / "x.ply").string() + " -q");
    EXPECT_EQ(truncated.exitCode, 2);
    EXPECT_NE(truncated.err.find("short.vkmap: truncated"), std::string::npos) << truncated.err;
    CliRun past = runCli("fuse " + seq + " --first-frame 6 -o " + (out / "x.ply").string() + " -q");
    EXPECT_EQ(past.exitCode, 2);
    EXPECT_NE(past.err.find("--first-frame 6"), std::string::npos) << past.err;
}

}  // namespace
}  // namespace vkmesh

namespace vkmesh {
namespace {

// A synthetic sequence whose camera moves as a sensor's does (240 poses to the orbit: about 3.6 cm and
// 1.5 degrees per frame), for tracking; made once for all the test programs of the build.
const std::filesystem::path& trackingSequence() {
    static const std::filesystem::path dir =
        test::sharedSynthSequence("cli_tracking", "--frames 240 --width 160 --height 120 --gt-spacing 0.05");
    return dir;
}

// The frames' poses relative to the first one, from a TUM trajectory file.
std::vector<Pose> relativePoses(const std::vector<TimedPose>& poses, size_t count) {
    std::vector<Pose> out;
    for (size_t i = 0; i < count && i < poses.size(); ++i) out.push_back(inverseRigid(poses[0].cameraToWorld) * poses[i].cameraToWorld);
    return out;
}

// `fuse --track` on a folder without poses (refused without --track, and the error says that --track exists):
// the trajectory starts at identity, follows the true motion within a centimetre, carries the dataset's
// timestamps, and --stats reports tracking.
TEST(Cli, TrackFusesASequenceWithoutPoses) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // tracking draws the mesh
    namespace fs = std::filesystem;
    fs::path d = test::makeTempDir("cli_track");
    fs::copy(trackingSequence(), d / "seq", fs::copy_options::recursive);
    const std::vector<TimedPose> truth = readTumTrajectory(d / "seq" / "groundtruth.txt");
    fs::remove(d / "seq" / "groundtruth.txt");
    test::CliRun r = test::runCli("fuse " + (d / "seq").string() + " -o " + (d / "m.ply").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("--track"), std::string::npos) << r.err;

    // (--frames-budget 0.05: 50 kB, a frame or two; the default loop closure's frames go on to the temporary folder.)
    r = test::runCli("fuse " + (d / "seq").string() + " --track --frames 12 --voxel 0.03 --trajectory " + (d / "t.txt").string() +
                     " --stats " + (d / "s.json").string() + " -o " + (d / "m.ply").string() + " --validation --frames-budget 0.05");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err.find("[validation"), std::string::npos) << r.err;
    const std::vector<TimedPose> tracked = readTumTrajectory(d / "t.txt");
    ASSERT_EQ(tracked.size(), 12u);
    EXPECT_TRUE(tracked[0].cameraToWorld.isApprox(Pose::Identity(), 1e-9));
    const std::vector<Pose> want = relativePoses(truth, 12);
    for (size_t i = 0; i < tracked.size(); ++i) {
        EXPECT_DOUBLE_EQ(tracked[i].timestamp, truth[i].timestamp) << "frame " << i;
        EXPECT_LT((tracked[i].cameraToWorld.block<3, 1>(0, 3) - want[i].block<3, 1>(0, 3)).norm(), 0.01) << "frame " << i;
    }
    const auto stats = nlohmann::json::parse(test::readText(d / "s.json"));
    EXPECT_EQ(stats["frames"]["integrated"], 12);
    EXPECT_EQ(stats["tracking"]["lost_frames"], 0);
    EXPECT_EQ(stats["tracking"]["frames_tracked"], 11);
    for (const char* key : {"median", "p90", "max"}) EXPECT_TRUE(stats["tracking"]["ms_per_frame"].contains(key)) << key;
    EXPECT_GT(stats["tracking"]["iterations"]["total"].get<double>(), 11);
    // --track closes loops and relocalises by default: keyframes are taken, and the frames are kept to be re-fused.
    EXPECT_EQ(stats["loop_closure"]["enabled"], true) << stats["loop_closure"].dump();
    EXPECT_GE(stats["loop_closure"]["keyframes"].get<int>(), 1);
    EXPECT_EQ(stats["frame_store"]["frames"], 12);
    EXPECT_GT(stats["frame_store"]["frames_spilled"].get<int>(), 0) << stats["frame_store"].dump();
    fs::remove_all(d);
}

// With poses in the dataset, --track takes the first one and estimates the others; --trajectory without
// --track writes the dataset's poses as used; --track-solve gpu tracks as well in one submission per frame.
// Bad --track-iterations and --track-solve are clear errors.
TEST(Cli, TrackStartsFromTheDatasetsFirstPose) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // tracking draws the mesh
    namespace fs = std::filesystem;
    fs::path d = test::makeTempDir("cli_track_gt");
    const std::vector<TimedPose> truth = readTumTrajectory(trackingSequence() / "groundtruth.txt");
    test::CliRun r = test::runCli("fuse " + trackingSequence().string() + " --track --frames 8 --voxel 0.03 --trajectory " +
                                  (d / "t.txt").string() + " -o " + (d / "m.ply").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::vector<TimedPose> tracked = readTumTrajectory(d / "t.txt");
    ASSERT_EQ(tracked.size(), 8u);
    EXPECT_LT((tracked[0].cameraToWorld - truth[0].cameraToWorld).cwiseAbs().maxCoeff(), 1e-8);
    for (size_t i = 1; i < tracked.size(); ++i)
        EXPECT_LT((tracked[i].cameraToWorld.block<3, 1>(0, 3) - truth[i].cameraToWorld.block<3, 1>(0, 3)).norm(), 0.01) << i;
    // The summary says how far the tracked positions are from the dataset's (its own comparison, printed by the demo).
    EXPECT_NE(r.out.find("tracked positions against the dataset's poses: RMSE"), std::string::npos) << r.out;

    // The same with the systems solved on the GPU: one submission per frame, as close to the truth. (Not the same
    // poses: float steps differ from double ones in the 7th digit, and the difference grows through the map each
    // frame fuses: 0.5-3 mm here by frame 7.)
    // (Tracking alone, --no-loop-closure: no keyframes, no frames kept.)
    r = test::runCli("fuse " + trackingSequence().string() + " --track --no-loop-closure --track-solve gpu --frames 8 --voxel 0.03 --trajectory " +
                     (d / "g.txt").string() + " --stats " + (d / "g.json").string() + " -o " + (d / "m.ply").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::vector<TimedPose> onGpu = readTumTrajectory(d / "g.txt");
    ASSERT_EQ(onGpu.size(), 8u);
    for (size_t i = 1; i < onGpu.size(); ++i)
        EXPECT_LT((onGpu[i].cameraToWorld.block<3, 1>(0, 3) - truth[i].cameraToWorld.block<3, 1>(0, 3)).norm(), 0.01) << i;
    const auto gpuStats = nlohmann::json::parse(test::readText(d / "g.json"));
    EXPECT_EQ(gpuStats["tracking"]["solve"], "gpu");
    // Against the dataset's poses (8 frames, the first shared); the model maps reused by some of the 7 tracked
    // frames, at most 2 in a row (the default); tracked at the frame's own size (160 x 120: no downsampling below
    // 640 pixels wide).
    EXPECT_EQ(gpuStats["tracking"]["position_error_m"]["frames"], 8);
    EXPECT_LT(gpuStats["tracking"]["position_error_m"]["max"].get<double>(), 0.01);
    EXPECT_GE(gpuStats["tracking"]["model_draws"].get<int>(), 3);
    EXPECT_LT(gpuStats["tracking"]["model_draws"].get<int>(), 7);
    EXPECT_EQ(gpuStats["tracking"]["model_reuse_frames"], 2);
    EXPECT_EQ(gpuStats["tracking"]["downsample"], 1);
    EXPECT_EQ(gpuStats["tracking"]["submissions_per_frame"]["max"], 1);
    EXPECT_EQ(gpuStats["tracking"]["fused_in_tracking_submission"], true);   // fusion and meshing in that submission
    EXPECT_EQ(gpuStats["frames"]["integrated"], 8) << gpuStats["frames"].dump();
    EXPECT_EQ(gpuStats["loop_closure"]["enabled"], false);
    EXPECT_FALSE(gpuStats.contains("frame_store"));
    for (const char* options : {" --track --loop-closure --no-loop-closure", " --no-loop-closure",
                                " --track --no-loop-closure --loop-place-candidates 3"}) {
        r = test::runCli("fuse " + trackingSequence().string() + options + " -o " + (d / "m.ply").string());
        EXPECT_NE(r.exitCode, 0) << options;
        EXPECT_NE(r.err.find("loop"), std::string::npos) << options << ": " << r.err;
    }
    r = test::runCli("fuse " + trackingSequence().string() + " --track --track-solve cpu -o " + (d / "m.ply").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("--track-solve"), std::string::npos) << r.err;
    r = test::runCli("fuse " + trackingSequence().string() + " --track --track-downsample 3 -o " + (d / "m.ply").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("--track-downsample"), std::string::npos) << r.err;
    r = test::runCli("fuse " + trackingSequence().string() + " --track-downsample 2 -o " + (d / "m.ply").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("need --track"), std::string::npos) << r.err;

    r = test::runCli("fuse " + trackingSequence().string() + " --frames 3 --voxel 0.05 --trajectory " + (d / "given.txt").string() +
                     " -o " + (d / "m.ply").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::vector<TimedPose> given = readTumTrajectory(d / "given.txt");
    ASSERT_EQ(given.size(), 3u);
    for (size_t i = 0; i < 3; ++i) EXPECT_LT((given[i].cameraToWorld - truth[i].cameraToWorld).cwiseAbs().maxCoeff(), 1e-8) << i;

    r = test::runCli("fuse " + trackingSequence().string() + " --track --track-iterations 10,x,4 -o " + (d / "m.ply").string());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("--track-iterations"), std::string::npos) << r.err;
    fs::remove_all(d);
}

}  // namespace
}  // namespace vkmesh

namespace vkmesh {
namespace {

// `vkmesh correct` (docs/CORRECTION.md): a map fused at drifted poses and saved with its frame store, corrected
// with the true trajectory, gives the mesh of a run fused at the true poses; a store that is not the map's,
// or a trajectory pose that is not rigid, is an error naming it.
TEST(Cli, CorrectRefusesDriftedFramesIntoTheTrueMap) {
    const fs::path out = test::makeTempDir("cli_correct");
    // The poses fuse uses, as --trajectory writes them (9 decimals): the truth both runs start from.
    const fs::path truthSeq = copyOfSmallSequence("cli_correct_truth"), driftSeq = copyOfSmallSequence("cli_correct_drift");
    CliRun poses = runCli("fuse " + truthSeq.string() + " -o " + (out / "x.ply").string() + " --voxel 0.05 -q --trajectory " +
                          (out / "truth.txt").string());
    ASSERT_EQ(poses.exitCode, 0) << poses.err;
    const std::vector<TimedPose> truth = readTumTrajectory(out / "truth.txt");
    ASSERT_EQ(truth.size(), 6u);
    std::vector<TimedPose> drifted = truth;
    for (size_t i = 0; i < drifted.size(); ++i) {
        Pose drift = Pose::Identity();
        drift.topLeftCorner<3, 3>() = Eigen::AngleAxisd(double(i) * 0.01, Eigen::Vector3d::UnitY()).toRotationMatrix();
        drift.topRightCorner<3, 1>() = double(i) * Eigen::Vector3d(0.01, 0.0, -0.005);
        drifted[i].cameraToWorld = drift * truth[i].cameraToWorld;
    }
    writeTumTrajectory(truthSeq / "groundtruth.txt", truth);
    writeTumTrajectory(driftSeq / "groundtruth.txt", drifted);
    const std::string common = " --voxel 0.05 -q --validation";
    ASSERT_EQ(runCli("fuse " + truthSeq.string() + " -o " + (out / "truth.ply").string() + common).exitCode, 0);
    CliRun fused = runCli("fuse " + driftSeq.string() + " -o " + (out / "drift.ply").string() + " --save " + (out / "drift.vkmap").string() +
                          " --stats " + (out / "fuse.json").string() + common);
    ASSERT_EQ(fused.exitCode, 0) << fused.err;
    ASSERT_TRUE(fs::exists(out / "drift.vkframes")) << "--save keeps the frames beside the map";
    const nlohmann::json fuseStats = nlohmann::json::parse(readText(out / "fuse.json"));
    EXPECT_EQ(fuseStats["frame_store"]["frames"], 6);
    EXPECT_GT(fuseStats["frame_store"]["bytes_per_frame"].get<double>(), 1000.0);
    EXPECT_GT(countTriangleMismatches(canonicalTriangles(readPly(out / "truth.ply")), canonicalTriangles(readPly(out / "drift.ply")), 0), 100u);

    CliRun corrected = runCli("correct " + (out / "drift.vkmap").string() + " --trajectory " + (out / "truth.txt").string() + " -o " +
                              (out / "corrected.ply").string() + " --save " + (out / "corrected.vkmap").string() + " --stats " +
                              (out / "correct.json").string() + " --validation");
    ASSERT_EQ(corrected.exitCode, 0) << corrected.err;
    EXPECT_EQ(corrected.err.find("[validation"), std::string::npos) << corrected.err;
    const nlohmann::json stats = nlohmann::json::parse(readText(out / "correct.json"));
    EXPECT_EQ(stats["correction"]["frames_refused"], 5) << "frame 0 did not drift";
    EXPECT_EQ(stats["correction"]["frames_unchanged"], 1);
    EXPECT_EQ(stats["correction"]["observations_dropped"], 0);
    const Mesh a = readPly(out / "truth.ply"), b = readPly(out / "corrected.ply");
    EXPECT_GT(a.triangles.size(), 1000u);
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(a), canonicalTriangles(b), 0), 0u);
    EXPECT_EQ(a.positions.size(), b.positions.size());
    // The corrected map was saved with its store: correcting it again with the same poses re-fuses nothing.
    CliRun again = runCli("correct " + (out / "corrected.vkmap").string() + " --trajectory " + (out / "truth.txt").string() + " -o " +
                          (out / "again.ply").string() + " --stats " + (out / "again.json").string());
    ASSERT_EQ(again.exitCode, 0) << again.err;
    EXPECT_EQ(nlohmann::json::parse(readText(out / "again.json"))["correction"]["frames_refused"], 0);

    // A map continued with --load keeps its store: frames from both runs can be corrected.
    CliRun firstHalf = runCli("fuse " + driftSeq.string() + " --frames 3 -o " + (out / "x.ply").string() + " --save " +
                              (out / "half.vkmap").string() + common);
    ASSERT_EQ(firstHalf.exitCode, 0) << firstHalf.err;
    CliRun secondHalf = runCli("fuse " + driftSeq.string() + " --load " + (out / "half.vkmap").string() + " --first-frame 3 -o " +
                               (out / "x.ply").string() + " --save " + (out / "whole.vkmap").string() + " -q --validation");
    ASSERT_EQ(secondHalf.exitCode, 0) << secondHalf.err;
    CliRun both = runCli("correct " + (out / "whole.vkmap").string() + " --trajectory " + (out / "truth.txt").string() + " -o " +
                         (out / "both.ply").string() + " --stats " + (out / "both.json").string());
    ASSERT_EQ(both.exitCode, 0) << both.err;
    EXPECT_EQ(nlohmann::json::parse(readText(out / "both.json"))["correction"]["frames_refused"], 5);
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(a), canonicalTriangles(readPly(out / "both.ply")), 0), 0u);

    // Two runs fusing a half each, merged (docs/SCALING.md): the merged map keeps both stores, so the correction
    // of all frames gives the true map again.
    CliRun otherHalf = runCli("fuse " + driftSeq.string() + " --first-frame 3 -o " + (out / "x.ply").string() + " --save " +
                              (out / "other.vkmap").string() + common);
    ASSERT_EQ(otherHalf.exitCode, 0) << otherHalf.err;
    CliRun merged = runCli("merge " + (out / "other.vkmap").string() + " " + (out / "half.vkmap").string() + " -o " +
                           (out / "merged.vkmap").string() + " --mesh " + (out / "merged.ply").string() + " --stats " +
                           (out / "merge.json").string());   // its GPU work is validated in MapMergeTest
    ASSERT_EQ(merged.exitCode, 0) << merged.err;
    const nlohmann::json mergeStats = nlohmann::json::parse(readText(out / "merge.json"));
    EXPECT_EQ(mergeStats["frames_integrated"], 6);
    EXPECT_EQ(mergeStats["frame_store"]["frames"], 6);
    EXPECT_EQ(mergeStats["frame_store"]["renumbered"], false) << "fuse numbers frames by the dataset: the halves do not collide";
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(readPly(out / "drift.ply")), canonicalTriangles(readPly(out / "merged.ply")), 0), 0u)
        << "the merged halves are the drifted run's map";
    CliRun mergedCorrected = runCli("correct " + (out / "merged.vkmap").string() + " --trajectory " + (out / "truth.txt").string() + " -o " +
                                    (out / "merged_corrected.ply").string() + " --stats " + (out / "merged_corrected.json").string());
    ASSERT_EQ(mergedCorrected.exitCode, 0) << mergedCorrected.err;
    EXPECT_EQ(nlohmann::json::parse(readText(out / "merged_corrected.json"))["correction"]["frames_refused"], 5);
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(a), canonicalTriangles(readPly(out / "merged_corrected.ply")), 0), 0u);
    // Maps that do not add up are refused naming the setting, and nothing is written.
    CliRun finer = runCli("fuse " + driftSeq.string() + " --frames 1 -o " + (out / "x.ply").string() + " --voxel 0.04 -q --save " +
                          (out / "finer.vkmap").string());
    ASSERT_EQ(finer.exitCode, 0) << finer.err;
    CliRun refused = runCli("merge " + (out / "half.vkmap").string() + " " + (out / "finer.vkmap").string() + " -o " +
                            (out / "refused.vkmap").string() + " --mesh " + (out / "refused.ply").string());
    EXPECT_EQ(refused.exitCode, 2);
    EXPECT_NE(refused.err.find("--voxel"), std::string::npos) << refused.err;
    EXPECT_NE(refused.err.find("finer.vkmap"), std::string::npos) << refused.err;
    EXPECT_FALSE(fs::exists(out / "refused.vkmap") || fs::exists(out / "refused.vkframes") || fs::exists(out / "refused.ply"));
    CliRun meshForMap = runCli("merge " + (out / "half.vkmap").string() + " -o " + (out / "refused.ply").string());
    EXPECT_EQ(meshForMap.exitCode, 2);
    EXPECT_NE(meshForMap.err.find("--mesh"), std::string::npos) << meshForMap.err;
    CliRun tilesWithoutSize = runCli("merge " + (out / "half.vkmap").string() + " --tiles " + (out / "tiles").string());
    EXPECT_EQ(tilesWithoutSize.exitCode, 2);
    EXPECT_NE(tilesWithoutSize.err.find("--tile-size"), std::string::npos) << tilesWithoutSize.err;
    EXPECT_FALSE(fs::exists(out / "tiles"));

    // Bad input: the store of another map, a missing store, a pose that is not rigid.
    fs::copy_file(out / "corrected.vkframes", out / "drift.vkframes", fs::copy_options::overwrite_existing);
    CliRun wrongStore = runCli("correct " + (out / "drift.vkmap").string() + " --trajectory " + (out / "truth.txt").string() + " -o " +
                               (out / "x.ply").string());
    EXPECT_EQ(wrongStore.exitCode, 2);
    EXPECT_NE(wrongStore.err.find("another map"), std::string::npos) << wrongStore.err;
    fs::remove(out / "drift.vkframes");
    CliRun noStore = runCli("correct " + (out / "drift.vkmap").string() + " --trajectory " + (out / "truth.txt").string() + " -o " +
                            (out / "x.ply").string());
    EXPECT_EQ(noStore.exitCode, 2);
    EXPECT_NE(noStore.err.find("drift.vkframes"), std::string::npos) << noStore.err;
    test::writeBytes(out / "bad.txt", "# timestamp tx ty tz qx qy qz qw\n0 0 0 0 0 0 0 7\n");   // a quaternion far from unit norm
    CliRun badPose = runCli("correct " + (out / "corrected.vkmap").string() + " --trajectory " + (out / "bad.txt").string() + " -o " +
                            (out / "x.ply").string());
    EXPECT_EQ(badPose.exitCode, 2);
    EXPECT_NE(badPose.err.find("bad.txt"), std::string::npos) << badPose.err;
}

}  // namespace
}  // namespace vkmesh
