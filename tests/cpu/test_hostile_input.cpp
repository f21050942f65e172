// Broken and hostile input (issue 5): each case writes one broken file into an otherwise valid dataset (or
// a mesh) and checks the outcome is a clear vkmesh::Error naming the file and the offending value, never a
// crash and never a silently wrong result. The conventions followed (src/io/dataset.cpp, host/*_command.cpp):
//   - a bad index, trajectory or calibration file rejects the whole dataset at Dataset::open (exit code 2
//     in `vkmesh fuse`): every frame depends on it;
//   - a bad depth image after frame 0 is an Error from loadDepth, which `vkmesh fuse` reports as a warning
//     and skips that frame; frame 0 is read at open (it gives the image size), so a bad frame 0 rejects;
//   - a NaN or non-rigid pose is never fused: it rejects the dataset (no pose can be trusted to be
//     "the only" bad one in a file that holds it);
//   - unsorted timestamps are legitimate (sorted); a repeated one keeps the first entry, with a warning.
#include "io/dataset.h"
#include "io/parsers.h"
#include "io/ply.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace vkmesh;
using test::errorMessageOf;
using test::makeMinimalTum;
using test::writeBytes;
using test::writePng;

namespace {

// EXPECT that `message` contains each of `needles`.
void expectMentions(const std::string& message, std::initializer_list<std::string> needles) {
    for (const auto& n : needles) EXPECT_NE(message.find(n), std::string::npos) << "'" << n << "' not in: " << message;
}

bool anyWarning(const Dataset& ds, const std::string& needle) {
    return std::any_of(ds.warnings().begin(), ds.warnings().end(),
                       [&](const std::string& w) { return w.find(needle) != std::string::npos; });
}

std::string depthPath(const fs::path& dir, int i) { return (dir / "depth" / (std::to_string(i) + ".png")).string(); }

}  // namespace

// ------------------------------------------------------------------------------------------ depth PNGs

TEST(HostileDepth, TruncatedPngNamesTheFile) {
    fs::path dir = makeMinimalTum("fr1_trunc");
    auto ds = Dataset::open(dir);
    // Frame 1 cut inside its image data: loadDepth fails (fuse warns and skips the frame).
    fs::resize_file(depthPath(dir, 1), fs::file_size(depthPath(dir, 1)) - 20);
    expectMentions(errorMessageOf([&] { ds->loadDepth(1); }), {depthPath(dir, 1), "truncated or corrupt"});
    // Frame 0 cut inside its header: the dataset is rejected at open.
    fs::resize_file(depthPath(dir, 0), 20);
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {depthPath(dir, 0), "truncated or corrupt"});
    // An empty file and a text file are not PNGs.
    writeBytes(depthPath(dir, 0), "");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {depthPath(dir, 0), "not a PNG", "empty"});
    writeBytes(depthPath(dir, 0), "1 2 3\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {depthPath(dir, 0), "not a PNG"});
}

TEST(HostileDepth, EightBitAndRgbPngsAreNotDepth) {
    fs::path dir = makeMinimalTum("fr1_types");
    auto ds = Dataset::open(dir);
    writePng(depthPath(dir, 1), 8, 6, CV_8UC1, 200);
    expectMentions(errorMessageOf([&] { ds->loadDepth(1); }), {depthPath(dir, 1), "8-bit grayscale", "16-bit"});
    writePng(depthPath(dir, 1), 8, 6, CV_16UC3, 5000);
    expectMentions(errorMessageOf([&] { ds->loadDepth(1); }), {depthPath(dir, 1), "16-bit RGB, 3 channels"});
    writePng(depthPath(dir, 1), 8, 6, CV_8UC3, 10);
    expectMentions(errorMessageOf([&] { ds->loadDepth(1); }), {depthPath(dir, 1), "8-bit RGB"});
    writePng(depthPath(dir, 1), 8, 6, CV_16UC4, 5000);
    expectMentions(errorMessageOf([&] { ds->loadDepth(1); }), {depthPath(dir, 1), "RGBA, 4 channels"});
    // As frame 0, the same image rejects the dataset.
    writePng(depthPath(dir, 0), 8, 6, CV_8UC1, 200);
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {depthPath(dir, 0), "8-bit"});
}

TEST(HostileDepth, WrongSizeForTheIntrinsics) {
    fs::path dir = makeMinimalTum("fr1_size");
    // camera.json states its image size: images of another size reject the dataset.
    writeBytes(dir / "camera.json", R"({"fx": 525, "fy": 525, "cx": 319.5, "cy": 239.5, "width": 640, "height": 480})");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }),
                   {(dir / "camera.json").string(), "640x480", depthPath(dir, 0), "8x6"});
    // The right size is accepted.
    writeBytes(dir / "camera.json", R"({"fx": 5, "fy": 5, "cx": 3.5, "cy": 2.5, "width": 8, "height": 6})");
    EXPECT_EQ(Dataset::open(dir)->size(), 3u);
    // Without a stated size, a principal point outside the images is warned about, naming the values.
    writeBytes(dir / "camera.json", R"({"fx": 525, "fy": 525, "cx": 319.5, "cy": 239.5})");
    auto ds = Dataset::open(dir);
    EXPECT_TRUE(anyWarning(*ds, "cx=319.5 cy=239.5 lies outside the 8x6")) << ds->warnings().size();
    // A frame of another size than frame 0: loadDepth names both sizes.
    writePng(depthPath(dir, 2), 16, 12, CV_16UC1, 5000);
    expectMentions(errorMessageOf([&] { ds->loadDepth(2); }), {depthPath(dir, 2), "16x12", "8x6"});
    // A header claiming a gigantic image is rejected before anything is allocated.
    std::string png = "\x89PNG\r\n\x1a\n" + std::string("\0\0\0\x0dIHDR", 8) + std::string("\0\0\x75\x30\0\0\x75\x30\x10\0\0\0\0", 13) +
                      std::string(4, '\0');
    writeBytes(depthPath(dir, 1), png);
    expectMentions(errorMessageOf([&] { ds->loadDepth(1); }), {depthPath(dir, 1), "30000x30000"});
}

// ------------------------------------------------------------------------------------------ poses

TEST(HostilePose, NanAndInfinityInAPoseRejectTheDataset) {
    fs::path dir = makeMinimalTum("fr1_nan");
    const fs::path gt = dir / "groundtruth.txt";
    writeBytes(gt, "1 0 0 0 0 0 0 1\n2 nan 0 0 0 0 0 1\n3 2 0 0 0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {gt.string() + ":2", "nan"});
    writeBytes(gt, "1 0 0 0 0 0 0 1\n2 1 0 0 0 0 inf 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {gt.string() + ":2", "inf"});
    // A timestamp overflowing to infinity.
    writeBytes(gt, "1e999 0 0 0 0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {gt.string() + ":1"});

    // Redwood: a NaN inside the 4x4 matrix.
    fs::path rw = test::makeTempDir("hostile") / "redwood";
    writePng(rw / "depth" / "000000.png", 8, 6, CV_16UC1, 1000);
    writeBytes(rw / "traj.log", "0 0 1\n1 0 0 0\n0 1 0 nan\n0 0 1 0\n0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(rw); }), {(rw / "traj.log").string() + ":2", "non-finite"});

    // 7-Scenes: infinity in the pose file.
    fs::path seven = test::makeTempDir("hostile") / "seq-01";
    writePng(seven / "frame-000000.depth.png", 8, 6, CV_16UC1, 1000);
    writeBytes(seven / "frame-000000.pose.txt", "1 0 0 inf\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(seven); }), {(seven / "frame-000000.pose.txt").string(), "non-finite"});
}

TEST(HostilePose, NonRigidPosesRejectTheDataset) {
    fs::path rw = test::makeTempDir("hostile") / "redwood";
    writePng(rw / "depth" / "000000.png", 8, 6, CV_16UC1, 1000);
    // Scaled rotation (a similarity, not a rigid transform).
    writeBytes(rw / "traj.log", "0 0 1\n1.1 0 0 0\n0 1.1 0 0\n0 0 1.1 0\n0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(rw); }), {(rw / "traj.log").string() + ":2", "not orthonormal", "frame 0"});
    // Sheared.
    writeBytes(rw / "traj.log", "0 0 1\n1 0.2 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(rw); }), {(rw / "traj.log").string() + ":2", "not orthonormal"});
    // A reflection: orthonormal, determinant -1.
    fs::path seven = test::makeTempDir("hostile") / "seq-01";
    writePng(seven / "frame-000000.depth.png", 8, 6, CV_16UC1, 1000);
    writeBytes(seven / "frame-000000.pose.txt", "-1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(seven); }), {(seven / "frame-000000.pose.txt").string(), "determinant"});
    // A projective bottom row.
    writeBytes(seven / "frame-000000.pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0.5 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(seven); }), {(seven / "frame-000000.pose.txt").string(), "bottom row"});
}

TEST(HostilePose, ZeroLengthQuaternion) {
    fs::path dir = makeMinimalTum("fr1_zeroq");
    writeBytes(dir / "groundtruth.txt", "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 0\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }),
                   {(dir / "groundtruth.txt").string() + ":2", "quaternion (0 0 0 0)", "norm 0"});
}

// ------------------------------------------------------------------------------------------ timestamps

TEST(HostileTimestamps, UnsortedAreSortedAndAssociatedByTime) {
    fs::path dir = makeMinimalTum("fr1_unsorted");
    writeBytes(dir / "depth.txt", "3 depth/2.png\n1 depth/0.png\n2 depth/1.png\n");
    writeBytes(dir / "groundtruth.txt", "2 1 0 0 0 0 0 1\n3 2 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n");
    auto ds = Dataset::open(dir);
    ASSERT_EQ(ds->size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_DOUBLE_EQ(ds->frame(i).timestamp, double(i + 1));
        EXPECT_EQ(ds->frame(i).depthPath.filename(), std::to_string(i) + ".png");
        EXPECT_DOUBLE_EQ(ds->frame(i).cameraToWorld(0, 3), double(i));  // the pose at the frame's own time
    }
}

TEST(HostileTimestamps, DuplicatesKeepTheFirstAndWarn) {
    fs::path dir = makeMinimalTum("fr1_dup");
    writeBytes(dir / "depth.txt", "1 depth/0.png\n2 depth/1.png\n2 depth/2.png\n");
    writeBytes(dir / "groundtruth.txt", "1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n2 7 0 0 0 0 0 1\n");
    auto ds = Dataset::open(dir);
    ASSERT_EQ(ds->size(), 2u);
    EXPECT_EQ(ds->frame(1).depthPath.filename(), "1.png");
    EXPECT_DOUBLE_EQ(ds->frame(1).cameraToWorld(0, 3), 1.0);
    EXPECT_EQ(ds->skippedFrames(), 1u);
    EXPECT_TRUE(anyWarning(*ds, (dir / "depth.txt").string() + ":3: timestamp 2 repeats line 2"));
    EXPECT_TRUE(anyWarning(*ds, (dir / "groundtruth.txt").string() + ":3: timestamp 2 repeats line 2"));
}

// ------------------------------------------------------------------------------------------ empty and missing files

TEST(HostileFiles, EmptyFilesNameTheFile) {
    fs::path dir = makeMinimalTum("fr1_empty");
    writeBytes(dir / "groundtruth.txt", "# only a comment\n\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "groundtruth.txt").string(), "no poses"});

    dir = makeMinimalTum("fr1_empty");
    writeBytes(dir / "depth.txt", "");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "depth.txt").string(), "no depth frames"});

    dir = makeMinimalTum("fr1_empty");
    fs::remove(dir / "depth.txt");
    writeBytes(dir / "associations.txt", "\r\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "associations.txt").string(), "no depth frames"});

    fs::path rw = test::makeTempDir("hostile") / "redwood";
    writePng(rw / "depth" / "000000.png", 8, 6, CV_16UC1, 1000);
    writeBytes(rw / "traj.log", "");
    expectMentions(errorMessageOf([&] { Dataset::open(rw); }), {(rw / "traj.log").string(), "no poses"});

    fs::path seven = test::makeTempDir("hostile") / "seq-01";
    writePng(seven / "frame-000000.depth.png", 8, 6, CV_16UC1, 1000);
    writeBytes(seven / "frame-000000.pose.txt", "");
    expectMentions(errorMessageOf([&] { Dataset::open(seven); }), {(seven / "frame-000000.pose.txt").string(), "found 0 numbers"});

    dir = makeMinimalTum("fr1_empty");
    writeBytes(dir / "camera.json", "");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "camera.json").string(), "not valid JSON"});
}

TEST(HostileFiles, MissingFilesNameTheFile) {
    fs::path dir = makeMinimalTum("fr1_missing");
    fs::remove(dir / "groundtruth.txt");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {dir.string(), "no groundtruth.txt"});

    dir = makeMinimalTum("fr1_missing");
    fs::remove(depthPath(dir, 2));
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {depthPath(dir, 2), "does not exist"});

    // Deleted between open and the frame's turn: an Error from loadDepth (fuse warns and skips it).
    dir = makeMinimalTum("fr1_missing");
    auto ds = Dataset::open(dir);
    fs::remove(depthPath(dir, 1));
    expectMentions(errorMessageOf([&] { ds->loadDepth(1); }), {depthPath(dir, 1), "does not exist"});

    expectMentions(errorMessageOf([&] { Dataset::open(dir / "nope"); }), {(dir / "nope").string(), "does not exist"});
}

// ------------------------------------------------------------------------------------------ malformed lines

TEST(HostileLines, TooFewFieldsNameTheLine) {
    fs::path dir = makeMinimalTum("fr1_fields");
    writeBytes(dir / "groundtruth.txt", "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "groundtruth.txt").string() + ":2", "got 7"});

    dir = makeMinimalTum("fr1_fields");
    writeBytes(dir / "depth.txt", "1 depth/0.png\n2\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "depth.txt").string() + ":2", "'timestamp path'"});

    dir = makeMinimalTum("fr1_fields");
    fs::remove(dir / "depth.txt");
    writeBytes(dir / "associations.txt", "1 rgb/0.png 1 depth/0.png\n2 rgb/1.png\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "associations.txt").string() + ":2"});

    fs::path rw = test::makeTempDir("hostile") / "redwood";
    writePng(rw / "depth" / "000000.png", 8, 6, CV_16UC1, 1000);
    writeBytes(rw / "traj.log", "0 0 1\n1 0 0 0\n0 1 0\n0 0 1 0\n0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(rw); }), {(rw / "traj.log").string() + ":3", "got 3"});
    writeBytes(rw / "traj.log", "0 0 1\n1 0 0 0\n0 1 0 0\n");  // the file ends inside the matrix
    expectMentions(errorMessageOf([&] { Dataset::open(rw); }), {(rw / "traj.log").string() + ":1", "ends inside"});
}

TEST(HostileLines, GarbageNumbersAreNamed) {
    fs::path dir = makeMinimalTum("fr1_garbage");
    writeBytes(dir / "depth.txt", "1 depth/0.png\n1.0abc depth/1.png\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "depth.txt").string() + ":2", "1.0abc"});

    dir = makeMinimalTum("fr1_garbage");
    writeBytes(dir / "groundtruth.txt", "1 0 0 0 0 0 0 1\n2 1.0abc 0 0 0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "groundtruth.txt").string() + ":2", "'1.0abc' is not a number"});

    dir = makeMinimalTum("fr1_garbage");
    writeBytes(dir / "groundtruth.txt", "1 0 0 0 0 0 0 1\n2 0x10 0 0 0 0 0 1\n");  // no hex either
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {(dir / "groundtruth.txt").string() + ":2", "0x10"});

    fs::path rw = test::makeTempDir("hostile") / "redwood";
    writePng(rw / "depth" / "000000.png", 8, 6, CV_16UC1, 1000);
    writeBytes(rw / "traj.log", "0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 1.0abc\n0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(rw); }), {(rw / "traj.log").string() + ":4", "1.0abc"});
    writeBytes(rw / "traj.log", "zero 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(rw); }), {(rw / "traj.log").string() + ":1", "zero"});

    fs::path seven = test::makeTempDir("hostile") / "seq-01";
    writePng(seven / "frame-000000.depth.png", 8, 6, CV_16UC1, 1000);
    writeBytes(seven / "frame-000000.pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    writeBytes(seven / "camera-intrinsics.txt", "585 0 320\n0 585 240.0abc\n0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(seven); }), {(seven / "camera-intrinsics.txt").string() + ":2", "240.0abc"});
}

// ------------------------------------------------------------------------------------------ calibration

TEST(HostileCalibration, CameraJsonWithoutUsableFields) {
    fs::path dir = makeMinimalTum("fr1_json");
    const std::string json = (dir / "camera.json").string();
    writeBytes(dir / "camera.json", "{}");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {json, "holds none of the keys", "(it is empty)"});
    // Another tool's format (Open3D's PinholeCameraIntrinsic): would otherwise be ignored in silence.
    writeBytes(dir / "camera.json", R"({"intrinsic_matrix": [525, 0, 0, 0, 525, 0, 319.5, 239.5, 1]})");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {json, "\"intrinsic_matrix\""});
    // Every key misspelt.
    writeBytes(dir / "camera.json", R"({"Fx": 500, "focal_y": 500})");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {json, "\"Fx\"", "\"focal_y\""});
    // A known key beside unknown ones: used, and the unknown ones named in a warning.
    writeBytes(dir / "camera.json", R"({"fx": 500, "depthscale": 1000})");
    auto ds = Dataset::open(dir);
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 500.0f);
    EXPECT_TRUE(anyWarning(*ds, "ignored unknown keys \"depthscale\""));
    // Wrong types and absurd sizes.
    writeBytes(dir / "camera.json", R"({"fx": null})");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {json, "\"fx\" is null"});
    writeBytes(dir / "camera.json", R"({"width": -640})");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {json, "\"width\" is -640"});
    writeBytes(dir / "camera.json", R"({"height": 1e30})");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {json, "\"height\""});
}

TEST(HostileCalibration, NegativeFocalLengths) {
    fs::path dir = makeMinimalTum("fr1_negf");
    const std::string json = (dir / "camera.json").string();
    writeBytes(dir / "camera.json", R"({"fx": -525, "fy": 525, "cx": 3.5, "cy": 2.5})");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {json, "\"fx\" = -525", "negative"});
    // A negative fy mirrors a TUM reconstruction: rejected, from camera.json or --intrinsics.
    writeBytes(dir / "camera.json", R"({"fx": 525, "fy": -525, "cx": 3.5, "cy": 2.5})");
    expectMentions(errorMessageOf([&] { Dataset::open(dir); }), {json, "fy = -525", "negative"});
    fs::remove(dir / "camera.json");
    DatasetOptions o;
    o.intrinsics = parseIntrinsics("525,-525,3.5,2.5");
    expectMentions(errorMessageOf([&] { Dataset::open(dir, o); }), {"--intrinsics", "fy = -525"});
    expectMentions(errorMessageOf([] { parseIntrinsics("-525,525,3.5,2.5"); }), {"-525,525,3.5,2.5", "fx = -525", "negative"});
    // ... but it is ICL-NUIM's convention, and accepted there.
    fs::path icl = makeMinimalTum("icl_office_negf");
    writeBytes(icl / "camera.json", R"({"fx": 481.2, "fy": -480, "cx": 3.5, "cy": 2.5})");
    auto ds = Dataset::open(icl);
    EXPECT_EQ(ds->kind(), DatasetKind::ICLNUIM);
    EXPECT_FLOAT_EQ(ds->intrinsics().fy, -480.0f);
    // 7-Scenes camera-intrinsics.txt with a negative focal length.
    fs::path seven = test::makeTempDir("hostile") / "seq-01";
    writePng(seven / "frame-000000.depth.png", 8, 6, CV_16UC1, 1000);
    writeBytes(seven / "frame-000000.pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    writeBytes(seven / "camera-intrinsics.txt", "-585 0 320\n0 585 240\n0 0 1\n");
    expectMentions(errorMessageOf([&] { Dataset::open(seven); }), {(seven / "camera-intrinsics.txt").string(), "fx=-585"});
}

// ------------------------------------------------------------------------------------------ PLY

namespace {
const std::string kPlyHead = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
const std::string kPlyVerts = "0 0 0\n1 0 0\n0 1 0\n";
}  // namespace

TEST(HostilePly, IndicesOutOfRange) {
    fs::path dir = test::makeTempDir("hostile_ply");
    const std::string face = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    writeBytes(dir / "a.ply", kPlyHead + face + kPlyVerts + "3 0 1 3\n");
    expectMentions(errorMessageOf([&] { readPly(dir / "a.ply"); }), {(dir / "a.ply").string(), "face 0 uses vertex 3 of 3"});
    writeBytes(dir / "b.ply", kPlyHead + face + kPlyVerts + "3 0 -1 2\n");
    expectMentions(errorMessageOf([&] { readPly(dir / "b.ply"); }), {(dir / "b.ply").string(), "vertex -1"});
    // Binary: index 2^32-1.
    std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                      "property float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
    bin += std::string(12, '\0') + std::string("\x03\0\0\0\0\0\0\0\0\xff\xff\xff\xff", 13);
    writeBytes(dir / "c.ply", bin);
    expectMentions(errorMessageOf([&] { readPly(dir / "c.ply"); }), {(dir / "c.ply").string(), "vertex 4294967295 of 1"});
}

TEST(HostilePly, TruncatedBody) {
    fs::path dir = test::makeTempDir("hostile_ply");
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    writePly(dir / "m.ply", m);
    fs::resize_file(dir / "m.ply", fs::file_size(dir / "m.ply") - 3);
    expectMentions(errorMessageOf([&] { readPly(dir / "m.ply"); }), {(dir / "m.ply").string(), "truncated"});
    writeBytes(dir / "a.ply", kPlyHead + "end_header\n0 0 0\n1 0");
    expectMentions(errorMessageOf([&] { readPly(dir / "a.ply"); }), {(dir / "a.ply").string(), "truncated"});
    writeBytes(dir / "h.ply", "ply\nformat ascii 1.0\nelement vertex 3\n");
    expectMentions(errorMessageOf([&] { readPly(dir / "h.ply"); }), {(dir / "h.ply").string(), "truncated header"});
}

// Found by fuzz/fuzz_ply: each hung, hit undefined behaviour or returned a silently wrong mesh before.
TEST(HostilePly, FuzzerFindings) {
    const fs::path name = "f.ply";
    // An element with no properties and a count of 2^64-1 spun through 2^64 empty iterations (a hang).
    auto start = std::chrono::steady_clock::now();
    Mesh m = parsePly(kPlyHead + "element junk 18446744073709551615\nend_header\n" + kPlyVerts, name);
    EXPECT_EQ(m.positions.size(), 3u);
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
    // An ascii list count of 1e300 or inf was cast to size_t (undefined behaviour).
    const std::string face = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    for (const char* count : {"1e300", "inf", "256", "2.5"})
        expectMentions(errorMessageOf([&] { parsePly(kPlyHead + face + kPlyVerts + count + " 0 1 2\n", name); }),
                       {"f.ply", std::string("'") + count + "' is not a valid uchar"});
    // NaN and out-of-float-range coordinates were stored as vertices.
    expectMentions(errorMessageOf([&] { parsePly(kPlyHead + "end_header\n0 0 0\n0 nan 0\n0 0 0\n", name); }),
                   {"f.ply", "vertex 1 has coordinate y = nan"});
    expectMentions(errorMessageOf([&] { parsePly(kPlyHead + "end_header\n0 0 0\n0 0 0\n0 0 1e300\n", name); }),
                   {"f.ply", "vertex 2 has coordinate z"});
}

// ------------------------------------------------------------------------------------------ the parsers on text

// The in-memory entry points the fuzzers use give the same messages as the file readers, named by the
// source string they are given.
TEST(HostileParsers, InMemoryParsersNameTheSource) {
    std::istringstream gt("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0\n");
    expectMentions(errorMessageOf([&] { io::parseTrajectory(gt, "mem.freiburg"); }), {"mem.freiburg:2", "got 7"});
    std::istringstream ok("# c\n0 0 0 -2.25 0 0 0 1\n1 0.1 0 -2.25 0 0 0.0998 0.995\n");
    auto poses = io::parseTrajectory(ok, "livingRoom0.gt.freiburg");
    ASSERT_EQ(poses.size(), 2u);
    EXPECT_EQ(poses[1].line, 3u);
    std::istringstream list("1 a.png b\n");
    expectMentions(errorMessageOf([&] { io::parseDepthList(list, "mem.txt", "/d"); }), {"mem.txt:1", "a.png b"});
    std::istringstream json("{\"fx\": \"five\"}");
    expectMentions(errorMessageOf([&] { io::parseCameraJson(json, "mem.json"); }), {"mem.json", "\"five\""});
    std::istringstream deep(std::string(100000, '['));
    expectMentions(errorMessageOf([&] { io::parseCameraJson(deep, "deep.json"); }), {"deep.json", "not valid JSON"});
    expectMentions(errorMessageOf([] { io::decodeDepthPng("", "mem.png"); }), {"mem.png", "empty"});
}

// ------------------------------------------------------------------------------------------ colour images
// Colour is optional: a bad colour image costs that frame its colour (a warning from loadColor), never the
// reconstruction; a bad colour calibration in camera.json is still an error at open, like any calibration.

namespace {

// A minimal TUM sequence whose frame 1 has `bytes` as its colour image and frames 0 and 2 a valid one.
fs::path tumWithColor(const std::string& name, const std::string& bytes, const std::string& ext = ".png") {
    fs::path dir = makeMinimalTum(name);
    writeBytes(dir / "rgb.txt", "1 rgb/0.png\n2 rgb/1" + ext + "\n3 rgb/2.png\n");
    writePng(dir / "rgb" / "0.png", 8, 6, CV_8UC3, 90);
    writePng(dir / "rgb" / "2.png", 8, 6, CV_8UC3, 90);
    writeBytes(dir / "rgb" / ("1" + ext), bytes);
    return dir;
}

std::string colorWarning(const Dataset& ds, size_t frame) {
    std::string warning;
    EXPECT_TRUE(ds.loadColor(frame, &warning).empty()) << "frame " << frame << " gave colour";
    return warning;
}

}  // namespace

TEST(HostileColor, EmptyGarbageAndTruncatedImagesAreWarnings) {
    const std::string png = test::readText(fs::path(VKMESH_SOURCE_DIR) / "fuzz/corpus/fuzz_depth_png/gray8_4x3.png");
    const struct {
        const char* name;
        std::string bytes;
        const char* ext;
        std::vector<std::string> needles;
    } cases[] = {
        {"empty", "", ".png", {"neither a PNG nor a JPEG", "empty"}},
        {"text", "P3\n2 2\n255\n", ".png", {"neither a PNG nor a JPEG"}},
        {"png_header_only", png.substr(0, 20), ".png", {"truncated or corrupt"}},
        {"png_cut", png.substr(0, png.size() - 20), ".png", {"1.png"}},
        {"jpeg_no_frame", std::string("\xFF\xD8\xFF\xD9", 4), ".jpg", {"JPEG", "no frame header"}},
        // A JPEG whose frame header claims 65535 x 65535: refused before the decoder allocates.
        {"jpeg_huge", std::string("\xFF\xD8\xFF\xC0\x00\x11\x08\xFF\xFF\xFF\xFF\x03\x01\x22\x00\x02\x11\x01\x03\x11\x01", 21), ".jpg",
         {"65535x65535", "more than vkmesh accepts"}},
        {"jpeg_bad_length", std::string("\xFF\xD8\xFF\xE0\x00\x00", 6), ".jpg", {"corrupt JPEG"}},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.name);
        const fs::path dir = tumWithColor(std::string("fr1_color_") + c.name, c.bytes, c.ext);
        auto ds = Dataset::open(dir);  // never an error: the file exists
        ASSERT_TRUE(ds->hasColor());
        EXPECT_FALSE(ds->loadColor(0).empty());
        const std::string w = colorWarning(*ds, 1);
        expectMentions(w, {(dir / "rgb" / (std::string("1") + c.ext)).string(), "frame 1 has no colour"});
        for (const auto& n : c.needles) expectMentions(w, {n});
        EXPECT_FALSE(ds->loadColor(2).empty());
    }
    // The in-memory decoder names its source and throws only vkmesh::Error.
    expectMentions(errorMessageOf([] { io::decodeColorImage("", "mem.jpg"); }), {"mem.jpg", "empty"});
}

TEST(HostileColor, WrongKindsOfImage) {
    fs::path dir = tumWithColor("fr1_color_kinds", "");
    writePng(dir / "rgb" / "1.png", 8, 6, CV_16UC3, 1000);  // 16-bit colour
    auto ds = Dataset::open(dir);
    expectMentions(colorWarning(*ds, 1), {"1.png", "16-bit", "expected 8 bits"});
    writePng(dir / "rgb" / "1.png", 6, 8, CV_8UC3, 10);  // transposed size
    expectMentions(colorWarning(*ds, 1), {"1.png", "6x8", "depth images are 8x6"});
    writePng(dir / "rgb" / "1.png", 8, 6, CV_8UC4, 10);  // RGBA: alpha dropped, fine
    std::string warning;
    EXPECT_FALSE(ds->loadColor(1, &warning).empty()) << warning;
    fs::remove(dir / "rgb" / "1.png");  // deleted after open: a warning, not a crash
    expectMentions(colorWarning(*ds, 1), {"1.png", "cannot open"});
    // Missing at open: that frame loses its colour with a warning, the rest keep theirs.
    ds = Dataset::open(dir);
    EXPECT_TRUE(ds->hasColor());
    EXPECT_TRUE(anyWarning(*ds, "1.png (frame 1) does not exist"));
    // A broken rgb.txt costs the colour, not the dataset.
    writeBytes(dir / "rgb.txt", "1 rgb/0.png extra\n");
    ds = Dataset::open(dir);
    EXPECT_FALSE(ds->hasColor());
    EXPECT_TRUE(anyWarning(*ds, "rgb.txt:1"));
    EXPECT_TRUE(anyWarning(*ds, "colour ignored"));
    EXPECT_TRUE(anyWarning(*ds, "no colour images: depth only"));
}

TEST(HostileColor, ColourCalibrationValues) {
    fs::path dir = tumWithColor("fr1_color_json", "");
    const std::string json = (dir / "camera.json").string();
    const struct {
        const char* text;
        std::vector<std::string> needles;
    } cases[] = {
        {R"({"color_fx": 500, "color_fy": 500, "color_cx": 3})", {"all four of color_fx"}},
        {R"({"color_fx": -5, "color_fy": 500, "color_cx": 3, "color_cy": 2})", {"\"color_fx\" = -5", "positive"}},
        {R"({"color_fx": 5, "color_fy": 0, "color_cx": 3, "color_cy": 2})", {"\"color_fy\" = 0"}},
        {R"({"color_fx": "five", "color_fy": 5, "color_cx": 3, "color_cy": 2})", {"\"color_fx\" is \"five\""}},
        {R"({"color_fx": 5, "color_fy": 5, "color_cx": 3, "color_cy": 2, "color_width": 1e30})", {"\"color_width\""}},
        {R"({"color_width": 640, "color_height": 480})", {"color_width/color_height given without"}},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.text);
        writeBytes(dir / "camera.json", c.text);
        const std::string m = errorMessageOf([&] { Dataset::open(dir); });
        expectMentions(m, {json});
        for (const auto& n : c.needles) expectMentions(m, {n});
    }
}
