// `vkmesh render`: the offscreen graphics pipeline (render pass, depth test, colouring, readback, PNG).
// GpuTest: the validation layer is on and any message it reports fails the test.
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>
#include <numbers>

#include "gpu_fixture.h"
#include "io/ply.h"
#include "io/png.h"
#include "render/mesh_renderer.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using render::Camera;
using render::ColorMode;
using render::Image;
using render::MeshRenderer;
using render::RenderOptions;

// An axis-aligned square in the plane z = z0, centred on (cx, cy), counter-clockwise seen from +z, every
// vertex with `normal` and `age`. Appended to `mesh`; `flip` reverses the order of its two triangles.
void addSquare(Mesh& mesh, float cx, float cy, float z0, float half, Eigen::Vector3f normal, uint32_t age = 0) {
    const uint32_t base = uint32_t(mesh.positions.size());
    mesh.positions.push_back({cx - half, cy - half, z0});
    mesh.positions.push_back({cx + half, cy - half, z0});
    mesh.positions.push_back({cx + half, cy + half, z0});
    mesh.positions.push_back({cx - half, cy + half, z0});
    for (int i = 0; i < 4; ++i) {
        mesh.normals.push_back(normal);
        mesh.vertexAge.push_back(age);
    }
    mesh.triangles.push_back({base, base + 1, base + 2});
    mesh.triangles.push_back({base, base + 2, base + 3});
}

Camera headOn(float distance) {
    Camera c;
    c.eye = {0, 0, distance};
    c.target = {0, 0, 0};
    return c;
}

bool isBackground(const uint8_t* p) {
    return p[0] == render::kBackground[0] && p[1] == render::kBackground[1] && p[2] == render::kBackground[2];
}

class Render : public test::GpuTest {};

TEST_F(Render, UnitSquareCoversItsProjectedArea) {
    Mesh mesh;
    addSquare(mesh, 0, 0, 0, 0.5f, {0, 0, 1});
    RenderOptions options;
    options.width = 200;
    options.height = 160;
    options.camera = headOn(2.0f);
    MeshRenderer renderer(context());
    Image image = renderer.render(mesh, options);
    ASSERT_EQ(image.width, 200);
    ASSERT_EQ(image.height, 160);
    ASSERT_EQ(image.rgba.size(), size_t(200 * 160 * 4));

    // Pinhole with a 60 degree vertical field of view: the side in pixels is side / (2 d tan 30deg) * height.
    const double sidePx = 1.0 / (2.0 * 2.0 * std::tan(std::numbers::pi / 6)) * options.height;
    const double expectedArea = sidePx * sidePx;
    const double cx = options.width / 2.0, cy = options.height / 2.0;
    size_t covered = 0, outside = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const bool bg = isBackground(image.pixel(x, y));
            if (!bg) ++covered;
            // Pixel centres more than 1.5 px outside the analytic square must be background.
            const double px = x + 0.5 - cx, py = y + 0.5 - cy;
            if (!bg && (std::abs(px) > sidePx / 2 + 1.5 || std::abs(py) > sidePx / 2 + 1.5)) ++outside;
        }
    EXPECT_NEAR(double(covered), expectedArea, 0.10 * expectedArea) << "side " << sidePx << " px";
    EXPECT_EQ(outside, 0u);
    EXPECT_FALSE(isBackground(image.pixel(image.width / 2, image.height / 2)));
    EXPECT_TRUE(isBackground(image.pixel(2, 2)));
}

TEST_F(Render, NormalColouringAtTheCentreOfAFrontFacingSquare) {
    Mesh mesh;
    addSquare(mesh, 0, 0, 0, 0.5f, {0, 0, 1});
    RenderOptions options;
    options.width = 64;
    options.height = 48;
    options.camera = headOn(1.5f);
    options.color = ColorMode::Normal;
    MeshRenderer renderer(context());
    Image image = renderer.render(mesh, options);
    const uint8_t* p = image.pixel(32, 24);
    EXPECT_NEAR(p[0], 128, 3);
    EXPECT_NEAR(p[1], 128, 3);
    EXPECT_NEAR(p[2], 255, 3);
    EXPECT_EQ(p[3], 255);
}

TEST_F(Render, BackFacesAreDrawnDarker) {
    Mesh mesh;
    addSquare(mesh, 0, 0, 0, 0.5f, {0, 0, 1});
    RenderOptions options;
    options.width = 64;
    options.height = 48;
    options.color = ColorMode::Normal;
    MeshRenderer renderer(context());
    Camera below;
    below.eye = {0, 0, -1.5f};
    below.target = {0, 0, 0};
    options.camera = below;
    Image back = renderer.render(mesh, options);
    const uint8_t* p = back.pixel(32, 24);
    EXPECT_FALSE(isBackground(p));
    EXPECT_NEAR(p[2], 128, 3);  // (0.5, 0.5, 1) * 0.5
    EXPECT_NEAR(p[0], 64, 3);
}

TEST_F(Render, NearerSurfaceWinsWhateverTheDrawOrder) {
    // Two overlapping squares seen from above: the nearer (z = 0.4, normal +x, reddish) and the farther
    // (z = 0, normal +y, greenish), offset so that each also shows on its own.
    const Eigen::Vector3f nearNormal(1, 0, 0), farNormal(0, 1, 0);
    Mesh nearFirst, farFirst;
    addSquare(nearFirst, 0.25f, 0, 0.4f, 0.4f, nearNormal);
    addSquare(nearFirst, -0.25f, 0, 0.0f, 0.4f, farNormal);
    addSquare(farFirst, -0.25f, 0, 0.0f, 0.4f, farNormal);
    addSquare(farFirst, 0.25f, 0, 0.4f, 0.4f, nearNormal);
    RenderOptions options;
    options.width = 120;
    options.height = 120;
    options.camera = headOn(2.5f);
    options.color = ColorMode::Normal;
    MeshRenderer renderer(context());
    for (const Mesh* mesh : {&nearFirst, &farFirst}) {
        Image image = renderer.render(*mesh, options);
        const uint8_t* c = image.pixel(60, 60);  // the overlap's centre (x = 0 in the world)
        EXPECT_NEAR(c[0], 255, 3) << (mesh == &nearFirst ? "near first" : "far first");
        EXPECT_NEAR(c[1], 128, 3);
        EXPECT_NEAR(c[2], 128, 3);
        // The far square alone, left of the near one (x = -0.42 at z = 0): greenish.
        const uint8_t* left = image.pixel(60 - 18, 60);
        EXPECT_NEAR(left[0], 128, 3);
        EXPECT_NEAR(left[1], 255, 3);
    }
}

TEST_F(Render, AgeColouringGoesFromWarmToCold) {
    Mesh mesh;
    addSquare(mesh, -0.5f, 0, 0, 0.3f, {0, 0, 1}, 0);   // newest: left
    addSquare(mesh, 0.5f, 0, 0, 0.3f, {0, 0, 1}, 40);   // oldest: right
    RenderOptions options;
    options.width = 160;
    options.height = 80;
    options.camera = headOn(1.5f);
    options.color = ColorMode::Age;
    MeshRenderer renderer(context());
    Image image = renderer.render(mesh, options);
    const double f = 80 / (2 * 1.5 * std::tan(std::numbers::pi / 6));  // pixels per metre at z = 0
    const uint8_t* warm = image.pixel(int(80 - 0.5 * f), 40);
    const uint8_t* cold = image.pixel(int(80 + 0.5 * f), 40);
    EXPECT_GT(warm[0], 200);
    EXPECT_LT(warm[2], 30);
    EXPECT_GT(cold[2], 200);
    EXPECT_LT(cold[0], 30);
}

TEST_F(Render, DefaultCameraSeesTheWholeMeshFromOutsideItsBox) {
    Mesh mesh;
    addSquare(mesh, 3, 4, 1, 1.0f, {0, 0, 1});
    Camera c = render::defaultCamera(mesh, 320, 240);
    EXPECT_TRUE(c.eye.x() > 4 || c.eye.x() < 2 || c.eye.y() > 5 || c.eye.y() < 3 || c.eye.z() > 1 || c.eye.z() < 1);
    EXPECT_GT(c.eye.z(), 1.0f);
    RenderOptions options;
    options.width = 320;
    options.height = 240;
    MeshRenderer renderer(context());
    Image image = renderer.render(mesh, options);
    size_t covered = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            bool bg = isBackground(image.pixel(x, y));
            covered += !bg;
            if (x == 0 || y == 0 || x == image.width - 1 || y == image.height - 1) {
                EXPECT_TRUE(bg) << x << "," << y;
            }
        }
    EXPECT_GT(covered, 2000u);
}

TEST_F(Render, CommandPathWritesPngOfTheRequestedSize) {
    auto dir = test::makeTempDir("render");
    Mesh mesh;
    addSquare(mesh, 0, 0, 0, 0.5f, {0, 0, 1}, 3);
    writePly(dir / "square.ply", mesh);
    RenderOptions options;
    options.width = 123;
    options.height = 77;
    options.color = ColorMode::Age;
    io::writePng(dir / "view.png", render::renderMeshFile(context(), dir / "square.ply", options));
    cv::Mat png = cv::imread((dir / "view.png").string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(png.empty());
    EXPECT_EQ(png.cols, 123);
    EXPECT_EQ(png.rows, 77);
    EXPECT_EQ(png.channels(), 3);
}

TEST_F(Render, ErrorsNameTheValue) {
    auto dir = test::makeTempDir("render_err");
    auto expectError = [](auto&& fn, const std::string& needle) {
        try {
            fn();
            ADD_FAILURE() << "no error, expected one naming '" << needle << "'";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    };
    const auto missing = dir / "missing.ply";
    expectError([&] { render::renderMeshFile(context(), missing, {}); }, missing.string());
    {
        std::ofstream(dir / "garbage.ply") << "not a ply file\n";
    }
    expectError([&] { render::renderMeshFile(context(), dir / "garbage.ply", {}); }, "garbage.ply");
    Mesh points;
    points.positions = {{0, 0, 0}, {1, 0, 0}};
    writePly(dir / "points.ply", points);
    expectError([&] { render::renderMeshFile(context(), dir / "points.ply", {}); }, "points.ply");
    expectError([] { render::parseCamera("1,2,3,4,5"); }, "1,2,3,4,5");
    expectError([] { render::parseCamera("1,2,x,4,5,6"); }, "1,2,x,4,5,6");
    expectError([] { render::parseCamera("1,1,1,1,1,1"); }, "1,1,1,1,1,1");
    expectError([] { render::parseColorMode("rainbow"); }, "rainbow");
    Camera c = render::parseCamera(" 1, 2,3,4,5.5,-6");
    EXPECT_FLOAT_EQ(c.eye.y(), 2.0f);
    EXPECT_FLOAT_EQ(c.target.z(), -6.0f);
    MeshRenderer renderer(context());
    expectError([&] { renderer.render(Mesh{}, {}); }, "empty");
}

TEST_F(Render, CliRendersAndReportsBadValues) {
    auto dir = test::makeTempDir("render_cli");
    Mesh mesh;
    addSquare(mesh, 0, 0, 0, 0.5f, {0, 0, 1});
    writePly(dir / "square.ply", mesh);
    const std::string png = (dir / "cli.png").string();
    test::CliRun ok = test::runCli("render " + (dir / "square.ply").string() + " -o " + png +
                                   " --width 90 --height 70 --color normal --camera 0,0,2,0,0,0");
    ASSERT_EQ(ok.exitCode, 0) << ok.err;
    cv::Mat image = cv::imread(png, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(image.empty());
    EXPECT_EQ(image.cols, 90);
    EXPECT_EQ(image.rows, 70);
    const cv::Vec3b centre = image.at<cv::Vec3b>(35, 45);  // BGR
    EXPECT_NEAR(centre[0], 255, 3);
    EXPECT_NEAR(centre[2], 128, 3);
    test::CliRun badCamera = test::runCli("render " + (dir / "square.ply").string() + " -o " + png + " --camera 1,2,3");
    EXPECT_EQ(badCamera.exitCode, 2);
    EXPECT_NE(badCamera.err.find("1,2,3"), std::string::npos) << badCamera.err;
    test::CliRun missing = test::runCli("render " + (dir / "nope.ply").string() + " -o " + png);
    EXPECT_EQ(missing.exitCode, 2);
    EXPECT_NE(missing.err.find("nope.ply"), std::string::npos) << missing.err;
    test::CliRun badColor = test::runCli("render " + (dir / "square.ply").string() + " -o " + png + " --color rainbow");
    EXPECT_EQ(badColor.exitCode, 2);
    EXPECT_NE(badColor.err.find("rainbow"), std::string::npos) << badColor.err;
}

}  // namespace
}  // namespace vkmesh
