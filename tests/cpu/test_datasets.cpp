// Dataset input by layout: detection, association, poses, depth scaling and calibration precedence of TUM,
// ICL-NUIM, Redwood and 7-Scenes, on tiny fixtures (dataset_fixtures.h) and on the shared real sequences.
// Bad input and camera presets: test_dataset_errors.cpp; colour and sequences without poses:
// test_dataset_color_poseless.cpp.
#include "io/dataset.h"
#include "test_support.h"
#include "dataset_fixtures.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <optional>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

namespace fs = std::filesystem;
using namespace vkmesh;
using namespace vkmesh::test::dataset_fixtures;

// ------------------------------------------------------------------------------------------ TUM

TEST(DatasetTum, DetectsAssociatesAndSkipsFrameWithoutPose) {
    TumFixture f = makeTum();
    auto ds = Dataset::open(f.dir);
    EXPECT_EQ(ds->kind(), DatasetKind::TUM);
    EXPECT_EQ(toString(ds->kind()), "TUM RGB-D");
    ASSERT_EQ(ds->size(), 5u);
    EXPECT_EQ(ds->skippedFrames(), 1u);
    // The skipped frame is named in a warning, with its distance to the nearest pose.
    EXPECT_TRUE(anyContains(ds->warnings(), "100.300000.png")) << joinLines(ds->warnings());
    EXPECT_TRUE(anyContains(ds->warnings(), "30.0 ms")) << joinLines(ds->warnings());
    EXPECT_TRUE(anyContains(ds->warnings(), "depth.txt:6")) << joinLines(ds->warnings());
    std::vector<double> kept{100.004, 100.104, 100.204, 100.404, 100.504};
    for (size_t i = 0; i < ds->size(); ++i) {
        EXPECT_EQ(ds->frame(i).index, i);
        EXPECT_DOUBLE_EQ(ds->frame(i).timestamp, kept[i]);
        // Nearest tick is 4 ms earlier; the file rounds the pose to 9 decimals.
        expectPoseNear(ds->frame(i).cameraToWorld, tumPoseAt(kept[i] - 0.004), 1e-6);
        validatePose(ds->frame(i).cameraToWorld, "frame");
    }
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 517.3f);
    EXPECT_FLOAT_EQ(ds->intrinsics().fy, 516.5f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cx, 318.6f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cy, 255.3f);
    EXPECT_EQ(ds->intrinsics().width, W);
    EXPECT_EQ(ds->intrinsics().height, H);
    EXPECT_DOUBLE_EQ(ds->depthScale(), 5000.0);
}

TEST(DatasetTum, DepthIsRawOver5000AndMaxDepthCuts) {
    TumFixture f = makeTum();
    auto ds = Dataset::open(f.dir);
    DepthImage d = ds->loadDepth(3);  // 4th kept frame = file index 4
    ASSERT_EQ(d.width, W);
    ASSERT_EQ(d.height, H);
    ASSERT_EQ(d.meters.size(), size_t(W * H));
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) EXPECT_FLOAT_EQ(d.at(x, y), ramp(4, x, y) / 5000.0f);

    DatasetOptions o;
    o.maxDepth = ramp(0, 4, 0) / 5000.0f;  // keeps x <= 4 of frame 0
    auto cut = Dataset::open(f.dir, o);
    DepthImage c = cut->loadDepth(0);
    for (int x = 0; x < W; ++x) EXPECT_EQ(c.at(x, 0) == 0.0f, x > 4) << x;
}

TEST(DatasetTum, QuaternionConversionAgainstKnownRotation) {
    auto dir = test::makeTempDir("tumq") / "rgbd_dataset_freiburg2_desk";
    writeDepth(dir / "depth/1.png", [](int, int) { return 5000; });
    writeDepth(dir / "depth/2.png", [](int, int) { return 5000; });
    writeText(dir / "depth.txt", "1.0 depth/1.png\n2.0 depth/2.png\n");
    // 90 degrees about z; line 2 is the same quaternion scaled by 1.5 (must be normalised).
    writeText(dir / "groundtruth.txt",
              "1.0 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n"
              "2.0 0 0 0 0 0 1.0606601717798212 1.0606601717798212\n");
    auto ds = Dataset::open(dir);
    ASSERT_EQ(ds->size(), 2u);
    Pose expected = Pose::Identity();
    expected.topLeftCorner<3, 3>() << 0, -1, 0, 1, 0, 0, 0, 0, 1;
    expected.topRightCorner<3, 1>() << 1, 2, 3;
    expectPoseNear(ds->frame(0).cameraToWorld, expected, 1e-12);
    expected.topRightCorner<3, 1>().setZero();
    expectPoseNear(ds->frame(1).cameraToWorld, expected, 1e-12);
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 520.9f);  // freiburg2
}

TEST(DatasetTum, SequenceNamesSelectIntrinsics) {
    struct Case { std::string name; float fx; bool warns; };
    for (const Case& c : {Case{"tum_fr1_rpy", 517.3f, false}, Case{"fr2_desk", 520.9f, false},
                          Case{"rgbd_dataset_freiburg3_office", 535.4f, false}, Case{"my_room", 525.0f, true}}) {
        TumFixture f = makeTum(c.name);
        auto ds = Dataset::open(f.dir);
        EXPECT_EQ(ds->kind(), DatasetKind::TUM) << c.name;
        EXPECT_FLOAT_EQ(ds->intrinsics().fx, c.fx) << c.name;
        EXPECT_EQ(anyContains(ds->warnings(), "default intrinsics"), c.warns) << c.name << "\n" << joinLines(ds->warnings());
    }
}

TEST(DatasetTum, IntrinsicsPrecedenceOptionsOverCameraJsonOverDefault) {
    TumFixture f = makeTum();
    writeText(f.dir / "camera.json", R"({"fx": 600.5, "cy": 100, "depth_scale": 1000})");
    auto ds = Dataset::open(f.dir);
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 600.5f);  // camera.json
    EXPECT_FLOAT_EQ(ds->intrinsics().fy, 516.5f);  // layout default (freiburg1)
    EXPECT_FLOAT_EQ(ds->intrinsics().cx, 318.6f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cy, 100.0f);
    EXPECT_DOUBLE_EQ(ds->depthScale(), 1000.0);
    EXPECT_FLOAT_EQ(ds->loadDepth(0).at(0, 0), ramp(0, 0, 0) / 1000.0f);

    DatasetOptions o;
    o.intrinsics = parseIntrinsics("400,401,300,200");
    o.depthScale = 2000.0;
    auto over = Dataset::open(f.dir, o);
    EXPECT_FLOAT_EQ(over->intrinsics().fx, 400.0f);
    EXPECT_FLOAT_EQ(over->intrinsics().fy, 401.0f);
    EXPECT_FLOAT_EQ(over->intrinsics().cx, 300.0f);
    EXPECT_FLOAT_EQ(over->intrinsics().cy, 200.0f);
    EXPECT_EQ(over->intrinsics().width, W);  // size still from the images
    EXPECT_EQ(over->intrinsics().height, H);
    EXPECT_DOUBLE_EQ(over->depthScale(), 2000.0);
    EXPECT_FLOAT_EQ(over->loadDepth(0).at(0, 0), ramp(0, 0, 0) / 2000.0f);
}

TEST(DatasetTum, FullCameraJsonSilencesTheDefaultIntrinsicsWarning) {
    TumFixture f = makeTum("synthetic_room");
    writeText(f.dir / "camera.json", R"({"fx": 300, "fy": 300, "cx": 3.5, "cy": 2.5, "depth_scale": 5000})");
    auto ds = Dataset::open(f.dir);
    EXPECT_FALSE(anyContains(ds->warnings(), "default intrinsics")) << joinLines(ds->warnings());
    EXPECT_FLOAT_EQ(ds->intrinsics().cx, 3.5f);
}

TEST(DatasetTum, UnsortedTimestampsAreSortedAndDuplicatesKeepTheFirst) {
    auto dir = test::makeTempDir("tumdup") / "fr1_dup";
    for (int i = 0; i < 4; ++i) writeDepth(dir / "depth" / (std::to_string(i) + ".png"), [&](int x, int y) { return ramp(i, x, y); });
    // Out of order, and 3.png repeats 1.png's timestamp on a later line.
    writeText(dir / "depth.txt", "2.0 depth/2.png\n1.0 depth/1.png\n0.0 depth/0.png\n1.0 depth/3.png\n");
    writeText(dir / "groundtruth.txt",
              "2.0 2 0 0 0 0 0 1\n0.0 0 0 0 0 0 0 1\n1.0 1 0 0 0 0 0 1\n1.0 9 0 0 0 0 0 1\n");
    auto ds = Dataset::open(dir);
    ASSERT_EQ(ds->size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_DOUBLE_EQ(ds->frame(i).timestamp, double(i));
        EXPECT_EQ(ds->frame(i).depthPath.filename(), std::to_string(i) + ".png");
        EXPECT_DOUBLE_EQ(ds->frame(i).cameraToWorld(0, 3), double(i));  // not 9: first groundtruth line kept
    }
    EXPECT_TRUE(anyContains(ds->warnings(), "depth.txt:4")) << joinLines(ds->warnings());
    EXPECT_TRUE(anyContains(ds->warnings(), "groundtruth.txt:4")) << joinLines(ds->warnings());
}

TEST(DatasetTum, MaxFramesKeepsTheFirstN) {
    TumFixture f = makeTum();
    DatasetOptions o;
    o.maxFrames = 2;
    auto ds = Dataset::open(f.dir, o);
    ASSERT_EQ(ds->size(), 2u);
    EXPECT_DOUBLE_EQ(ds->frame(1).timestamp, 100.104);
}

TEST(DatasetTum, AllZeroDepthIsReturnedNotRejected) {
    TumFixture f = makeTum();
    writeDepth(f.dir / "depth/100.104000.png", [](int, int) { return 0; });
    auto ds = Dataset::open(f.dir);
    DepthImage d = ds->loadDepth(1);
    EXPECT_TRUE(std::all_of(d.meters.begin(), d.meters.end(), [](float v) { return v == 0.0f; }));
}

TEST(DatasetTum, AssociationsTxtIsUsedOnlyWithoutDepthTxt) {
    TumFixture f = makeTum();
    // Lists only two frames, rgb first as TUM's associate.py writes it: ignored while depth.txt exists.
    writeText(f.dir / "associations.txt",
              "100.004 rgb/a.png 100.004000 depth/100.004000.png\n100.1 rgb/b.png 100.104000 depth/100.104000.png\n");
    EXPECT_EQ(Dataset::open(f.dir)->size(), 5u);
    fs::remove(f.dir / "depth.txt");
    auto ds = Dataset::open(f.dir);
    EXPECT_EQ(ds->kind(), DatasetKind::TUM);
    ASSERT_EQ(ds->size(), 2u);
    EXPECT_EQ(ds->frame(1).depthPath.filename(), "100.104000.png");
}

TEST(DatasetTum, NoPoseForAnyFrameIsFatal) {
    TumFixture f = makeTum();
    writeText(f.dir / "groundtruth.txt", "50.0 0 0 0 0 0 0 1\n51.0 0 0 0 0 0 0 1\n");
    std::string msg = errorMessageOf([&] { Dataset::open(f.dir); });
    EXPECT_NE(msg.find("groundtruth.txt"), std::string::npos) << msg;
    EXPECT_NE(msg.find("depth.txt"), std::string::npos) << msg;
}

// ------------------------------------------------------------------------------------------ ICL-NUIM

TEST(DatasetIcl, DetectedByFolderNameWithNegativeFyAndExactAssociation) {
    // Frame 3 has no pose; poses 2 and 4 are one frame away and must not be taken for it.
    auto dir = makeIcl("ICL_office_traj1", {0, 1, 2, 3, 4}, {0, 1, 2, 4});
    auto ds = Dataset::open(dir);
    EXPECT_EQ(ds->kind(), DatasetKind::ICLNUIM);
    EXPECT_EQ(toString(ds->kind()), "ICL-NUIM");
    ASSERT_EQ(ds->size(), 4u);
    EXPECT_EQ(ds->skippedFrames(), 1u);
    EXPECT_TRUE(anyContains(ds->warnings(), "3.png")) << joinLines(ds->warnings());
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 481.2f);
    EXPECT_FLOAT_EQ(ds->intrinsics().fy, -480.0f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cx, 319.5f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cy, 239.5f);
    for (size_t i = 0; i < ds->size(); ++i)
        EXPECT_DOUBLE_EQ(ds->frame(i).cameraToWorld(0, 3), ds->frame(i).timestamp);  // pose i belongs to frame i
    EXPECT_FLOAT_EQ(ds->loadDepth(3).at(1, 1), ramp(4, 1, 1) / 5000.0f);
}

TEST(DatasetIcl, DetectedByFrameIndexTimestamps) {
    auto dir = makeIcl("living_room_traj0_frei_png", {0, 1, 2}, {0, 1, 2});
    EXPECT_EQ(Dataset::open(dir)->kind(), DatasetKind::ICLNUIM);
    // "icl" inside a word is no clue, and Unix-time stamps make it TUM.
    TumFixture f = makeTum("bicycle_shed");
    EXPECT_EQ(Dataset::open(f.dir)->kind(), DatasetKind::TUM);
}

// ------------------------------------------------------------------------------------------ Redwood

TEST(DatasetRedwood, ReadsLogAndMillimetreDepth) {
    auto dir = makeRedwood({0, 1, 3, 4});  // frame 2 has no pose
    auto ds = Dataset::open(dir);
    EXPECT_EQ(ds->kind(), DatasetKind::Redwood);
    EXPECT_EQ(toString(ds->kind()), "Redwood");
    ASSERT_EQ(ds->size(), 4u);
    EXPECT_EQ(ds->skippedFrames(), 1u);
    EXPECT_TRUE(anyContains(ds->warnings(), "000002.png")) << joinLines(ds->warnings());
    std::vector<int> ids{0, 1, 3, 4};
    for (size_t i = 0; i < 4; ++i) {
        expectPoseNear(ds->frame(i).cameraToWorld, redwoodPose(ids[i]), 1e-12);
        EXPECT_FLOAT_EQ(ds->loadDepth(i).at(2, 3), ramp(ids[i], 2, 3) / 1000.0f);
    }
    EXPECT_DOUBLE_EQ(ds->depthScale(), 1000.0);
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 525.0f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cy, 239.5f);
}

TEST(DatasetRedwood, MalformedLogNamesFileAndLine) {
    auto dir = makeRedwood({0, 1});
    writeText(dir / "livingroom1-traj.log", logBlock(0, redwoodPose(0)) + "1 1 2\n1 0 0 0\n0 1 0\n0 0 1 0\n0 0 0 1\n");
    std::string msg = errorMessageOf([&] { Dataset::open(dir); });
    EXPECT_NE(msg.find("livingroom1-traj.log:8"), std::string::npos) << msg;

    writeText(dir / "livingroom1-traj.log", logBlock(0, redwoodPose(0)) + "1 1 2\n1 0 0 0\n");
    msg = errorMessageOf([&] { Dataset::open(dir); });
    EXPECT_NE(msg.find("livingroom1-traj.log:6"), std::string::npos) << msg;

    // A scaled rotation is not a rigid pose.
    Pose bad = redwoodPose(1);
    bad.topLeftCorner<3, 3>() *= 1.1;
    writeText(dir / "livingroom1-traj.log", logBlock(0, redwoodPose(0)) + logBlock(1, bad));
    msg = errorMessageOf([&] { Dataset::open(dir); });
    EXPECT_NE(msg.find("livingroom1-traj.log:7"), std::string::npos) << msg;
    EXPECT_NE(msg.find("orthonormal"), std::string::npos) << msg;
}

// ------------------------------------------------------------------------------------------ 7-Scenes

TEST(DatasetSevenScenes, ReadsFramesPosesAndInvalidMarkers) {
    auto dir = makeSevenScenes(test::makeTempDir("7s") / "chess" / "seq-01", 5,
                               [](int i) { return i == 2 ? std::string() : matrixText(redwoodPose(i)); });
    auto ds = Dataset::open(dir);
    EXPECT_EQ(ds->kind(), DatasetKind::SevenScenes);
    EXPECT_EQ(toString(ds->kind()), "7-Scenes");
    ASSERT_EQ(ds->size(), 4u);
    EXPECT_TRUE(anyContains(ds->warnings(), "frame-000002")) << joinLines(ds->warnings());
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 585.0f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cx, 320.0f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cy, 240.0f);
    expectPoseNear(ds->frame(2).cameraToWorld, redwoodPose(3), 1e-8);
    EXPECT_DOUBLE_EQ(ds->frame(2).timestamp, 3.0);
    DepthImage d = ds->loadDepth(0);
    for (int y = 0; y < H; ++y) {
        EXPECT_EQ(d.at(0, y), 0.0f);  // 65535 = invalid
        EXPECT_EQ(d.at(1, y), 0.0f);
        EXPECT_FLOAT_EQ(d.at(5, y), 1.5f);
    }
    DatasetOptions o;
    o.maxDepth = 2.0f;
    auto cut = Dataset::open(dir, o);
    EXPECT_FLOAT_EQ(cut->loadDepth(0).at(5, 0), 1.5f);
    EXPECT_EQ(cut->loadDepth(1).at(5, 0), 0.0f);  // 2.5 m > 2 m
}

TEST(DatasetSevenScenes, CameraIntrinsicsFileAndSceneFolder) {
    auto scene = test::makeTempDir("7sk") / "heads";
    auto seq = makeSevenScenes(scene / "seq-02", 3, [](int i) { return matrixText(redwoodPose(i)); });
    writeText(scene / "camera-intrinsics.txt", "532.5 0 320.5\n0 531.0 240.5\n0 0 1\n");
    auto ds = Dataset::open(seq);
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 532.5f);
    EXPECT_FLOAT_EQ(ds->intrinsics().fy, 531.0f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cx, 320.5f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cy, 240.5f);
    // camera.json beats the layout's file; options beat camera.json.
    writeText(seq / "camera.json", R"({"fy": 500})");
    EXPECT_FLOAT_EQ(Dataset::open(seq)->intrinsics().fy, 500.0f);
    EXPECT_FLOAT_EQ(Dataset::open(seq)->intrinsics().fx, 532.5f);

    // The scene folder itself holds sequences, not frames: the error says which to pass.
    std::string msg = errorMessageOf([&] { Dataset::open(scene); });
    EXPECT_NE(msg.find("seq-02"), std::string::npos) << msg;

    writeText(scene / "camera-intrinsics.txt", "532.5 0 320.5\n0 531.0 240.5\n");
    msg = errorMessageOf([&] { Dataset::open(seq); });
    EXPECT_NE(msg.find("camera-intrinsics.txt"), std::string::npos) << msg;
}

TEST(DatasetSevenScenes, BadPosesNameTheFile) {
    auto base = test::makeTempDir("7sbad");
    struct Case { std::string name, text, needle; };
    Pose mirror = Pose::Identity();
    mirror(2, 2) = -1;
    Pose bottom = Pose::Identity();
    bottom(3, 0) = 0.5;
    std::vector<Case> cases{
        {"nan", "nan 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "non-finite"},
        {"skew", "1 0.1 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "orthonormal"},
        {"mirror", matrixText(mirror), "determinant"},
        {"bottom", matrixText(bottom), "bottom row"},
        {"short", "1 0 0 0\n0 1 0 0\n0 0 1 0\n", "16"},
        {"word", "1 0 0 0\n0 1 x 0\n0 0 1 0\n0 0 0 1\n", ":2"},
    };
    for (const Case& c : cases) {
        auto dir = makeSevenScenes(base / c.name, 2,
                                   [&](int i) { return i == 1 ? c.text : matrixText(Pose::Identity()); });
        std::string msg = errorMessageOf([&] { Dataset::open(dir); });
        EXPECT_NE(msg.find("frame-000001.pose.txt"), std::string::npos) << c.name << ": " << msg;
        EXPECT_NE(msg.find(c.needle), std::string::npos) << c.name << ": " << msg;
    }
}

// ------------------------------------------------------------------------------------------ real data

namespace {
// Percentile of the valid (non-zero) samples of a depth image.
std::pair<float, float> validPercentiles(const DepthImage& d, double lo, double hi, size_t& valid) {
    std::vector<float> v;
    for (float m : d.meters)
        if (m > 0) v.push_back(m);
    valid = v.size();
    if (v.empty()) return {0, 0};
    std::sort(v.begin(), v.end());
    return {v[size_t(lo * (v.size() - 1))], v[size_t(hi * (v.size() - 1))]};
}
}  // namespace

TEST(DatasetReal, TumFr1Rpy) {
    auto dir = realDataset("tum_fr1_rpy");
    if (!dir) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    auto ds = Dataset::open(*dir);
    EXPECT_EQ(ds->kind(), DatasetKind::TUM);
    // 361 depth frames; 1305031244.881801 falls in a motion-capture gap (README).
    EXPECT_EQ(ds->size(), 360u);
    EXPECT_EQ(ds->skippedFrames(), 1u);
    EXPECT_TRUE(anyContains(ds->warnings(), "depth.txt:235: depth frame 1305031244.881801")) << joinLines(ds->warnings());
    const Intrinsics& k = ds->intrinsics();
    EXPECT_FLOAT_EQ(k.fx, 517.3f);
    EXPECT_FLOAT_EQ(k.fy, 516.5f);
    EXPECT_FLOAT_EQ(k.cx, 318.6f);
    EXPECT_FLOAT_EQ(k.cy, 255.3f);
    EXPECT_EQ(k.width, 640);
    EXPECT_EQ(k.height, 480);
    for (size_t i = 0; i < ds->size(); ++i) EXPECT_NO_THROW(validatePose(ds->frame(i).cameraToWorld, "frame"));

    // The derived pairing file (nearest groundtruth line within 20 ms, values copied) must agree with
    // our association, pose for pose.
    std::ifstream assoc(*dir / "depth_groundtruth_assoc.txt");
    std::map<double, Pose> expected;
    for (std::string line; std::getline(assoc, line);) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream is(line);
        double t, gtT, tx, ty, tz, qx, qy, qz, qw;
        std::string file;
        is >> t >> file >> gtT >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
        Pose T = Pose::Identity();
        T.topLeftCorner<3, 3>() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
        T.topRightCorner<3, 1>() << tx, ty, tz;
        expected[t] = T;
    }
    ASSERT_EQ(expected.size(), ds->size());
    for (size_t i = 0; i < ds->size(); ++i) {
        auto it = expected.find(ds->frame(i).timestamp);
        ASSERT_NE(it, expected.end()) << std::setprecision(17) << ds->frame(i).timestamp;
        expectPoseNear(ds->frame(i).cameraToWorld, it->second, 1e-12);
    }

    for (size_t i : {size_t(0), ds->size() / 2, ds->size() - 1}) {
        DepthImage d = ds->loadDepth(i);
        ASSERT_EQ(d.width, 640);
        size_t valid = 0;
        auto [p1, p99] = validPercentiles(d, 0.01, 0.99, valid);
        // README: 20-30 % holes, valid range 0.57-9.8 m over the sequence.
        EXPECT_GT(valid, d.meters.size() / 2) << i;
        EXPECT_GE(p1, 0.3f) << i;
        EXPECT_LE(p99, 6.0f) << i;
    }
}

TEST(DatasetReal, IclNuimOfficeTraj0) {
    auto dir = realDataset("iclnuim_office_traj0");
    if (!dir) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    auto ds = Dataset::open(*dir);
    EXPECT_EQ(ds->kind(), DatasetKind::ICLNUIM);
    EXPECT_EQ(ds->size(), 252u);
    EXPECT_EQ(ds->skippedFrames(), 0u);
    const Intrinsics& k = ds->intrinsics();
    EXPECT_FLOAT_EQ(k.fx, 481.2f);
    EXPECT_FLOAT_EQ(k.fy, -480.0f);
    EXPECT_FLOAT_EQ(k.cx, 319.5f);
    EXPECT_FLOAT_EQ(k.cy, 239.5f);
    EXPECT_EQ(k.width, 640);
    EXPECT_EQ(k.height, 480);
    for (size_t i = 0; i < ds->size(); ++i) {
        EXPECT_NO_THROW(validatePose(ds->frame(i).cameraToWorld, "frame"));
        // depth/<i>.png carries pose i
        EXPECT_EQ(ds->frame(i).depthPath.stem().string(), std::to_string(int(ds->frame(i).timestamp)));
    }
    EXPECT_DOUBLE_EQ(ds->frame(0).timestamp, 2.0);
    EXPECT_NEAR(ds->frame(0).cameraToWorld(2, 3), -2.5, 1e-12);  // first groundtruth line: "2 0.000472546 0.00897074 -2.5 ..."
    EXPECT_NEAR(ds->frame(0).cameraToWorld(0, 3), 0.000472546, 1e-12);

    for (size_t i : {size_t(0), ds->size() / 2, ds->size() - 1}) {
        DepthImage d = ds->loadDepth(i);
        size_t valid = 0;
        auto [p1, p99] = validPercentiles(d, 0.01, 0.99, valid);
        EXPECT_EQ(valid, d.meters.size()) << i;  // synthetic: no holes
        EXPECT_GE(p1, 0.3f) << i;
        EXPECT_LE(p99, 6.0f) << i;
    }
}
