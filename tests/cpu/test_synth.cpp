// Synthetic scenes: the signed distance function, the sphere-tracing renderer, the noise model, the camera
// path and the TUM-layout writer, each checked against closed-form ground truth.
#include "synth/synthetic_scene.h"
#include "synth/tum_sequence.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <utility>

using namespace vkmesh;
using namespace vkmesh::synth;

namespace {

Eigen::Vector3d backProject(const Intrinsics& k, int u, int v, double depth) {
    return {(u - k.cx) / k.fx * depth, (v - k.cy) / k.fy * depth, depth};
}

Eigen::Vector3d toWorld(const Pose& cameraToWorld, const Eigen::Vector3d& cameraPoint) {
    return cameraToWorld.topLeftCorner<3, 3>() * cameraPoint + cameraToWorld.topRightCorner<3, 1>();
}

using test::lookAt;

// A small camera whose principal point is a pixel centre, so that pixel (cx, cy) looks along +z exactly.
Intrinsics centredIntrinsics(int width, int height, float focal) {
    Intrinsics k;
    k.width = width;
    k.height = height;
    k.fx = k.fy = focal;
    k.cx = static_cast<float>(width / 2);
    k.cy = static_cast<float>(height / 2);
    return k;
}

void expectProperRotation(const Pose& pose) {
    const Eigen::Matrix3d r = pose.topLeftCorner<3, 3>();
    EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_NEAR(r.determinant(), 1.0, 1e-9);
    EXPECT_EQ(pose.row(3), Eigen::RowVector4d(0, 0, 0, 1));
}

struct PlyPoints {
    std::vector<Eigen::Vector3d> positions, normals;
    std::vector<Rgb> colors;
};

// Reads the binary little-endian "float x y z nx ny nz uchar red green blue" clouds writeTumSequence
// produces (and nothing else).
PlyPoints readGroundTruthPly(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    EXPECT_TRUE(in.good()) << path;
    std::string line;
    size_t count = 0;
    std::vector<std::string> properties;
    bool binaryLittleEndian = false;
    while (std::getline(in, line) && line != "end_header") {
        std::istringstream words(line);
        std::string word, type, name;
        words >> word;
        if (word == "format") binaryLittleEndian = line == "format binary_little_endian 1.0";
        if (word == "element") words >> name >> count;
        if (word == "property") {
            words >> type >> name;
            EXPECT_EQ(type, properties.size() < 6 ? "float" : "uchar") << name;
            properties.push_back(name);
        }
    }
    EXPECT_TRUE(binaryLittleEndian);
    EXPECT_EQ(properties, (std::vector<std::string>{"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"}));
    PlyPoints points;
    constexpr size_t kRecord = 6 * sizeof(float) + 3;
    std::vector<char> bytes(count * kRecord);
    in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    EXPECT_EQ(static_cast<size_t>(in.gcount()), bytes.size()) << "truncated " << path;
    for (size_t i = 0; i < count; ++i) {
        float v[6];
        std::memcpy(v, bytes.data() + i * kRecord, sizeof v);
        points.positions.emplace_back(v[0], v[1], v[2]);
        points.normals.emplace_back(v[3], v[4], v[5]);
        const auto* c = reinterpret_cast<const uint8_t*>(bytes.data() + i * kRecord + sizeof v);
        points.colors.push_back({c[0], c[1], c[2]});
    }
    return points;
}

std::vector<std::vector<std::string>> readDataLines(const std::filesystem::path& path) {
    std::ifstream in(path);
    EXPECT_TRUE(in.good()) << path;
    std::vector<std::vector<std::string>> rows;
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream words(line);
        std::vector<std::string> row;
        for (std::string word; words >> word;) row.push_back(word);
        rows.push_back(row);
    }
    return rows;
}

double kinectSigma(double z) { return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4); }

}  // namespace

// ----------------------------------------------------------------------------------------------------------
TEST(SyntheticSdf, SphereSignAndMagnitude) {
    const Eigen::Vector3d center(0.3, -1.2, 2.0);
    const auto scene = SyntheticScene::singleSphere(center, 0.5);
    EXPECT_NEAR(scene.sdf(center), -0.5, 1e-12);
    EXPECT_NEAR(scene.sdf(center + Eigen::Vector3d(0, 0.2, 0)), -0.3, 1e-12);
    EXPECT_NEAR(scene.sdf(center + 0.5 * Eigen::Vector3d(1, 2, -2).normalized()), 0.0, 1e-12);
    EXPECT_NEAR(scene.sdf(center + Eigen::Vector3d(0, 0, 2.0)), 1.5, 1e-12);
    const Eigen::Vector3d direction = Eigen::Vector3d(-1, 0.5, 0.3).normalized();
    EXPECT_LT((scene.normal(center + 0.5 * direction) - direction).norm(), 1e-6);
    EXPECT_EQ(scene.object("sphere").center(), center);
    EXPECT_EQ(scene.object("sphere").radius, 0.5);
}

TEST(SyntheticSdf, SlantedPlaneIsTheExactDistance) {
    const Eigen::Vector3d normal(1.0, -2.0, 3.0);
    const double offset = 0.7;  // relative to the unit normal
    const auto scene = SyntheticScene::slantedPlane(normal, offset);
    const Eigen::Vector3d unit = normal.normalized();
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(-4, 0.5, 1),
                                     Eigen::Vector3d(10, -10, 2), Eigen::Vector3d(unit * offset)}) {
        EXPECT_NEAR(scene.sdf(p), unit.dot(p) - offset, 1e-12) << p.transpose();
        EXPECT_LT((scene.normal(p) - unit).norm(), 1e-6);
    }
    EXPECT_THROW(SyntheticScene::slantedPlane(Eigen::Vector3d::Zero(), 1.0), Error);
}

TEST(SyntheticSdf, DefaultRoomLayout) {
    const auto scene = SyntheticScene::defaultRoom();
    const Object& sphere = scene.object("sphere");
    const Object& torus = scene.object("torus");
    EXPECT_NEAR(sphere.radius, 0.35, 1e-12);
    EXPECT_NEAR(torus.radius, 0.3, 1e-12);
    EXPECT_NEAR(torus.tubeRadius, 0.1, 1e-12);
    EXPECT_LT(scene.sdf(sphere.center()), -0.3);  // inside matter
    EXPECT_NEAR(scene.sdf(sphere.center() + Eigen::Vector3d(0, 0, 0.35)), 0.0, 1e-12);
    EXPECT_GT(scene.sdf(Eigen::Vector3d(0, 0, 2.0)), 0.3);  // the air above the objects
    EXPECT_LT(scene.sdf(Eigen::Vector3d(0, 0, -0.1)), 0.0);  // under the floor
    EXPECT_LT(scene.sdf(Eigen::Vector3d(0, 0, 3.0)), 0.0);   // above the ceiling

    // The walls are turned ~20 degrees about the vertical: no wall normal along a world axis.
    const Eigen::Matrix3d roomRotation = scene.object("room").objectToWorld.linear();
    EXPECT_NEAR(std::atan2(roomRotation(1, 0), roomRotation(0, 0)) * 180 / std::numbers::pi, 20.0, 1e-9);
    // The ramp's top face is slanted 30 degrees.
    const Eigen::Vector3d rampUp = scene.object("ramp").objectToWorld.linear().col(2);
    EXPECT_NEAR(std::acos(rampUp.z()) * 180 / std::numbers::pi, 30.0, 1e-9);
    EXPECT_LE(2 * scene.object("thin_plate").halfExtents.minCoeff(), 0.03);

    // Sphere and torus are free-standing: every point of their surfaces is at least 5 cm from anything else.
    for (const char* name : {"sphere", "torus"}) {
        const Object& object = scene.object(name);
        const auto samples = sampleSurface(SyntheticScene({object}), 0.02);
        ASSERT_GT(samples.size(), 100u);
        for (const Object& other : scene.objects()) {
            if (other.name == object.name) continue;
            double nearest = 1e9;
            for (const SurfaceSample& s : samples) nearest = std::min(nearest, other.sdf(s.position));
            EXPECT_GT(nearest, 0.05) << name << " comes close to " << other.name;
        }
    }
    EXPECT_THROW(scene.object("teapot"), Error);
}

// The scene's sdf() takes each point's minimum over the objects its grid cell lists (SyntheticScene::NearestGrid):
// that must be the minimum over every object, to the bit, anywhere (near surfaces, between objects, on cell
// borders, outside the grid), or renders would change with the grid.
TEST(SyntheticSdf, NearestObjectListsGiveTheMinimumOverAllObjects) {
    for (const SyntheticScene& scene : {SyntheticScene::defaultRoom(), SyntheticScene::gallery(), SyntheticScene::twinGroups()}) {
        std::mt19937_64 random(7);
        std::uniform_real_distribution<double> coordinate(-8.0, 8.0), height(-0.5, 3.5), unit(0.0, 1.0);
        size_t nearSurface = 0;
        for (int n = 0; n < 200000; ++n) {
            Eigen::Vector3d p(coordinate(random), coordinate(random), height(random));
            if (n % 4 == 0) {   // a quarter snapped to a 5 cm lattice: points on cell borders and object faces
                p = (p / 0.05).array().round().matrix() * 0.05;
            } else if (n % 4 == 1) {   // a quarter pulled onto an object's surface
                const Object& o = scene.objects()[static_cast<size_t>(unit(random) * scene.objects().size()) % scene.objects().size()];
                const double d = o.sdf(p);
                if (std::isfinite(o.boundingRadius())) p = o.center() + (p - o.center()).normalized() * (o.boundingRadius() * unit(random));
                else p.z() = p.z() - d * 0.999;
            }
            double everyObject = std::numeric_limits<double>::infinity();
            for (const Object& o : scene.objects()) everyObject = std::min(everyObject, o.sdf(p));
            nearSurface += std::abs(everyObject) < 0.05;
            ASSERT_EQ(scene.sdf(p), everyObject) << "at (" << p.transpose() << ")";
        }
        EXPECT_GT(nearSurface, 1000u) << "the points hardly came near a surface: the test tests little";
    }
}

TEST(SyntheticSdf, RejectsBadObjects) {
    Object sphere{.name = "s", .kind = ObjectKind::Sphere};
    EXPECT_THROW(SyntheticScene({sphere}), Error);  // radius 0
    sphere.radius = 1;
    EXPECT_THROW(SyntheticScene({sphere, sphere}), Error);  // duplicate names
    EXPECT_THROW(SyntheticScene(std::vector<Object>{}), Error);
}

// ----------------------------------------------------------------------------------------------------------
TEST(SyntheticRender, SingleSphereDepthIsExact) {
    const Eigen::Vector3d center(0.4, -0.3, 1.1);
    const double radius = 0.5;
    const auto scene = SyntheticScene::singleSphere(center, radius);
    const Intrinsics k = centredIntrinsics(64, 48, 50.0f);
    const Eigen::Vector3d eye(2.5, 1.0, 1.6);
    const Pose pose = lookAt(eye, center);
    const DepthImage depth = scene.renderDepth(k, pose);
    ASSERT_EQ(depth.width, 64);
    ASSERT_EQ(depth.height, 48);

    const double distance = (center - eye).norm();
    EXPECT_NEAR(depth.at(32, 24), distance - radius, 1e-4);

    // The sphere covers a disc of angular radius asin(r / distance) around the optical axis.
    const double discAngle = std::asin(radius / distance);
    int valid = 0;
    for (int v = 0; v < k.height; ++v) {
        for (int u = 0; u < k.width; ++u) {
            const double angle = std::atan(std::hypot((u - k.cx) / k.fx, (v - k.cy) / k.fy));
            const float z = depth.at(u, v);
            if (angle > discAngle + 0.01) {
                EXPECT_EQ(z, 0.0f) << u << "," << v;
            }
            if (angle < discAngle - 0.01) {
                EXPECT_GT(z, 0.0f) << u << "," << v;
            }
            if (z <= 0) continue;
            ++valid;
            const Eigen::Vector3d world = toWorld(pose, backProject(k, u, v, z));
            EXPECT_LT(std::abs(scene.sdf(world)), 5e-4) << u << "," << v;
        }
    }
    EXPECT_GT(valid, 200);
}

TEST(SyntheticRender, DefaultRoomAlongThePath) {
    const auto scene = SyntheticScene::defaultRoom();
    const Intrinsics k = kinectIntrinsics(80, 60);
    const std::vector<Pose> path = cameraPath(12);
    for (size_t frame : {0u, 4u, 9u}) {
        const Pose& pose = path[frame];
        const DepthImage depth = scene.renderDepth(k, pose);
        size_t valid = 0;
        double worst = 0;
        for (int v = 0; v < k.height; ++v) {
            for (int u = 0; u < k.width; ++u) {
                const float z = depth.at(u, v);
                if (z <= 0) continue;
                ++valid;
                worst = std::max(worst, std::abs(scene.sdf(toWorld(pose, backProject(k, u, v, z)))));
            }
        }
        EXPECT_GE(valid, 0.9 * k.width * k.height) << "frame " << frame;
        EXPECT_LT(worst, 5e-4) << "frame " << frame;
    }
}

TEST(SyntheticRender, RejectsBadInput) {
    const auto scene = SyntheticScene::singleSphere({0, 0, 2}, 0.5);
    Intrinsics k = kinectIntrinsics(32, 24);
    k.fx = 0;
    EXPECT_THROW(scene.renderDepth(k, Pose::Identity()), Error);
    k = kinectIntrinsics(32, 24);
    k.width = 0;
    EXPECT_THROW(scene.renderDepth(k, Pose::Identity()), Error);
    Pose scaled = Pose::Identity();
    scaled(0, 0) = 2;
    EXPECT_THROW(scene.renderDepth(kinectIntrinsics(32, 24), scaled), Error);
}

// ----------------------------------------------------------------------------------------------------------
TEST(SyntheticNoise, DeterministicPerSeedWithKinectSigma) {
    // A wall facing the camera at z = 1.5 m: free space where -z > -1.5.
    const auto scene = SyntheticScene::slantedPlane({0, 0, -1}, -1.5);
    const Intrinsics k = kinectIntrinsics(64, 48);
    const DepthImage clean = scene.renderDepth(k, Pose::Identity());
    RenderOptions noisy;
    noisy.noise = true;
    noisy.seed = 7;
    const DepthImage first = scene.renderDepth(k, Pose::Identity(), noisy);
    const DepthImage again = scene.renderDepth(k, Pose::Identity(), noisy);
    noisy.seed = 8;
    const DepthImage other = scene.renderDepth(k, Pose::Identity(), noisy);
    EXPECT_EQ(first.meters, again.meters);

    size_t differing = 0, compared = 0;
    double sum = 0, sumSquares = 0;
    for (size_t i = 0; i < clean.meters.size(); ++i) {
        ASSERT_NEAR(clean.meters[i], 1.5, 1e-4);
        if (first.meters[i] != other.meters[i]) ++differing;
        if (first.meters[i] <= 0) continue;
        const double error = first.meters[i] - clean.meters[i];
        sum += error;
        sumSquares += error * error;
        ++compared;
    }
    EXPECT_GT(differing, clean.meters.size() * 9 / 10);
    ASSERT_GT(compared, clean.meters.size() * 9 / 10);  // a facing wall keeps (nearly) all its pixels
    const double mean = sum / compared;
    const double sigma = std::sqrt(sumSquares / compared - mean * mean);
    EXPECT_NEAR(sigma, kinectSigma(1.5), 0.3 * kinectSigma(1.5));
    EXPECT_LT(std::abs(mean), 4 * kinectSigma(1.5) / std::sqrt(static_cast<double>(compared)));
}

TEST(SyntheticNoise, DropsGrazingPixels) {
    // A floor 0.2 m below the camera (camera y points down): the rows near the horizon see it edge-on.
    const auto scene = SyntheticScene::slantedPlane({0, -1, 0}, -0.2);
    const Intrinsics k = kinectIntrinsics(64, 48);
    const DepthImage clean = scene.renderDepth(k, Pose::Identity());
    RenderOptions options;
    options.noise = true;
    const DepthImage noisy = scene.renderDepth(k, Pose::Identity(), options);
    int grazing = 0;
    for (int v = 0; v < k.height; ++v) {
        for (int u = 0; u < k.width; ++u) {
            if (clean.at(u, v) <= 0) continue;
            const Eigen::Vector3d ray = backProject(k, u, v, 1.0).normalized();
            const double incidence = std::acos(std::abs(ray.y())) * 180 / std::numbers::pi;
            if (incidence > 80.5) {
                ++grazing;
                EXPECT_EQ(noisy.at(u, v), 0.0f) << u << "," << v;
            }
        }
    }
    EXPECT_GT(grazing, 0);
}

// ----------------------------------------------------------------------------------------------------------
TEST(SyntheticPath, ProperSmoothLoops) {
    const auto scene = SyntheticScene::defaultRoom();
    const std::vector<Pose> orbit = cameraPath(40, PathKind::Orbit);
    ASSERT_EQ(orbit.size(), 40u);
    for (size_t i = 0; i < orbit.size(); ++i) {
        expectProperRotation(orbit[i]);
        const Eigen::Vector3d eye = orbit[i].topRightCorner<3, 1>();
        EXPECT_NEAR(eye.z(), 1.5, 0.25);
        EXPECT_GT(scene.sdf(eye), 0.3) << "camera " << i << " too close to something";
        // Smooth: neighbouring poses (the loop closing too) are close in position and orientation.
        const Pose& next = orbit[(i + 1) % orbit.size()];
        EXPECT_LT((next.topRightCorner<3, 1>() - eye).norm(), 0.4);
        const Eigen::Matrix3d relative = orbit[i].topLeftCorner<3, 3>().transpose() * next.topLeftCorner<3, 3>();
        EXPECT_LT(Eigen::AngleAxisd(relative).angle(), 0.4);
        // Looking at the objects: the sphere and torus are in front of the camera.
        for (const char* name : {"sphere", "torus"}) {
            const Eigen::Vector3d inCamera =
                orbit[i].topLeftCorner<3, 3>().transpose() * (scene.object(name).center() - eye);
            EXPECT_GT(inCamera.z(), 0.5) << name << " behind camera " << i;
        }
    }
    const std::vector<Pose> revisit = cameraPath(30, PathKind::Revisit);
    ASSERT_EQ(revisit.size(), 30u);
    for (size_t i = 0; i < revisit.size(); ++i) {
        expectProperRotation(revisit[i]);
        if (i + 10 < revisit.size()) {
            EXPECT_LT((revisit[i] - revisit[i + 10]).cwiseAbs().maxCoeff(), 1e-9);
        }
    }
    EXPECT_THROW(cameraPath(0), Error);
}

namespace {

// The loop-closure scenes' paths: smooth, rigid, in free space.
void expectSmoothInFreeSpace(const std::vector<Pose>& path, const SyntheticScene& scene, double clearance) {
    for (size_t i = 0; i < path.size(); ++i) {
        expectProperRotation(path[i]);
        const Eigen::Vector3d eye = path[i].topRightCorner<3, 1>();
        EXPECT_GT(scene.sdf(eye), clearance) << "camera " << i << " too close to something";
        if (i + 1 == path.size()) break;
        EXPECT_LT((path[i + 1].topRightCorner<3, 1>() - eye).norm(), 0.15) << i;
        const Eigen::Matrix3d relative = path[i].topLeftCorner<3, 3>().transpose() * path[i + 1].topLeftCorner<3, 3>();
        EXPECT_LT(Eigen::AngleAxisd(relative).angle(), 0.1) << i;
    }
}

}  // namespace

TEST(SyntheticPath, GalleryLoopLooksOutwardAndRevisitsItsStart) {
    const auto scene = SyntheticScene::gallery();
    const std::vector<Pose> path = cameraPath(240, PathKind::GalleryLoop);
    ASSERT_EQ(path.size(), 240u);
    expectSmoothInFreeSpace(path, scene, 0.5);
    const Eigen::Vector3d hallCenter = scene.object("hall").center();
    for (size_t i = 0; i < path.size(); ++i) {
        const Eigen::Vector3d eye = path[i].topRightCorner<3, 1>();
        Eigen::Vector3d outward = eye - hallCenter;
        outward.z() = 0;
        EXPECT_GT(path[i].col(2).head<3>().dot(outward.normalized()), 0.8) << "camera " << i << " not looking outward";
    }
    // The path starts at rest: frame 1 is a small step, not a lap's average one.
    const Eigen::Vector3d firstStep = path[1].topRightCorner<3, 1>() - path[0].topRightCorner<3, 1>();
    EXPECT_LT(firstStep.norm(), 0.01);
    // The last sixth drives the start again: near an early pose throughout, and exactly on one once the first
    // pass is at full speed (a lap is 200 frames, its first 20 the start from rest).
    for (size_t i = 200; i < path.size(); ++i) {
        double nearest = 1e9;
        for (size_t j = 0; j < 60; ++j) nearest = std::min(nearest, (path[i] - path[j]).cwiseAbs().maxCoeff());
        EXPECT_LT(nearest, i >= 210 ? 1e-6 : 0.05) << "frame " << i << " revisits no early pose";
    }
}

TEST(SyntheticPath, TwinVisitSeesBothGroupsFromTheSameSpot) {
    const auto scene = SyntheticScene::twinGroups();
    // The groups are identical but for where they stand.
    const Eigen::Vector3d offset = scene.object("b_box").center() - scene.object("a_box").center();
    EXPECT_GT(offset.norm(), 4.0);
    for (const char* part : {"box", "sphere", "cylinder", "torus"}) {
        const Object& a = scene.object(std::string("a_") + part);
        const Object& b = scene.object(std::string("b_") + part);
        EXPECT_EQ(a.kind, b.kind) << part;
        EXPECT_LT((b.center() - a.center() - offset).norm(), 1e-12) << part;
        EXPECT_LT((b.objectToWorld.linear() - a.objectToWorld.linear()).cwiseAbs().maxCoeff(), 1e-12) << part;
        EXPECT_EQ(a.halfExtents, b.halfExtents) << part;
        EXPECT_EQ(a.radius, b.radius) << part;
        EXPECT_EQ(a.texture.a, b.texture.a) << part;
        EXPECT_EQ(a.texture.period, b.texture.period) << part;
    }
    const std::vector<Pose> path = cameraPath(200, PathKind::TwinVisit);
    ASSERT_EQ(path.size(), 200u);
    expectSmoothInFreeSpace(path, scene, 0.3);
    // The last quarter is the first moved by the groups' offset: the same view of the other group.
    for (size_t i = 0; i < 50; ++i) {
        const Pose& early = path[i];
        const Pose& late = path[i + 150];
        const Eigen::Matrix3d turn = late.topLeftCorner<3, 3>() - early.topLeftCorner<3, 3>();
        EXPECT_LT(turn.cwiseAbs().maxCoeff(), 1e-9) << i;
        EXPECT_LT((late.topRightCorner<3, 1>() - early.topRightCorner<3, 1>() - offset).norm(), 1e-9) << i;
    }
    // Each visit looks at its group.
    for (const auto& [frame, name] : {std::pair<size_t, const char*>{10, "a_sphere"}, {160, "b_sphere"}}) {
        const Eigen::Vector3d inCamera = path[frame].topLeftCorner<3, 3>().transpose() *
                                         (scene.object(name).center() - path[frame].topRightCorner<3, 1>());
        EXPECT_GT(inCamera.z(), 1.0) << name;
        EXPECT_LT(std::abs(inCamera.x()), 0.5 * inCamera.z()) << name;
    }
    EXPECT_EQ(pathName(PathKind::GalleryLoop), "gallery-loop");
    EXPECT_EQ(pathName(PathKind::TwinVisit), "twin-visit");
}

// ----------------------------------------------------------------------------------------------------------
TEST(SyntheticSequence, RendersGivenPosesInsteadOfThePath) {
    const auto dir = test::makeTempDir("synth_given_poses");
    const auto scene = SyntheticScene::twinGroups();
    const std::vector<Pose> path = cameraPath(40, PathKind::TwinVisit);
    SequenceOptions options;
    options.frames = 40;  // ignored: the poses say how many
    options.width = 32;
    options.height = 24;
    options.intrinsics = kinectIntrinsics(32, 24);
    options.gtPointSpacing = 0.2;
    options.poses = {path[0], path[5], path[33]};  // a kidnapped camera: frames cut out
    writeTumSequence(dir, scene, options);

    EXPECT_EQ(readDataLines(dir / "depth.txt").size(), 3u);
    EXPECT_EQ(readDataLines(dir / "rgb.txt").size(), 3u);
    const auto groundTruth = readDataLines(dir / "groundtruth.txt");
    ASSERT_EQ(groundTruth.size(), 3u);
    for (size_t frame = 0; frame < 3; ++frame) {
        const Eigen::Vector3d t(std::stod(groundTruth[frame][1]), std::stod(groundTruth[frame][2]),
                                std::stod(groundTruth[frame][3]));
        EXPECT_LT((t - options.poses[frame].topRightCorner<3, 1>()).cwiseAbs().maxCoeff(), 1e-8) << frame;
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "depth" / "000003.png"));
    const cv::Mat png = cv::imread((dir / "depth" / "000002.png").string(), cv::IMREAD_UNCHANGED);
    const DepthImage expected = scene.renderDepth(options.intrinsics, options.poses[2]);
    ASSERT_EQ(png.type(), CV_16UC1);
    int mismatches = 0;
    for (int v = 0; v < 24; ++v)
        for (int u = 0; u < 32; ++u)
            mismatches += png.at<uint16_t>(v, u) != static_cast<uint16_t>(std::lround(expected.at(u, v) * 5000.0));
    EXPECT_EQ(mismatches, 0);
    std::filesystem::remove_all(dir);
}

// ----------------------------------------------------------------------------------------------------------
TEST(SyntheticSequence, WritesTumLayoutWithGroundTruth) {
    const auto dir = test::makeTempDir("synth_sequence");
    const auto scene = SyntheticScene::defaultRoom();
    SequenceOptions options;
    options.frames = 4;
    options.width = 64;
    options.height = 48;
    options.intrinsics = kinectIntrinsics(64, 48);
    options.gtPointSpacing = 0.02;  // coarse, to keep the test quick
    writeTumSequence(dir, scene, options);

    for (const char* file : {"depth.txt", "groundtruth.txt", "camera.json", "gt_points.ply", "scene.json", "README.txt"})
        EXPECT_TRUE(std::filesystem::is_regular_file(dir / file)) << file;

    const auto camera = nlohmann::json::parse(std::ifstream(dir / "camera.json"));
    EXPECT_FLOAT_EQ(camera.at("fx").get<float>(), options.intrinsics.fx);
    EXPECT_FLOAT_EQ(camera.at("fy").get<float>(), options.intrinsics.fy);
    EXPECT_FLOAT_EQ(camera.at("cx").get<float>(), options.intrinsics.cx);
    EXPECT_FLOAT_EQ(camera.at("cy").get<float>(), options.intrinsics.cy);
    EXPECT_EQ(camera.at("depth_scale").get<double>(), 5000.0);
    EXPECT_EQ(camera.at("width").get<int>(), 64);
    EXPECT_EQ(camera.at("height").get<int>(), 48);

    const auto sceneDescription = nlohmann::json::parse(std::ifstream(dir / "scene.json"));
    ASSERT_EQ(sceneDescription.at("objects").size(), scene.objects().size());
    EXPECT_EQ(sceneDescription.at("objects")[1].at("name"), "sphere");
    EXPECT_NEAR(sceneDescription.at("objects")[1].at("radius").get<double>(), 0.35, 1e-12);

    const auto depthIndex = readDataLines(dir / "depth.txt");
    const auto groundTruth = readDataLines(dir / "groundtruth.txt");
    ASSERT_EQ(depthIndex.size(), 4u);
    ASSERT_EQ(groundTruth.size(), 4u);
    const std::vector<Pose> poses = cameraPath(4, PathKind::Orbit);
    for (size_t frame = 0; frame < 4; ++frame) {
        const double timestamp = 1.0 + 0.033 * frame;
        ASSERT_EQ(depthIndex[frame].size(), 2u);
        EXPECT_NEAR(std::stod(depthIndex[frame][0]), timestamp, 1e-9);
        char name[32];
        std::snprintf(name, sizeof name, "depth/%06zu.png", frame);
        EXPECT_EQ(depthIndex[frame][1], name);

        // groundtruth.txt reproduces the pose.
        ASSERT_EQ(groundTruth[frame].size(), 8u);
        EXPECT_NEAR(std::stod(groundTruth[frame][0]), timestamp, 1e-9);
        const Eigen::Vector3d t(std::stod(groundTruth[frame][1]), std::stod(groundTruth[frame][2]),
                                std::stod(groundTruth[frame][3]));
        const Eigen::Quaterniond q(std::stod(groundTruth[frame][7]), std::stod(groundTruth[frame][4]),
                                   std::stod(groundTruth[frame][5]), std::stod(groundTruth[frame][6]));
        EXPECT_NEAR(q.norm(), 1.0, 1e-8);
        EXPECT_LT((t - poses[frame].topRightCorner<3, 1>()).cwiseAbs().maxCoeff(), 1e-8);
        EXPECT_LT((q.normalized().toRotationMatrix() - poses[frame].topLeftCorner<3, 3>()).cwiseAbs().maxCoeff(), 1e-8);

        // The PNG holds round(depth * 5000) of the clean render from that pose.
        const cv::Mat png = cv::imread((dir / name).string(), cv::IMREAD_UNCHANGED);
        ASSERT_EQ(png.type(), CV_16UC1);
        ASSERT_EQ(png.cols, 64);
        ASSERT_EQ(png.rows, 48);
        const DepthImage expected = scene.renderDepth(options.intrinsics, poses[frame]);
        int mismatches = 0, valid = 0;
        for (int v = 0; v < 48; ++v) {
            for (int u = 0; u < 64; ++u) {
                const auto raw = png.at<uint16_t>(v, u);
                valid += raw > 0;
                mismatches += raw != static_cast<uint16_t>(std::lround(expected.at(u, v) * 5000.0));
            }
        }
        EXPECT_EQ(mismatches, 0) << name;
        EXPECT_GE(valid, 0.9 * 64 * 48) << name;
    }

    // The ground-truth points lie on the surface, with unit normals agreeing with the SDF's gradient.
    const PlyPoints points = readGroundTruthPly(dir / "gt_points.ply");
    ASSERT_GT(points.positions.size(), 10000u);
    size_t normalsAgreeing = 0, onSphere = 0;
    const Object& sphere = scene.object("sphere");
    for (size_t i = 0; i < points.positions.size(); ++i) {
        ASSERT_LT(std::abs(scene.sdf(points.positions[i])), 1e-3) << points.positions[i].transpose();
        EXPECT_NEAR(points.normals[i].norm(), 1.0, 1e-5);
        normalsAgreeing += points.normals[i].dot(scene.normal(points.positions[i])) > 0.95;
        onSphere += std::abs(sphere.sdf(points.positions[i])) < 1e-5;
    }
    EXPECT_GT(normalsAgreeing, points.positions.size() * 98 / 100);
    // Uniform by area: the sphere gets its area / spacing^2 samples.
    const double sphereArea = 4 * std::numbers::pi * sphere.radius * sphere.radius;
    EXPECT_NEAR(static_cast<double>(onSphere), sphereArea / (0.02 * 0.02), 0.02 * sphereArea / (0.02 * 0.02));

    // Every GT point carries the exact colour of the scene there, and every object's colours show up.
    std::set<Rgb> seenColors;
    size_t colorMismatches = 0;
    for (size_t i = 0; i < points.positions.size(); ++i) {
        // The file holds float positions: a point within float rounding (~0.1 um) of a band edge may read
        // the other band, so a handful may differ; the textures' offsets keep that rare.
        colorMismatches += points.colors[i] != scene.color(points.positions[i]);
        seenColors.insert(points.colors[i]);
    }
    EXPECT_LE(colorMismatches, points.positions.size() / 1000) << colorMismatches << " of " << points.positions.size();
    for (const Object& object : scene.objects()) {
        EXPECT_TRUE(seenColors.count(object.texture.a)) << object.name;
        EXPECT_TRUE(seenColors.count(object.texture.b)) << object.name;
    }

    // rgb.txt lists one colour image per depth frame, with its timestamp; the image is the clean render's colour.
    const auto rgbIndex = readDataLines(dir / "rgb.txt");
    ASSERT_EQ(rgbIndex.size(), 4u);
    for (size_t frame = 0; frame < 4; ++frame) {
        EXPECT_EQ(rgbIndex[frame][0], depthIndex[frame][0]);
        char name[32];
        std::snprintf(name, sizeof name, "rgb/%06zu.png", frame);
        EXPECT_EQ(rgbIndex[frame][1], name);
        const cv::Mat png = cv::imread((dir / name).string(), cv::IMREAD_UNCHANGED);
        ASSERT_EQ(png.type(), CV_8UC3);
        ColorImage expected;
        scene.renderDepth(options.intrinsics, poses[frame], {}, &expected);
        for (int v = 0; v < 48; ++v)
            for (int u = 0; u < 64; ++u) {
                const cv::Vec3b bgr = png.at<cv::Vec3b>(v, u);
                ASSERT_EQ(bgr[2], expected.at(u, v)[0]) << name << " " << u << "," << v;
                ASSERT_EQ(bgr[1], expected.at(u, v)[1]);
                ASSERT_EQ(bgr[0], expected.at(u, v)[2]);
            }
    }
    std::filesystem::remove_all(dir);
}

TEST(SyntheticColor, PixelColourIsTheTextureAtTheHitPoint) {
    const auto scene = SyntheticScene::defaultRoom();
    const Intrinsics k = kinectIntrinsics(160, 120);
    const Pose pose = cameraPath(12)[5];
    ColorImage color;
    const DepthImage depth = scene.renderDepth(k, pose, {}, &color);
    // The depth is the same with or without colour.
    EXPECT_EQ(depth.meters, scene.renderDepth(k, pose).meters);
    ASSERT_EQ(color.width, 160);
    ASSERT_EQ(color.height, 120);
    size_t checked = 0, agreeing = 0;
    std::set<std::string> objectsSeen;
    for (int v = 0; v < k.height; ++v)
        for (int u = 0; u < k.width; ++u) {
            const float z = depth.at(u, v);
            if (z <= 0) {
                EXPECT_EQ(color.at(u, v)[0] + color.at(u, v)[1] + color.at(u, v)[2], 0);  // nothing hit: black
                continue;
            }
            // The back-projected float depth is within ~0.1 um of the hit: off by a band only at a band edge.
            const Eigen::Vector3d p = toWorld(pose, backProject(k, u, v, z));
            const Rgb texture = scene.color(p);
            ++checked;
            agreeing += Rgb{color.at(u, v)[0], color.at(u, v)[1], color.at(u, v)[2]} == texture;
            for (const Object& object : scene.objects())
                if (std::abs(object.sdf(p)) < 1e-4) objectsSeen.insert(object.name);
        }
    EXPECT_GT(checked, size_t(0.9 * 160 * 120));
    EXPECT_GE(agreeing, checked * 998 / 1000) << agreeing << " of " << checked;
    EXPECT_GE(objectsSeen.size(), 5u);

    // Texture patterns: stripes across their axis, a 3D checker, each band `period` wide.
    const Texture stripes{Texture::Pattern::Stripes, 0.01, 2, 0, {1, 1, 1}, {2, 2, 2}};
    EXPECT_EQ(stripes.at({5, 5, 0.005}), (Rgb{1, 1, 1}));
    EXPECT_EQ(stripes.at({-5, 3, 0.015}), (Rgb{2, 2, 2}));
    EXPECT_EQ(stripes.at({0, 0, -0.005}), (Rgb{2, 2, 2}));
    const Texture checker{Texture::Pattern::Checker, 0.5, 2, 0, {1, 1, 1}, {2, 2, 2}};
    EXPECT_EQ(checker.at({0.25, 0.25, 0.25}), (Rgb{1, 1, 1}));
    EXPECT_EQ(checker.at({0.75, 0.25, 0.25}), (Rgb{2, 2, 2}));
    EXPECT_EQ(checker.at({0.75, 0.75, 0.25}), (Rgb{1, 1, 1}));
}

TEST(SyntheticColor, ExposureAndNoiseAreDeterministic) {
    const auto scene = SyntheticScene::defaultRoom();
    const Intrinsics k = kinectIntrinsics(64, 48);
    const Pose pose = cameraPath(8)[2];
    ColorImage clean, bright, noisy, noisyAgain, otherSeed;
    scene.renderDepth(k, pose, {}, &clean);
    RenderOptions options;
    options.exposure = 1.2;
    scene.renderDepth(k, pose, options, &bright);
    for (size_t i = 0; i < clean.rgb.size(); ++i)
        ASSERT_EQ(bright.rgb[i], uint8_t(std::min(255.0, std::round(clean.rgb[i] * 1.2)))) << i;
    options = {};
    options.colorNoise = 5;
    options.seed = 7;
    const DepthImage depthNoisy = scene.renderDepth(k, pose, options, &noisy);
    scene.renderDepth(k, pose, options, &noisyAgain);
    EXPECT_EQ(noisy.rgb, noisyAgain.rgb);
    EXPECT_EQ(depthNoisy.meters, scene.renderDepth(k, pose).meters);  // colour noise leaves depth alone
    options.seed = 8;
    scene.renderDepth(k, pose, options, &otherSeed);
    EXPECT_NE(noisy.rgb, otherSeed.rgb);
    double sum = 0, sum2 = 0;
    size_t n = 0;
    for (size_t i = 0; i < clean.rgb.size(); ++i) {
        if (clean.rgb[i] < 30 || clean.rgb[i] > 225) continue;  // away from clamping
        const double d = double(noisy.rgb[i]) - double(clean.rgb[i]);
        sum += d, sum2 += d * d, ++n;
    }
    ASSERT_GT(n, 1000u);
    EXPECT_NEAR(sum / n, 0, 0.5);
    EXPECT_NEAR(std::sqrt(sum2 / n), 5.0, 0.5);  // sigma 5 (plus rounding, 1/12)
}

TEST(SyntheticSequence, ReportsBadOptions) {
    const auto dir = test::makeTempDir("synth_errors");
    const auto scene = SyntheticScene::singleSphere({0, 0, 0.6}, 0.3);
    SequenceOptions options;
    options.frames = 2;
    options.width = 16;
    options.height = 12;
    options.intrinsics = kinectIntrinsics(16, 12);
    options.gtPointSpacing = 0.05;

    auto messageOf = [&](const std::filesystem::path& where, const SequenceOptions& o) -> std::string {
        try {
            writeTumSequence(where, scene, o);
        } catch (const Error& e) {
            return e.what();
        }
        return "";
    };
    SequenceOptions noFrames = options;
    noFrames.frames = 0;
    EXPECT_NE(messageOf(dir / "a", noFrames).find("frames"), std::string::npos);

    SequenceOptions badFocal = options;
    badFocal.intrinsics.fx = 0;
    EXPECT_NE(messageOf(dir / "b", badFocal).find("fx"), std::string::npos);

    SequenceOptions mismatched = options;
    mismatched.width = 640;
    EXPECT_NE(messageOf(dir / "c", mismatched).find("640"), std::string::npos);

    SequenceOptions badColor = options;
    badColor.colorNoise = -1;
    EXPECT_NE(messageOf(dir / "d", badColor).find("colour noise"), std::string::npos);
    badColor = options;
    badColor.exposureDrift = 1.5;
    EXPECT_NE(messageOf(dir / "e", badColor).find("exposure drift"), std::string::npos);

    // A folder that cannot be created: its parent is a regular file.
    std::ofstream(dir / "blocker") << "not a folder";
    const std::string message = messageOf(dir / "blocker" / "sequence", options);
    EXPECT_NE(message.find((dir / "blocker").string()), std::string::npos) << message;
    std::filesystem::remove_all(dir);
}
