// Dataset input: layout detection, association, poses, depth scaling, calibration precedence and the
// error messages for bad input, on tiny fixtures written here and on the shared real sequences.
#include "io/dataset.h"
#include "test_support.h"

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

namespace {

constexpr int W = 8, H = 6;

void writeText(const fs::path& file, const std::string& text) {
    fs::create_directories(file.parent_path());
    std::ofstream(file) << text;
}

void writeDepth(const fs::path& file, const std::function<uint16_t(int, int)>& value, int w = W, int h = H) {
    fs::create_directories(file.parent_path());
    cv::Mat m(h, w, CV_16UC1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) m.at<uint16_t>(y, x) = value(x, y);
    ASSERT_TRUE(cv::imwrite(file.string(), m)) << file;
}

// A raw depth ramp that differs per frame, so a test can tell frames apart.
uint16_t ramp(int frame, int x, int y) { return static_cast<uint16_t>(1000 + 100 * frame + 10 * x + y); }

using test::errorMessageOf;

bool anyContains(const std::vector<std::string>& lines, const std::string& needle) {
    return std::any_of(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(needle) != std::string::npos; });
}

std::string joinLines(const std::vector<std::string>& lines) {
    std::string s;
    for (const auto& l : lines) s += l + "\n";
    return s;
}

// The pose the TUM fixture's groundtruth holds at time t: a rotation growing with t about a fixed
// oblique axis, and a translation that also grows with t.
Pose tumPoseAt(double t) {
    double s = t - 100.0;
    Pose T = Pose::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(2.0 * s, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(s, 2 * s, 0.5);
    return T;
}

std::string gtLine(double t, const Pose& T) {
    Eigen::Quaterniond q(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
    std::ostringstream os;
    os << std::fixed << std::setprecision(4) << t << std::setprecision(9) << " " << T(0, 3) << " " << T(1, 3) << " "
       << T(2, 3) << " " << q.x() << " " << q.y() << " " << q.z() << " " << q.w() << "\n";
    return os.str();
}

// TUM fixture: six depth frames 4 ms after a 100 Hz groundtruth tick, except frame 3 (t = 100.30),
// whose groundtruth ticks within 30 ms were removed: it must be skipped.
struct TumFixture {
    fs::path dir;
    std::vector<double> depthTimes{100.004, 100.104, 100.204, 100.300, 100.404, 100.504};
};

TumFixture makeTum(const std::string& name = "rgbd_dataset_freiburg1_xyz") {
    TumFixture f;
    f.dir = test::makeTempDir("tum") / name;
    std::string depthTxt = "# depth maps\n# timestamp filename\n";
    for (size_t i = 0; i < f.depthTimes.size(); ++i) {
        std::ostringstream name;
        name << std::fixed << std::setprecision(6) << f.depthTimes[i];
        depthTxt += name.str() + " depth/" + name.str() + ".png\n";
        writeDepth(f.dir / "depth" / (name.str() + ".png"), [&](int x, int y) { return ramp(int(i), x, y); });
    }
    writeText(f.dir / "depth.txt", depthTxt);
    std::string gt = "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
    for (int k = -5; k <= 60; ++k) {
        double t = 100.0 + k * 0.01;
        if (std::abs(t - 100.30) < 0.025) continue;  // the gap: nearest remaining ticks are 30 ms away
        gt += gtLine(t, tumPoseAt(t));
    }
    writeText(f.dir / "groundtruth.txt", gt);
    return f;
}

void expectPoseNear(const Pose& a, const Pose& b, double tol) {
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), tol) << "got\n" << a << "\nexpected\n" << b;
}

}  // namespace

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

namespace {
fs::path makeIcl(const std::string& name, const std::vector<int>& depthIds, const std::vector<int>& poseIds) {
    auto dir = test::makeTempDir("icl") / name;
    std::string depthTxt, gt;
    for (int i : depthIds) {
        depthTxt += std::to_string(i) + " depth/" + std::to_string(i) + ".png\n";
        writeDepth(dir / "depth" / (std::to_string(i) + ".png"), [&](int x, int y) { return ramp(i, x, y); });
    }
    for (int i : poseIds) gt += std::to_string(i) + " " + std::to_string(i) + " 0 -2.5 0 0 0 1\n";
    writeText(dir / "depth.txt", depthTxt);
    writeText(dir / "groundtruth.txt", gt);
    return dir;
}
}  // namespace

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

namespace {
Pose redwoodPose(int i) {
    Pose T = Pose::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(0.1 * i, -0.2, 1.5);
    return T;
}

std::string logBlock(int id, const Pose& T) {
    std::ostringstream os;
    os << id << " " << id << " " << id + 1 << "\n" << std::setprecision(17);
    for (int r = 0; r < 4; ++r) os << T(r, 0) << " " << T(r, 1) << " " << T(r, 2) << " " << T(r, 3) << "\n";
    return os.str();
}

fs::path makeRedwood(const std::vector<int>& poseIds, int images = 5) {
    auto dir = test::makeTempDir("redwood") / "livingroom1";
    for (int i = 0; i < images; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", i);
        writeDepth(dir / "depth" / name, [&](int x, int y) { return ramp(i, x, y); });
    }
    std::string log;
    for (int i : poseIds) log += logBlock(i, redwoodPose(i));
    writeText(dir / "livingroom1-traj.log", log);
    return dir;
}
}  // namespace

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

namespace {
fs::path makeSevenScenes(fs::path dir, int frames, const std::function<std::string(int)>& poseText) {
    for (int i = 0; i < frames; ++i) {
        char stem[32];
        std::snprintf(stem, sizeof stem, "frame-%06d", i);
        // Column x = 0 holds the "no reading" marker 65535, x = 1 holds 0, the rest i+1.5 m (mm).
        writeDepth(dir / (std::string(stem) + ".depth.png"), [&](int x, int) -> uint16_t {
            return x == 0 ? 65535 : x == 1 ? 0 : static_cast<uint16_t>(1500 + 1000 * i);
        });
        std::string pose = poseText(i);
        if (!pose.empty()) writeText(dir / (std::string(stem) + ".pose.txt"), pose);
    }
    return dir;
}

std::string matrixText(const Pose& T) {
    std::ostringstream os;
    os << std::setprecision(9) << std::scientific;
    for (int r = 0; r < 4; ++r) os << T(r, 0) << "\t" << T(r, 1) << "\t" << T(r, 2) << "\t" << T(r, 3) << "\t\n";
    return os.str();
}
}  // namespace

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

// ------------------------------------------------------------------------------------------ bad input

TEST(DatasetErrors, MissingFolderAndUnknownLayout) {
    auto base = test::makeTempDir("err");
    std::string msg = errorMessageOf([&] { Dataset::open(base / "nope"); });
    EXPECT_NE(msg.find((base / "nope").string()), std::string::npos) << msg;

    writeText(base / "file.txt", "x");
    msg = errorMessageOf([&] { Dataset::open(base / "file.txt"); });
    EXPECT_NE(msg.find("file.txt"), std::string::npos) << msg;

    fs::create_directories(base / "empty");
    writeText(base / "empty" / "groundtruth.txt", "1 0 0 0 0 0 0 1\n");
    msg = errorMessageOf([&] { Dataset::open(base / "empty"); });
    for (const char* looked : {"empty", "depth.txt", "groundtruth.txt", ".log", "frame-NNNNNN.depth.png"})
        EXPECT_NE(msg.find(looked), std::string::npos) << looked << ": " << msg;
}

TEST(DatasetErrors, DepthTxtWithoutGroundtruth) {
    TumFixture f = makeTum();
    fs::remove(f.dir / "groundtruth.txt");
    std::string msg = errorMessageOf([&] { Dataset::open(f.dir); });
    EXPECT_NE(msg.find("groundtruth.txt"), std::string::npos) << msg;
}

TEST(DatasetErrors, MalformedIndexLinesNameFileAndLine) {
    struct Case { std::string file, text, needle; };
    std::vector<Case> cases{
        {"depth.txt", "", "depth.txt"},  // no frames at all
        {"depth.txt", "# c\n100.004000 depth/100.004000.png\n100.104000\n", "depth.txt:3"},
        {"depth.txt", "100.004000 depth/100.004000.png\nabc depth/x.png\n", "depth.txt:2"},
        {"depth.txt", "inf depth/100.004000.png\n", "depth.txt:1"},
        {"groundtruth.txt", "", "groundtruth.txt"},
        {"groundtruth.txt", "100.0 0 0 0 0 0 0 1\n100.1 0 0 0 0 0 1\n", "groundtruth.txt:2"},
        {"groundtruth.txt", "100.0 0 0 0 0 0 0 1\n\n100.1 0 nan 0 0 0 0 1\n", "groundtruth.txt:3"},
        {"groundtruth.txt", "100.0 0 0 0 0 0 0 1\n100.1 0 0 0 0 0 0 0.1\n", "groundtruth.txt:2"},  // |q| = 0.1
        {"groundtruth.txt", "100.0 0 0 0 0 0 0 1\n100.1 0 0 0 2 2 0 1\n", "groundtruth.txt:2"},  // |q| = 3
        {"groundtruth.txt", "100.0 0 0 0 0 0 0 1x\n", "1x"},
    };
    for (const Case& c : cases) {
        TumFixture f = makeTum();
        writeText(f.dir / c.file, c.text);
        std::string msg = errorMessageOf([&] { Dataset::open(f.dir); });
        EXPECT_NE(msg.find(c.needle), std::string::npos) << c.file << " '" << c.text << "': " << msg;
    }
    // A quaternion rounded in print (norm 0.9) is accepted and normalised; norm 0.3 is a corrupt line.
    TumFixture f = makeTum();
    writeText(f.dir / "groundtruth.txt", "100.0 0 0 0 0 0 0 0.9\n100.1 0 0 0 0 0 0 0.9\n");
    auto ds = Dataset::open(f.dir);
    expectPoseNear(ds->frame(0).cameraToWorld, Pose::Identity(), 1e-12);
    writeText(f.dir / "groundtruth.txt", "100.0 0 0 0 0 0 0 1\n100.1 0 0 0 0 0 0 0.3\n");
    std::string msg = errorMessageOf([&] { Dataset::open(f.dir); });
    EXPECT_NE(msg.find("groundtruth.txt:2"), std::string::npos) << msg;
    EXPECT_NE(msg.find("norm"), std::string::npos) << msg;
}

TEST(DatasetErrors, BadImagesNameTheFile) {
    // Frame 0 corrupt: reported at open time.
    {
        TumFixture f = makeTum();
        writeText(f.dir / "depth/100.004000.png", "not a png at all");
        std::string msg = errorMessageOf([&] { Dataset::open(f.dir); });
        EXPECT_NE(msg.find("100.004000.png"), std::string::npos) << msg;
    }
    TumFixture f = makeTum();
    auto ds = Dataset::open(f.dir);
    // Truncated PNG (header intact, data cut).
    {
        fs::path p = f.dir / "depth/100.104000.png";
        auto size = fs::file_size(p);
        fs::resize_file(p, size / 2);
        std::string msg = errorMessageOf([&] { ds->loadDepth(1); });
        EXPECT_NE(msg.find("100.104000.png"), std::string::npos) << msg;
    }
    // 8-bit grayscale.
    {
        cv::Mat m(H, W, CV_8UC1, cv::Scalar(7));
        cv::imwrite((f.dir / "depth/100.204000.png").string(), m);
        std::string msg = errorMessageOf([&] { ds->loadDepth(2); });
        EXPECT_NE(msg.find("100.204000.png"), std::string::npos) << msg;
        EXPECT_NE(msg.find("8-bit"), std::string::npos) << msg;
    }
    // 16-bit but three channels.
    {
        cv::Mat m(H, W, CV_16UC3, cv::Scalar(7, 7, 7));
        cv::imwrite((f.dir / "depth/100.404000.png").string(), m);
        std::string msg = errorMessageOf([&] { ds->loadDepth(3); });
        EXPECT_NE(msg.find("100.404000.png"), std::string::npos) << msg;
        EXPECT_NE(msg.find("3 channels"), std::string::npos) << msg;
    }
    // Another size than frame 0.
    {
        writeDepth(f.dir / "depth/100.504000.png", [](int, int) { return 1000; }, W + 2, H);
        std::string msg = errorMessageOf([&] { ds->loadDepth(4); });
        EXPECT_NE(msg.find("100.504000.png"), std::string::npos) << msg;
        EXPECT_NE(msg.find("10x6"), std::string::npos) << msg;
    }
    // Deleted after open.
    {
        fs::remove(f.dir / "depth/100.004000.png");
        std::string msg = errorMessageOf([&] { ds->loadDepth(0); });
        EXPECT_NE(msg.find("100.004000.png"), std::string::npos) << msg;
    }
    // Out-of-range frame index.
    std::string msg = errorMessageOf([&] { ds->loadDepth(99); });
    EXPECT_NE(msg.find("99"), std::string::npos) << msg;
    // Listed but missing at open time: reported then, not in the middle of a run.
    msg = errorMessageOf([&] { Dataset::open(f.dir); });
    EXPECT_NE(msg.find("100.004000.png"), std::string::npos) << msg;
}

TEST(DatasetErrors, BadOptionsAndCameraJsonNameTheValue) {
    TumFixture f = makeTum();
    for (double s : {0.0, -5.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
        DatasetOptions o;
        o.depthScale = s;
        std::string msg = errorMessageOf([&] { Dataset::open(f.dir, o); });
        EXPECT_NE(msg.find("depth scale"), std::string::npos) << msg;
    }
    {
        DatasetOptions o;
        o.depthScale = -5.0;
        EXPECT_NE(errorMessageOf([&] { Dataset::open(f.dir, o); }).find("-5"), std::string::npos);
    }
    {
        DatasetOptions o;
        o.maxDepth = -1.5f;
        std::string msg = errorMessageOf([&] { Dataset::open(f.dir, o); });
        EXPECT_NE(msg.find("-1.5"), std::string::npos) << msg;
    }
    {
        DatasetOptions o;
        o.intrinsics = Intrinsics{0.0f, 500.0f, 1, 1, 0, 0};
        std::string msg = errorMessageOf([&] { Dataset::open(f.dir, o); });
        EXPECT_NE(msg.find("fx"), std::string::npos) << msg;
    }
    struct Case { std::string json, needle; };
    for (const Case& c : {Case{"{\"fx\": 500,", "camera.json"}, Case{R"({"fx": "five hundred"})", "fx"},
                          Case{R"({"fy": 0})", "fy"}, Case{R"({"depth_scale": -1})", "depth_scale"},
                          Case{"[1, 2]", "camera.json"}}) {
        writeText(f.dir / "camera.json", c.json);
        std::string msg = errorMessageOf([&] { Dataset::open(f.dir); });
        EXPECT_NE(msg.find(c.needle), std::string::npos) << c.json << ": " << msg;
        EXPECT_NE(msg.find("camera.json"), std::string::npos) << c.json << ": " << msg;
    }
}

TEST(ParseIntrinsics, AcceptsFourNumbersAndNamesTheBadValue) {
    Intrinsics k = parseIntrinsics("481.2, -480, 319.5,239.5");
    EXPECT_FLOAT_EQ(k.fx, 481.2f);
    EXPECT_FLOAT_EQ(k.fy, -480.0f);
    EXPECT_FLOAT_EQ(k.cx, 319.5f);
    EXPECT_FLOAT_EQ(k.cy, 239.5f);
    EXPECT_EQ(k.width, 0);
    EXPECT_NE(errorMessageOf([] { parseIntrinsics("525,525,319.5"); }).find("525,525,319.5"), std::string::npos);
    EXPECT_NE(errorMessageOf([] { parseIntrinsics("525,abc,319.5,239.5"); }).find("abc"), std::string::npos);
    EXPECT_NE(errorMessageOf([] { parseIntrinsics("525,0,319.5,239.5"); }).find("fy"), std::string::npos);
    EXPECT_NE(errorMessageOf([] { parseIntrinsics("nan,525,319.5,239.5"); }).find("nan"), std::string::npos);
    EXPECT_NE(errorMessageOf([] { parseIntrinsics(""); }).find("fx,fy,cx,cy"), std::string::npos);
}

TEST(ValidatePose, AcceptsRigidRejectsTheRest) {
    Pose ok = Pose::Identity();
    ok.topLeftCorner<3, 3>() = Eigen::AngleAxisd(1.0, Eigen::Vector3d(0.3, -1, 2).normalized()).toRotationMatrix();
    ok.topRightCorner<3, 1>() << 1, -2, 3;
    EXPECT_NO_THROW(validatePose(ok, "ok"));
    Pose nearly = ok;
    nearly(0, 0) += 2e-4;  // print rounding
    EXPECT_NO_THROW(validatePose(nearly, "nearly"));

    Pose p = ok;
    p(1, 3) = std::numeric_limits<double>::infinity();
    EXPECT_NE(errorMessageOf([&] { validatePose(p, "traj.txt:7"); }).find("traj.txt:7"), std::string::npos);
    p = ok;
    p.topLeftCorner<3, 3>() *= 1.01;
    EXPECT_NE(errorMessageOf([&] { validatePose(p, "frame 3"); }).find("frame 3"), std::string::npos);
    p = ok;
    p.col(0) *= -1;  // mirror
    std::string msg = errorMessageOf([&] { validatePose(p, "frame 4"); });
    EXPECT_NE(msg.find("determinant"), std::string::npos) << msg;
    p = ok;
    p(3, 2) = 1;
    msg = errorMessageOf([&] { validatePose(p, "frame 5"); });
    EXPECT_NE(msg.find("bottom row"), std::string::npos) << msg;
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

std::optional<fs::path> realDataset(const std::string& name) {
    auto root = test::sharedDatasetsDir();
    if (!root || !fs::is_directory(*root / name)) return std::nullopt;
    return *root / name;
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

// ---------------------------------------------------------------------------------------------------
// Camera presets (data/cameras/<name>/camera.json) and where they are found (io/data_dir.h).

namespace {

// Sets VKMESH_DATA_DIR for one test and restores what was there before.
class DataDirOverride {
public:
    explicit DataDirOverride(const fs::path& dir) {
        if (const char* old = std::getenv("VKMESH_DATA_DIR")) previous_ = old;
        setenv("VKMESH_DATA_DIR", dir.c_str(), 1);
    }
    ~DataDirOverride() {
        if (previous_)
            setenv("VKMESH_DATA_DIR", previous_->c_str(), 1);
        else
            unsetenv("VKMESH_DATA_DIR");
    }

private:
    std::optional<std::string> previous_;
};

}  // namespace

TEST(CameraPresets, HoldTheSensorsCalibration) {
    struct Case { std::string name; Intrinsics k; double depthScale; };
    for (const Case& c : {Case{"tum_fr1", {517.3f, 516.5f, 318.6f, 255.3f}, 5000}, Case{"tum_fr2", {520.9f, 521.0f, 325.1f, 249.7f}, 5000},
                          Case{"tum_fr3", {535.4f, 539.2f, 320.1f, 247.6f}, 5000}, Case{"tum_default", {525, 525, 319.5f, 239.5f}, 5000},
                          Case{"icl_nuim", {481.2f, -480.0f, 319.5f, 239.5f}, 5000}, Case{"redwood", {525, 525, 319.5f, 239.5f}, 1000},
                          Case{"seven_scenes", {585, 585, 320, 240}, 1000}}) {
        const CameraPreset p = loadCameraPreset(c.name);
        EXPECT_EQ(p.file.parent_path().filename(), c.name);
        EXPECT_FLOAT_EQ(p.intrinsics.fx, c.k.fx) << c.name;
        EXPECT_FLOAT_EQ(p.intrinsics.fy, c.k.fy) << c.name;
        EXPECT_FLOAT_EQ(p.intrinsics.cx, c.k.cx) << c.name;
        EXPECT_FLOAT_EQ(p.intrinsics.cy, c.k.cy) << c.name;
        EXPECT_DOUBLE_EQ(p.depthScale, c.depthScale) << c.name;
    }
    EXPECT_NE(errorMessageOf([] { loadCameraPreset("no_such_sensor"); }).find("cameras/no_such_sensor/camera.json"),
              std::string::npos);
}

TEST(CameraPresets, TheDataDirVariableWins) {
    const fs::path data = test::makeTempDir("data_dir");
    writeText(data / "cameras" / "tum_fr1" / "camera.json",
              R"({"fx": 111, "fy": 112, "cx": 4, "cy": 3, "depth_scale": 1000})");
    TumFixture f = makeTum("tum_fr1_rpy");
    DataDirOverride override(data);
    auto ds = Dataset::open(f.dir);
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 111.0f);
    EXPECT_FLOAT_EQ(ds->intrinsics().cy, 3.0f);
    EXPECT_DOUBLE_EQ(ds->depthScale(), 1000.0);
    // A folder's camera.json still overrides the preset.
    writeText(f.dir / "camera.json", R"({"fx": 600.5})");
    EXPECT_FLOAT_EQ(Dataset::open(f.dir)->intrinsics().fx, 600.5f);
    EXPECT_FLOAT_EQ(Dataset::open(f.dir)->intrinsics().fy, 112.0f);
}

TEST(CameraPresets, AMissingOrBrokenPresetIsAClearError) {
    const fs::path data = test::makeTempDir("data_dir_bad");
    TumFixture f = makeTum("tum_fr2_desk");
    DataDirOverride override(data);
    std::string message = errorMessageOf([&] { Dataset::open(f.dir); });
    EXPECT_NE(message.find((data / "cameras" / "tum_fr2" / "camera.json").string()), std::string::npos) << message;
    EXPECT_NE(message.find("VKMESH_DATA_DIR"), std::string::npos) << message;
    // Incomplete: a preset must state every value.
    writeText(data / "cameras" / "tum_fr2" / "camera.json", R"({"fx": 520.9, "fy": 521.0, "cx": 325.1, "cy": 249.7})");
    message = errorMessageOf([&] { Dataset::open(f.dir); });
    EXPECT_NE(message.find("missing depth_scale"), std::string::npos) << message;
    // A typo is not silently ignored.
    writeText(data / "cameras" / "tum_fr2" / "camera.json",
              R"({"fx": 520.9, "fy": 521.0, "cx": 325.1, "cy": 249.7, "depth_scale": 5000, "depth_sclae": 1})");
    message = errorMessageOf([&] { Dataset::open(f.dir); });
    EXPECT_NE(message.find("depth_sclae"), std::string::npos) << message;
}

TEST(CameraPresets, AFullyCalibratedFolderNeedsNoPreset) {
    const fs::path empty = test::makeTempDir("data_dir_empty");
    TumFixture f = makeTum("tum_fr3_office");
    writeText(f.dir / "camera.json", R"({"fx": 500, "fy": 501, "cx": 4, "cy": 3, "depth_scale": 5000})");
    DataDirOverride override(empty);
    auto ds = Dataset::open(f.dir);
    EXPECT_FLOAT_EQ(ds->intrinsics().fy, 501.0f);
    // Without depth_scale the preset is needed again, and missing.
    writeText(f.dir / "camera.json", R"({"fx": 500, "fy": 501, "cx": 4, "cy": 3})");
    EXPECT_NE(errorMessageOf([&] { Dataset::open(f.dir); }).find("cameras/tum_fr3/camera.json"), std::string::npos);
}

// ------------------------------------------------------------------------------------------ colour

namespace {

// A colour image whose pixel (x, y) is rgb(x, y), written as OpenCV writes it (BGR in memory); .png or .jpg.
void writeColor(const fs::path& file, const std::function<std::array<uint8_t, 3>(int, int)>& rgb, int w = W, int h = H) {
    fs::create_directories(file.parent_path());
    cv::Mat m(h, w, CV_8UC3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const auto c = rgb(x, y);
            m.at<cv::Vec3b>(y, x) = cv::Vec3b(c[2], c[1], c[0]);
        }
    ASSERT_TRUE(cv::imwrite(file.string(), m)) << file;
}

// Distinct in every channel, and per frame: red follows x, green y, blue the frame.
std::array<uint8_t, 3> colorRamp(int frame, int x, int y) {
    return {uint8_t(10 * x + 1), uint8_t(20 * y + 2), uint8_t(200 + frame)};
}

void expectColorRamp(const ColorImage& c, int frame) {
    ASSERT_EQ(c.width, W);
    ASSERT_EQ(c.height, H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const auto e = colorRamp(frame, x, y);
            ASSERT_EQ(c.at(x, y)[0], e[0]) << x << "," << y;
            ASSERT_EQ(c.at(x, y)[1], e[1]) << x << "," << y;
            ASSERT_EQ(c.at(x, y)[2], e[2]) << x << "," << y;
        }
}

size_t countContaining(const std::vector<std::string>& lines, const std::string& needle) {
    return size_t(std::count_if(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(needle) != std::string::npos; }));
}

}  // namespace

TEST(DatasetColor, TumTakesTheNearestRgbWithin20ms) {
    TumFixture f = makeTum();
    // Colour 10 ms after each depth frame, except frame 5's, 30 ms after: too far. Listed unsorted.
    std::string rgbTxt = "# color images\n";
    for (size_t i = f.depthTimes.size(); i-- > 0;) {
        std::ostringstream name;
        name << std::fixed << std::setprecision(6) << f.depthTimes[i] + (i == 5 ? 0.030 : 0.010);
        rgbTxt += name.str() + " rgb/" + name.str() + ".png\n";
        writeColor(f.dir / "rgb" / (name.str() + ".png"), [&](int x, int y) { return colorRamp(int(i), x, y); });
    }
    writeText(f.dir / "rgb.txt", rgbTxt);
    auto ds = Dataset::open(f.dir);
    ASSERT_EQ(ds->size(), 5u);  // frame 3 has no pose
    EXPECT_TRUE(ds->hasColor());
    EXPECT_FALSE(anyContains(ds->warnings(), "no colour images")) << joinLines(ds->warnings());
    const int listed[5] = {0, 1, 2, 4, 5};
    for (size_t i = 0; i < 4; ++i) {
        SCOPED_TRACE(i);
        EXPECT_NE(ds->frame(i).colorPath.string().find("rgb/"), std::string::npos);
        std::string warning;
        expectColorRamp(ds->loadColor(i, &warning), listed[i]);
        EXPECT_TRUE(warning.empty()) << warning;
    }
    EXPECT_TRUE(ds->frame(4).colorPath.empty());
    EXPECT_TRUE(anyContains(ds->warnings(), "no colour image within 20 ms of depth frame 100.504")) << joinLines(ds->warnings());
    EXPECT_TRUE(anyContains(ds->warnings(), "30.0 ms")) << joinLines(ds->warnings());
    std::string warning;
    EXPECT_TRUE(ds->loadColor(4, &warning).empty());
    EXPECT_NE(warning.find("100.504000.png"), std::string::npos) << warning;
    EXPECT_THROW(ds->loadColor(5), Error);
}

TEST(DatasetColor, NoColourAtAllIsDepthOnlySaidOnce) {
    TumFixture f = makeTum();
    auto ds = Dataset::open(f.dir);
    EXPECT_FALSE(ds->hasColor());
    EXPECT_EQ(countContaining(ds->warnings(), "no colour images: depth only"), 1u) << joinLines(ds->warnings());
    std::string warning = "untouched";
    EXPECT_TRUE(ds->loadColor(0, &warning).empty());
    EXPECT_EQ(warning, "untouched");  // nothing to say per frame: open() said it once
    EXPECT_TRUE(ds->frame(0).colorPath.empty());
}

TEST(DatasetColor, IclRedwoodAndSevenScenesFindTheirColour) {
    {  // ICL-NUIM: rgb.txt with the same frame indices; frame 2's colour is listed but missing.
        auto dir = makeIcl("ICL_living_room", {0, 1, 2}, {0, 1, 2});
        writeText(dir / "rgb.txt", "0 rgb/0.png\n1 rgb/1.png\n2 rgb/2.png\n");
        for (int i : {0, 1}) writeColor(dir / "rgb" / (std::to_string(i) + ".png"), [&](int x, int y) { return colorRamp(i, x, y); });
        auto ds = Dataset::open(dir);
        EXPECT_TRUE(ds->hasColor());
        expectColorRamp(ds->loadColor(1), 1);
        EXPECT_TRUE(ds->frame(2).colorPath.empty());
        EXPECT_TRUE(anyContains(ds->warnings(), "2.png (frame 2) does not exist")) << joinLines(ds->warnings());
    }
    {  // Redwood: color/ beside depth/, paired by name order (frame 1 has no pose: colour 2 goes with depth 2).
        auto dir = makeRedwood({0, 2, 3, 4});
        for (int i = 0; i < 5; ++i) {
            char name[32];
            std::snprintf(name, sizeof name, "%06d.png", i);
            writeColor(dir / "color" / name, [&](int x, int y) { return colorRamp(i, x, y); });
        }
        auto ds = Dataset::open(dir);
        ASSERT_EQ(ds->size(), 4u);
        EXPECT_TRUE(ds->hasColor());
        expectColorRamp(ds->loadColor(1), 2);
        expectColorRamp(ds->loadColor(3), 4);
    }
    {  // 7-Scenes: frame-NNNNNN.color.png beside the depth; frame 1 has none.
        const std::string identity = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
        auto dir = makeSevenScenes(test::makeTempDir("seven_color") / "seq-01", 3, [&](int) { return identity; });
        for (int i : {0, 2}) {
            char name[40];
            std::snprintf(name, sizeof name, "frame-%06d.color.png", i);
            writeColor(dir / name, [&](int x, int y) { return colorRamp(i, x, y); });
        }
        auto ds = Dataset::open(dir);
        EXPECT_TRUE(ds->hasColor());
        expectColorRamp(ds->loadColor(2), 2);
        EXPECT_TRUE(anyContains(ds->warnings(), "1 of 3 frames have no frame-NNNNNN.color.png")) << joinLines(ds->warnings());
        std::string warning;
        EXPECT_TRUE(ds->loadColor(1, &warning).empty());
        EXPECT_NE(warning.find("frame-000001.depth.png"), std::string::npos) << warning;
    }
}

TEST(DatasetColor, JpegGrayscaleAndBadImagesPerFrame) {
    TumFixture f = makeTum();
    std::string rgbTxt;
    for (size_t i = 0; i < f.depthTimes.size(); ++i) {
        std::ostringstream t;
        t << std::fixed << std::setprecision(6) << f.depthTimes[i];
        rgbTxt += t.str() + " rgb/" + std::to_string(i) + (i == 0 ? ".jpg" : ".png") + "\n";
    }
    writeText(f.dir / "rgb.txt", rgbTxt);
    // 0: a JPEG (lossy: a flat colour survives within a few levels).
    writeColor(f.dir / "rgb" / "0.jpg", [](int, int) { return std::array<uint8_t, 3>{200, 100, 30}; });
    // 1: 8-bit grayscale becomes grey RGB.
    test::writePng(f.dir / "rgb" / "1.png", W, H, CV_8UC1, 77);
    // 2: the wrong size; 4: a 16-bit image (a depth image by mistake); 5: not an image.
    writeColor(f.dir / "rgb" / "2.png", [](int, int) { return std::array<uint8_t, 3>{1, 2, 3}; }, W * 2, H * 2);
    test::writePng(f.dir / "rgb" / "4.png", W, H, CV_16UC1, 1000);
    test::writeBytes(f.dir / "rgb" / "5.png", "not an image at all");
    auto ds = Dataset::open(f.dir);
    ASSERT_EQ(ds->size(), 5u);
    EXPECT_TRUE(ds->hasColor());

    std::string warning;
    ColorImage c = ds->loadColor(0, &warning);
    ASSERT_FALSE(c.empty()) << warning;
    EXPECT_NEAR(c.at(3, 3)[0], 200, 4);
    EXPECT_NEAR(c.at(3, 3)[1], 100, 4);
    EXPECT_NEAR(c.at(3, 3)[2], 30, 4);
    c = ds->loadColor(1, &warning);
    ASSERT_FALSE(c.empty()) << warning;
    EXPECT_EQ(c.at(5, 2)[0], 77);
    EXPECT_EQ(c.at(5, 2)[2], 77);

    const struct {
        size_t frame;
        std::vector<std::string> needles;
    } bad[] = {{2, {"2.png", "16x12", "8x6"}}, {3, {"4.png", "16-bit", "depth image?"}}, {4, {"5.png", "neither a PNG nor a JPEG"}}};
    for (const auto& b : bad) {
        warning.clear();
        EXPECT_TRUE(ds->loadColor(b.frame, &warning).empty());
        for (const auto& n : b.needles) EXPECT_NE(warning.find(n), std::string::npos) << warning << " lacks " << n;
        EXPECT_NE(warning.find("has no colour"), std::string::npos) << warning;
    }
}

TEST(DatasetColor, ColourIntrinsicsResampleOntoTheDepthGrid) {
    TumFixture f = makeTum("rgbd_dataset_freiburg1_color_camera");
    // Depth camera fx = fy = 4, centre (3.5, 2.5) on 8x6; colour camera twice the resolution: depth pixel
    // (u, v) lies at (2u + 0.5, 2v + 0.5) in the colour image, halfway between two colour pixels.
    writeText(f.dir / "camera.json",
              R"({"fx": 4, "fy": 4, "cx": 3.5, "cy": 2.5, "color_fx": 8, "color_fy": 8, "color_cx": 7.5, "color_cy": 5.5,
                  "color_width": 16, "color_height": 12})");
    std::string rgbTxt;
    for (size_t i = 0; i < f.depthTimes.size(); ++i) {
        std::ostringstream t;
        t << std::fixed << std::setprecision(6) << f.depthTimes[i];
        rgbTxt += t.str() + " rgb/" + std::to_string(i) + ".png\n";
        writeColor(f.dir / "rgb" / (std::to_string(i) + ".png"),
                   [](int x, int y) { return std::array<uint8_t, 3>{uint8_t(10 * x), uint8_t(10 * y), 77}; }, 16, 12);
    }
    writeText(f.dir / "rgb.txt", rgbTxt);
    auto ds = Dataset::open(f.dir);
    std::string warning;
    const ColorImage c = ds->loadColor(0, &warning);
    ASSERT_EQ(c.width, W) << warning;
    ASSERT_EQ(c.height, H);
    for (int v = 0; v < H; ++v)
        for (int u = 0; u < W; ++u) {
            // Bilinear between 10 * 2u and 10 * (2u + 1).
            EXPECT_NEAR(c.at(u, v)[0], 20 * u + 5, 1) << u << "," << v;
            EXPECT_NEAR(c.at(u, v)[1], 20 * v + 5, 1) << u << "," << v;
            EXPECT_EQ(c.at(u, v)[2], 77);
        }
    // Without color_width/height the size comes from the first colour image; a colour image of another
    // size than the calibration's is a per-frame warning.
    writeText(f.dir / "camera.json", R"({"fx": 4, "fy": 4, "cx": 3.5, "cy": 2.5, "color_fx": 8, "color_fy": 8, "color_cx": 7.5, "color_cy": 5.5})");
    writeColor(f.dir / "rgb" / "1.png", [](int, int) { return std::array<uint8_t, 3>{1, 2, 3}; }, 8, 6);
    ds = Dataset::open(f.dir);
    EXPECT_FALSE(ds->loadColor(0).empty());
    EXPECT_TRUE(ds->loadColor(1, &warning).empty());
    EXPECT_NE(warning.find("colour calibration (camera.json) is for 16x12"), std::string::npos) << warning;
    // Half a colour calibration is an error naming the file.
    writeText(f.dir / "camera.json", R"({"fx": 4, "fy": 4, "cx": 3.5, "cy": 2.5, "color_fx": 8})");
    const std::string message = errorMessageOf([&] { Dataset::open(f.dir); });
    EXPECT_NE(message.find("camera.json"), std::string::npos) << message;
    EXPECT_NE(message.find("color_fx, color_fy, color_cx, color_cy"), std::string::npos) << message;
}

TEST(DatasetReal, ColourOfTheSharedSequences) {
    for (const char* name : {"tum_fr1_rpy", "iclnuim_office_traj0"}) {
        auto dir = realDataset(name);
        if (!dir) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
        if (!fs::exists(*dir / "rgb.txt")) GTEST_SKIP() << *dir << " has no rgb.txt";
        SCOPED_TRACE(name);
        auto ds = Dataset::open(*dir);
        EXPECT_TRUE(ds->hasColor());
        EXPECT_FALSE(anyContains(ds->warnings(), "colour")) << joinLines(ds->warnings());
        for (size_t i : {size_t(0), ds->size() - 1}) {
            std::string warning;
            const ColorImage c = ds->loadColor(i, &warning);
            ASSERT_FALSE(c.empty()) << warning;
            EXPECT_EQ(c.width, 640);
            EXPECT_EQ(c.height, 480);
            // A real picture: not one flat colour.
            EXPECT_GT(*std::max_element(c.rgb.begin(), c.rgb.end()) - *std::min_element(c.rgb.begin(), c.rgb.end()), 100);
        }
    }
}

// ------------------------------------------------------------------------------------------ without poses
// Sequences whose poses camera tracking will estimate (DatasetOptions::requirePoses = false).

namespace {

DatasetOptions withoutPoses() {
    DatasetOptions o;
    o.requirePoses = false;
    return o;
}

void expectNoPoses(const Dataset& ds) {
    EXPECT_FALSE(ds.hasPoses());
    for (size_t i = 0; i < ds.size(); ++i) {
        EXPECT_FALSE(ds.frame(i).hasPose) << "frame " << i;
        EXPECT_TRUE(ds.frame(i).cameraToWorld.isIdentity()) << "frame " << i;
        EXPECT_EQ(ds.frame(i).index, i);
    }
}

void expectTimestamps(const Dataset& ds, const std::vector<double>& expected) {
    ASSERT_EQ(ds.size(), expected.size());
    for (size_t i = 0; i < ds.size(); ++i) EXPECT_DOUBLE_EQ(ds.frame(i).timestamp, expected[i]) << "frame " << i;
}

void expectMentionsTracking(const std::string& message, const std::string& file) {
    EXPECT_NE(message.find(file), std::string::npos) << message;
    EXPECT_NE(message.find("vkmesh fuse --track estimates them"), std::string::npos) << message;
}

// A plain folder: camera.json and 16-bit depth PNGs named `names` (in depth/ when `inDepthDir`), frame k
// holding ramp(k) in millimetres.
fs::path makeFolder(const fs::path& dir, const std::vector<std::string>& names, bool inDepthDir = true) {
    writeText(dir / "camera.json", R"({"fx": 500, "fy": 501, "cx": 3.5, "cy": 2.5, "depth_scale": 1000})");
    for (size_t k = 0; k < names.size(); ++k)
        writeDepth((inDepthDir ? dir / "depth" : dir) / names[k], [&](int x, int y) { return ramp(int(k), x, y); });
    return dir;
}

}  // namespace

TEST(DatasetWithoutPoses, TumWithoutGroundtruthKeepsEveryListedFrame) {
    TumFixture f = makeTum();
    fs::remove(f.dir / "groundtruth.txt");
    expectMentionsTracking(errorMessageOf([&] { Dataset::open(f.dir); }), "groundtruth.txt");

    auto ds = Dataset::open(f.dir, withoutPoses());
    EXPECT_EQ(ds->kind(), DatasetKind::TUM);
    EXPECT_EQ(ds->skippedFrames(), 0u);
    expectTimestamps(*ds, f.depthTimes);
    expectNoPoses(*ds);
    EXPECT_FLOAT_EQ(ds->loadDepth(3).at(2, 1), ramp(3, 2, 1) / 5000.0f);

    // maxFrames: the first N listed frames.
    DatasetOptions o = withoutPoses();
    o.maxFrames = 2;
    expectTimestamps(*Dataset::open(f.dir, o), {f.depthTimes[0], f.depthTimes[1]});
}

TEST(DatasetWithoutPoses, TumWithGroundtruthKeepsFramesWithoutAPose) {
    // Frame 3 (t = 100.300) has no groundtruth tick within 20 ms: skipped by default, kept without a pose here.
    TumFixture f = makeTum();
    auto ds = Dataset::open(f.dir, withoutPoses());
    expectTimestamps(*ds, f.depthTimes);
    EXPECT_EQ(ds->skippedFrames(), 0u);
    EXPECT_TRUE(ds->hasPoses());
    for (size_t i = 0; i < ds->size(); ++i) EXPECT_EQ(ds->frame(i).hasPose, i != 3) << "frame " << i;
    EXPECT_TRUE(ds->frame(3).cameraToWorld.isIdentity());
    // The first frame (t = 100.004) gets the pose of the nearest tick, 100.00, as with requirePoses.
    expectPoseNear(ds->frame(0).cameraToWorld, tumPoseAt(100.00), 1e-6);
    EXPECT_EQ(ds->frame(0).cameraToWorld, Dataset::open(f.dir)->frame(0).cameraToWorld);
    EXPECT_TRUE(anyContains(ds->warnings(), "1 of 6 depth frames have no pose within 20 ms")) << joinLines(ds->warnings());
}

TEST(DatasetWithoutPoses, IclNuimWithoutGroundtruth) {
    auto dir = makeIcl("ICL_office_traj2", {0, 1, 2, 3}, {});  // an empty groundtruth.txt
    expectMentionsTracking(errorMessageOf([&] { Dataset::open(dir); }), "groundtruth.txt");
    expectNoPoses(*Dataset::open(dir, withoutPoses()));

    fs::remove(dir / "groundtruth.txt");
    expectMentionsTracking(errorMessageOf([&] { Dataset::open(dir); }), "groundtruth.txt");
    auto ds = Dataset::open(dir, withoutPoses());
    EXPECT_EQ(ds->kind(), DatasetKind::ICLNUIM);
    EXPECT_FLOAT_EQ(ds->intrinsics().fy, -480.0f);
    expectTimestamps(*ds, {0, 1, 2, 3});
    expectNoPoses(*ds);
}

TEST(DatasetWithoutPoses, RedwoodWithoutItsLog) {
    auto dir = makeRedwood({}, 4);  // an empty .log
    expectMentionsTracking(errorMessageOf([&] { Dataset::open(dir); }), "livingroom1-traj.log");
    expectNoPoses(*Dataset::open(dir, withoutPoses()));

    fs::remove(dir / "livingroom1-traj.log");
    expectMentionsTracking(errorMessageOf([&] { Dataset::open(dir); }), dir.string());
    auto ds = Dataset::open(dir, withoutPoses());
    EXPECT_EQ(ds->kind(), DatasetKind::Redwood);
    EXPECT_DOUBLE_EQ(ds->depthScale(), 1000.0);
    expectTimestamps(*ds, {0, 1, 2, 3});  // the position in name order, as the .log's ids count frames
    expectNoPoses(*ds);
    // Nothing said which camera this is: the default calibration is named as a guess.
    EXPECT_TRUE(anyContains(ds->warnings(), "Redwood's default intrinsics")) << joinLines(ds->warnings());
    EXPECT_FLOAT_EQ(ds->loadDepth(2).at(1, 4), ramp(2, 1, 4) / 1000.0f);

    // A log with a gap: the frame without a pose is kept.
    writeText(dir / "livingroom1-traj.log", logBlock(0, redwoodPose(0)) + logBlock(2, redwoodPose(2)));
    ds = Dataset::open(dir, withoutPoses());
    ASSERT_EQ(ds->size(), 4u);
    EXPECT_TRUE(ds->hasPoses());
    for (size_t i = 0; i < 4; ++i) EXPECT_EQ(ds->frame(i).hasPose, i == 0 || i == 2) << "frame " << i;
    expectPoseNear(ds->frame(2).cameraToWorld, redwoodPose(2), 1e-12);
}

TEST(DatasetWithoutPoses, SevenScenesWithoutPoseFiles) {
    auto dir = makeSevenScenes(test::makeTempDir("7s_nopose") / "chess" / "seq-02", 3, [](int) { return std::string(); });
    // Frame numbers come from the names: renumber them so that they differ from the positions.
    for (int i = 2; i >= 0; --i) {
        char from[40], to[40];
        std::snprintf(from, sizeof from, "frame-%06d.depth.png", i);
        std::snprintf(to, sizeof to, "frame-%06d.depth.png", 10 + 5 * i);
        fs::rename(dir / from, dir / to);
    }
    expectMentionsTracking(errorMessageOf([&] { Dataset::open(dir); }), "frame-*.pose.txt");
    auto ds = Dataset::open(dir, withoutPoses());
    EXPECT_EQ(ds->kind(), DatasetKind::SevenScenes);
    expectTimestamps(*ds, {10, 15, 20});
    expectNoPoses(*ds);

    // Where some frames have pose files, those keep their poses.
    writeText(dir / "frame-000015.pose.txt", matrixText(redwoodPose(1)));
    ds = Dataset::open(dir, withoutPoses());
    ASSERT_EQ(ds->size(), 3u);
    EXPECT_TRUE(ds->hasPoses());
    EXPECT_FALSE(ds->frame(0).hasPose);
    EXPECT_TRUE(ds->frame(1).hasPose);
    expectPoseNear(ds->frame(1).cameraToWorld, redwoodPose(1), 1e-8);
    EXPECT_EQ(Dataset::open(dir)->size(), 1u);  // with requirePoses, as before: the others are skipped
}

TEST(DatasetWithoutPoses, FolderOfDepthImagesWithCameraJson) {
    // Unpadded numbers: natural order 1, 2, 10 (not 1, 10, 2); colour paired by name stem, one image missing.
    auto dir = makeFolder(test::makeTempDir("folder") / "scan", {"depth_1.png", "depth_2.png", "depth_10.png"});
    for (int k : {0, 2}) {
        const std::string stem = k == 0 ? "depth_1" : "depth_10";
        writeColor(dir / "color" / (stem + ".png"), [&](int x, int y) { return colorRamp(k, x, y); });
    }
    expectMentionsTracking(errorMessageOf([&] { Dataset::open(dir); }), dir.string());
    EXPECT_NE(errorMessageOf([&] { Dataset::open(dir); }).find("no poses; vkmesh fuse --track"), std::string::npos);

    auto ds = Dataset::open(dir, withoutPoses());
    EXPECT_EQ(ds->kind(), DatasetKind::Folder);
    EXPECT_EQ(toString(ds->kind()), "folder");
    expectTimestamps(*ds, {1, 2, 10});
    expectNoPoses(*ds);
    EXPECT_EQ(ds->frame(2).depthPath.filename(), "depth_10.png");
    EXPECT_FLOAT_EQ(ds->intrinsics().fx, 500.0f);
    EXPECT_FLOAT_EQ(ds->intrinsics().fy, 501.0f);
    EXPECT_DOUBLE_EQ(ds->depthScale(), 1000.0);
    EXPECT_FLOAT_EQ(ds->loadDepth(2).at(3, 2), ramp(2, 3, 2) / 1000.0f);
    EXPECT_TRUE(ds->hasColor());
    expectColorRamp(ds->loadColor(0), 0);
    expectColorRamp(ds->loadColor(2), 2);
    EXPECT_TRUE(ds->frame(1).colorPath.empty());
    EXPECT_TRUE(anyContains(ds->warnings(), "depth_2.png has no colour image of the same name")) << joinLines(ds->warnings());

    DatasetOptions o = withoutPoses();
    o.maxFrames = 2;
    expectTimestamps(*Dataset::open(dir, o), {1, 2});
}

TEST(DatasetWithoutPoses, FolderItselfNamesWithoutNumbersAndColourByPosition) {
    // No depth/: the PNGs are in the folder itself; names without digits number the frames by position;
    // colour names that match no depth image pair by position when the counts are equal.
    auto dir = makeFolder(test::makeTempDir("folder_flat") / "phone_scan", {"a.png", "b.png", "c.png"}, false);
    for (int k = 0; k < 3; ++k)
        writeColor(dir / "rgb" / ("colour_" + std::to_string(k) + ".jpg"), [&](int x, int y) { return colorRamp(k, x, y); });
    auto ds = Dataset::open(dir, withoutPoses());
    EXPECT_EQ(ds->kind(), DatasetKind::Folder);
    expectTimestamps(*ds, {0, 1, 2});
    EXPECT_TRUE(anyContains(ds->warnings(), "has no number in its name")) << joinLines(ds->warnings());
    EXPECT_EQ(ds->frame(1).colorPath.filename(), "colour_1.jpg");
    EXPECT_FLOAT_EQ(ds->loadDepth(1).at(0, 0), ramp(1, 0, 0) / 1000.0f);

    // Timestamps in the names (Unix seconds) stay seconds.
    auto stamped = makeFolder(test::makeTempDir("folder_stamped") / "rec",
                              {"1305031102.175304.png", "1305031102.211214.png"});
    expectTimestamps(*Dataset::open(stamped, withoutPoses()), {1305031102.175304, 1305031102.211214});
}

TEST(DatasetWithoutPoses, FolderNeedsAFullCameraJson) {
    auto dir = makeFolder(test::makeTempDir("folder_cal") / "scan", {"0.png", "1.png"});
    writeText(dir / "camera.json", R"({"fx": 500, "fy": 500, "cx": 3.5, "cy": 2.5})");
    std::string msg = errorMessageOf([&] { Dataset::open(dir, withoutPoses()); });
    EXPECT_NE(msg.find((dir / "camera.json").string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("missing depth_scale"), std::string::npos) << msg;
    DatasetOptions o = withoutPoses();
    o.depthScale = 5000;  // the option completes it
    EXPECT_DOUBLE_EQ(Dataset::open(dir, o)->depthScale(), 5000.0);

    // PNGs with no camera.json at all: not a dataset vkmesh can calibrate; the message says what is missing.
    auto bare = test::makeTempDir("folder_bare") / "pngs";
    writeDepth(bare / "0.png", [](int, int) { return uint16_t(1000); });
    msg = errorMessageOf([&] { Dataset::open(bare, withoutPoses()); });
    EXPECT_NE(msg.find(bare.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("no camera.json"), std::string::npos) << msg;
}
