// Dataset input that must fail with a clear message (missing folders, malformed index and pose lines, bad images,
// options and camera.json), parseIntrinsics and validatePose, and the camera presets (data/cameras, VKMESH_DATA_DIR).
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

