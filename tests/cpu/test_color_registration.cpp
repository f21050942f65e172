// Colour from a camera beside the depth camera (io/color_registration.h): a synthetic two-camera rig with a
// known baseline, rotation and intrinsics of its own. The colour registered onto the depth grid must match what
// a colour camera at the depth camera would have seen, far better than registration that ignores the baseline,
// and surfaces the colour camera cannot see must get no colour rather than the occluder's.
#include "io/color_registration.h"
#include "io/dataset.h"
#include "io/png.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>
#include <iostream>
#include <iomanip>

namespace fs = std::filesystem;
using namespace vkmesh;

namespace {

struct Rig {
    Intrinsics depthK = synth::kinectIntrinsics(320, 240);
    ColorCamera color;
    Pose depthToWorld;
    Pose colorToWorld;
};

// A depth camera looking into the default room and, 5 cm to its right, turned 3 degrees, a colour camera with
// a wider image and its own focal length (as a RealSense D435's colour camera beside its depth camera).
Rig makeRig() {
    Rig rig;
    rig.depthToWorld = synth::cameraPath(30, synth::PathKind::Orbit)[7];
    rig.color.intrinsics = Intrinsics{330.f, 331.f, 211.f, 159.f, 424, 320};
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisd(3.0 * M_PI / 180.0, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
    T.topRightCorner<3, 1>() = Eigen::Vector3d(-0.05, 0.003, 0.002);   // the colour camera at x = +5 cm: p_c = R p_d + t
    rig.color.depthToColor = T;
    rig.colorToWorld = rig.depthToWorld * T.inverse();
    return rig;
}

struct ColorError {
    double mean = 0;     // mean absolute error per channel over the compared pixels
    double coloured = 0; // fraction of depth pixels that got a colour
};

// Compares `registered` with the truth (what a colour camera at the depth camera sees), on the depth pixels
// that got a colour and are not within 2 pixels of a depth edge (where either image mixes two surfaces).
ColorError compare(const ColorImage& registered, const ColorImage& truth, const DepthImage& depth) {
    ColorError e;
    size_t n = 0, withDepth = 0, coloured = 0;
    for (int y = 2; y < depth.height - 2; ++y)
        for (int x = 2; x < depth.width - 2; ++x) {
            const float z = depth.meters[size_t(y) * depth.width + x];
            if (!(z > 0)) continue;
            ++withDepth;
            const uint8_t* r = registered.at(x, y);
            if (r[0] == 0 && r[1] == 0 && r[2] == 0) continue;
            ++coloured;
            bool edge = false;
            for (int dy = -2; dy <= 2 && !edge; ++dy)
                for (int dx = -2; dx <= 2; ++dx)
                    if (std::abs(depth.meters[size_t(y + dy) * depth.width + x + dx] - z) > 0.03f * z) edge = true;
            if (edge) continue;
            const uint8_t* t = truth.at(x, y);
            for (int c = 0; c < 3; ++c) e.mean += std::abs(int(r[c]) - int(t[c]));
            n += 3;
        }
    e.mean /= double(std::max<size_t>(n, 1));
    e.coloured = double(coloured) / double(std::max<size_t>(withDepth, 1));
    return e;
}

}  // namespace

TEST(ColorRegistration, TwoCameraRigMatchesTheColourSeenFromTheDepthCamera) {
    const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    const Rig rig = makeRig();
    ColorImage truth, seen;
    const DepthImage depth = scene.renderDepth(rig.depthK, rig.depthToWorld, {}, &truth);
    scene.renderDepth(rig.color.intrinsics, rig.colorToWorld, {}, &seen);

    const ColorImage registered = registerColorToDepth(seen, rig.color, depth, rig.depthK);
    // Ignoring the baseline (the cameras' optical centres taken as one, as vkmesh did before): the same
    // intrinsics and rotation, no translation.
    ColorCamera noBaseline = rig.color;
    noBaseline.depthToColor.topRightCorner<3, 1>().setZero();
    const ColorImage naive = registerColorToDepth(seen, noBaseline, depth, rig.depthK);

    const ColorError good = compare(registered, truth, depth), bad = compare(naive, truth, depth);
    std::cout << "registered: " << good.mean << " levels, " << good.coloured << " coloured; without the baseline: " << bad.mean
              << " levels\n";
    // The textures hold 8 mm stripes: resampling costs a few levels; a 5 cm baseline puts many pixels on the
    // wrong stripe or object.
    EXPECT_LT(good.mean, 9.0) << "registered colour is off by " << good.mean << " levels on average";
    EXPECT_LT(good.mean, 0.3 * bad.mean) << "with the baseline " << good.mean << ", without " << bad.mean;
    EXPECT_GT(good.coloured, 0.9) << "only " << good.coloured << " of the depth pixels got a colour";
}

TEST(ColorRegistration, SurfacesHiddenFromTheColourCameraGetNoColour) {
    // A sphere 1 m in front of a wall, seen by the depth camera; the colour camera 15 cm to the side sees a
    // strip of wall the depth camera sees that the sphere hides from it. Without the depth test that strip
    // would be painted with the sphere's colour.
    const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    Rig rig = makeRig();
    rig.color.depthToColor = Eigen::Matrix4d::Identity();
    rig.color.depthToColor(0, 3) = -0.15;
    rig.colorToWorld = rig.depthToWorld * rig.color.depthToColor.inverse();
    ColorImage truth, seen;
    const DepthImage depth = scene.renderDepth(rig.depthK, rig.depthToWorld, {}, &truth);
    scene.renderDepth(rig.color.intrinsics, rig.colorToWorld, {}, &seen);
    const ColorImage registered = registerColorToDepth(seen, rig.color, depth, rig.depthK);
    const ColorImage untested = registerColorToDepth(seen, rig.color, depth, rig.depthK, false);

    // Pixels whose point the colour camera cannot see: it renders something more than 5 cm nearer along the
    // ray to that point. Those must be black; the others mostly coloured.
    const Eigen::Matrix3d R = rig.color.depthToColor.topLeftCorner<3, 3>();
    const Eigen::Vector3d t = rig.color.depthToColor.topRightCorner<3, 1>();
    const DepthImage colorDepth = scene.renderDepth(rig.color.intrinsics, rig.colorToWorld);
    const Intrinsics& k = rig.depthK;
    const Intrinsics& ck = rig.color.intrinsics;
    size_t hidden = 0, hiddenColoured = 0, hiddenColouredUntested = 0;
    for (int v = 0; v < k.height; ++v)
        for (int u = 0; u < k.width; ++u) {
            const double z = depth.meters[size_t(v) * k.width + u];
            if (!(z > 0)) continue;
            const Eigen::Vector3d q = R * Eigen::Vector3d(z * (u - k.cx) / k.fx, z * (v - k.cy) / k.fy, z) + t;
            const int x = int(std::lround(ck.fx * q.x() / q.z() + ck.cx)), y = int(std::lround(ck.fy * q.y() / q.z() + ck.cy));
            if (x < 0 || y < 0 || x >= ck.width || y >= ck.height) continue;
            const float seenZ = colorDepth.meters[size_t(y) * ck.width + x];
            if (!(seenZ > 0 && seenZ < q.z() - 0.10 - 0.03 * q.z())) continue;   // clearly hidden, not a grazing edge
            ++hidden;
            const uint8_t* c = registered.at(u, v);
            hiddenColoured += (c[0] | c[1] | c[2]) != 0;
            const uint8_t* d = untested.at(u, v);
            hiddenColouredUntested += (d[0] | d[1] | d[2]) != 0;
        }
    std::cout << hidden << " pixels hidden from the colour camera; coloured with the depth test " << hiddenColoured
              << ", without " << hiddenColouredUntested << "\n";
    ASSERT_GT(hidden, 200u) << "the rig should hide some of the room from the colour camera";
    // What remains is the band only the colour camera sees beside an object's silhouette, which no depth test on
    // the depth image can find.
    EXPECT_GT(double(hiddenColouredUntested), 0.9 * double(hidden));
    EXPECT_LT(double(hiddenColoured), 0.25 * double(hidden)) << hiddenColoured << " of " << hidden << " hidden pixels got a colour";
}

TEST(ColorRegistration, WithoutABaselineAndTheSameCameraColourIsCopiedExactly) {
    const Rig rig = makeRig();
    ColorImage color;
    color.width = rig.depthK.width;
    color.height = rig.depthK.height;
    color.rgb.resize(size_t(color.width) * color.height * 3);
    for (size_t i = 0; i < color.rgb.size(); ++i) color.rgb[i] = uint8_t(i * 7);
    DepthImage depth;
    depth.width = color.width;
    depth.height = color.height;
    depth.meters.assign(size_t(depth.width) * depth.height, 1.5f);
    const ColorImage out = registerColorToDepth(color, ColorCamera{rig.depthK, Eigen::Matrix4d::Identity()}, depth, rig.depthK);
    EXPECT_EQ(out.rgb, color.rgb);
    // A colour image of the wrong size is an error, not a wrong colour.
    ColorImage small = color;
    small.width -= 1;
    EXPECT_THROW(registerColorToDepth(small, ColorCamera{rig.depthK, Eigen::Matrix4d::Identity()}, depth, rig.depthK), Error);
}

TEST(ColorRegistration, DatasetRegistersThroughDepthWithCameraJsonExtrinsics) {
    // The rig written as a folder: depth PNGs, the colour camera's own images and a camera.json with its
    // intrinsics and depth_to_color. Dataset::loadColor must give exactly registerColorToDepth's image.
    const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    const Rig rig = makeRig();
    const fs::path dir = test::makeTempDir("color_rig");
    fs::create_directories(dir / "depth");
    fs::create_directories(dir / "color");
    ColorImage seen;
    const DepthImage depth = scene.renderDepth(rig.depthK, rig.depthToWorld, {}, &seen);
    scene.renderDepth(rig.color.intrinsics, rig.colorToWorld, {}, &seen);
    cv::Mat raw(rig.depthK.height, rig.depthK.width, CV_16UC1);
    for (int i = 0; i < raw.rows * raw.cols; ++i) raw.at<uint16_t>(i) = uint16_t(std::lround(depth.meters[size_t(i)] * 1000.0));
    ASSERT_TRUE(cv::imwrite((dir / "depth" / "000000.png").string(), raw));
    cv::Mat bgr(seen.height, seen.width, CV_8UC3);
    for (int i = 0; i < seen.width * seen.height; ++i)
        bgr.at<cv::Vec3b>(i) = cv::Vec3b(seen.rgb[size_t(i) * 3 + 2], seen.rgb[size_t(i) * 3 + 1], seen.rgb[size_t(i) * 3]);
    ASSERT_TRUE(cv::imwrite((dir / "color" / "000000.png").string(), bgr));
    const Eigen::Matrix4d& T = rig.color.depthToColor;
    std::ofstream(dir / "camera.json") << std::setprecision(17) << "{\"fx\": " << rig.depthK.fx << ", \"fy\": " << rig.depthK.fy
                                       << ", \"cx\": " << rig.depthK.cx << ", \"cy\": " << rig.depthK.cy
                                       << ", \"depth_scale\": 1000, \"color_fx\": " << rig.color.intrinsics.fx
                                       << ", \"color_fy\": " << rig.color.intrinsics.fy << ", \"color_cx\": " << rig.color.intrinsics.cx
                                       << ", \"color_cy\": " << rig.color.intrinsics.cy << ", \"depth_to_color\": {\"rotation\": ["
                                       << T(0, 0) << ", " << T(0, 1) << ", " << T(0, 2) << ", " << T(1, 0) << ", " << T(1, 1) << ", "
                                       << T(1, 2) << ", " << T(2, 0) << ", " << T(2, 1) << ", " << T(2, 2) << "], \"translation\": ["
                                       << T(0, 3) << ", " << T(1, 3) << ", " << T(2, 3) << "]}}";
    DatasetOptions options;
    options.requirePoses = false;
    const auto ds = Dataset::open(dir, options);
    std::string warning;
    const DepthImage loaded = ds->loadDepth(0);
    const ColorImage fromDataset = ds->loadColor(0, &warning);
    ASSERT_FALSE(fromDataset.empty()) << warning;
    const ColorImage expected = registerColorToDepth(seen, rig.color, loaded, ds->intrinsics());
    EXPECT_EQ(fromDataset.rgb, expected.rgb);
    EXPECT_EQ(ds->loadColor(0, &warning, &loaded).rgb, expected.rgb);

    // A rotation that is not one is refused, naming the key.
    std::ofstream(dir / "camera.json") << "{\"fx\": 300, \"fy\": 300, \"cx\": 160, \"cy\": 120, \"depth_scale\": 1000, "
                                          "\"depth_to_color\": {\"rotation\": [1, 0, 0, 0, 1, 0, 0, 0, 2], \"translation\": [0, 0, 0]}}";
    EXPECT_NE(test::errorMessageOf([&] { Dataset::open(dir, options); }).find("depth_to_color"), std::string::npos);
}
