// Dataset colour (rgb.txt association, colour of every layout, bad colour images, colour intrinsics) and sequences
// read without poses for camera tracking (DatasetOptions::requirePoses = false), plain folders of depth images too.
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
