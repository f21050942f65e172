// Sessions of one place (docs/SCALING.md, "Sessions of one place"; `vkmesh merge --register`): two maps saved in
// world frames of their own are registered by the frames their stores keep and joined into the map of every frame at
// the registered poses. Real data: ICL-NUIM office 0 (../shared/datasets), cut into two sessions that see a common
// part of the room from different images.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <tuple>

#include "api/exported_mesh.h"
#include "api/mapper.h"
#include "core/camera.h"
#include "core/icp_solve.h"
#include "core/map_format.h"
#include "core/mesh_analysis.h"
#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "io/dataset.h"
#include "mesh_checks.h"
#include "slam/session_join.h"
#include "test_support.h"

namespace vkmesh {
namespace {

namespace fs = std::filesystem;
using test::GpuTest;

constexpr float kVoxel = 0.04f;

// A rigid motion: `degrees` about z, then a translation.
Pose motion(double degrees, const Eigen::Vector3d& t) {
    Pose p = Pose::Identity();
    p.block<3, 3>(0, 0) = Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    p.block<3, 1>(0, 3) = t;
    return p;
}

struct SessionFrame {
    size_t frame;   // in the dataset
    Pose pose;      // as fused
};

// Frames of `dataset` fused by one Mapper at the poses given (with their colour, kept in the frame store), saved at `path`.
void fuse(const vk::Context& context, const Dataset& dataset, const std::vector<SessionFrame>& frames, const fs::path& path) {
    MapperOptions options;
    options.volume.params.voxelSize = kVoxel;
    options.volume.imageWidth = options.volume.imageHeight = 0;
    Mapper mapper(context, options);
    mapper.keepFrames(FrameStore());
    uint32_t index = 0;
    for (const SessionFrame& f : frames) {
        const DepthImage depth = dataset.loadDepth(f.frame);
        const ColorImage color = dataset.loadColor(f.frame, nullptr, &depth);
        MapperFrame in;
        in.index = index++;
        in.timestamp = double(f.frame);   // one timestamp per dataset frame, in either session
        in.depth = &depth;
        in.color = &color;
        in.intrinsics = dataset.intrinsics();
        in.pose = f.pose;
        ASSERT_TRUE(mapper.process(in).isFused()) << "frame " << f.frame;
    }
    mapper.finish();
    mapper.save(path);
}

// The observed blocks' step sums and counts, by coordinate (a block no frame observed carries nothing).
using Corners = std::map<std::tuple<int, int, int>, std::pair<std::vector<int32_t>, std::vector<float>>>;
Corners observedCorners(const gpu::GpuVolume& volume) {
    Corners out;
    for (auto& b : volume.downloadBlocks()) {
        bool observed = false;
        for (float w : b.weight) observed = observed || w > 0;
        if (observed) out[{b.coord.x(), b.coord.y(), b.coord.z()}] = {b.sdfSum, b.weight};
    }
    return out;
}

class SessionJoinTest : public GpuTest {};

// Session 1: frames 60, 63, ..., 138 at their true poses. Session 2: frames 121, 124, ..., 199 in a world turned
// 30 degrees and moved 1.1 m (as if its camera had started elsewhere): other images of a part of the room both saw.
// Joined, the second session's frames land within 5 mm and 0.3 degrees of the truth (measured at every second frame:
// 0.3 mm, 19 of 20 verified pairs agree), and the joined map is the map of one run fusing every frame at the registered poses: the
// same observed TSDF bits and triangles.
TEST_F(SessionJoinTest, IclSessionsInTwoWorldFramesAreJoinedWhereTheyBelong) {
    const auto root = test::sharedDatasetsDir();
    if (!root) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    const auto dataset = Dataset::open(*root / "iclnuim_office_traj0");
    const fs::path d = test::makeTempDir("sessions_icl");
    const Pose elsewhere = motion(30.0, {1.0, -0.5, 0.2});   // the second session's world -> the true one's inverse
    std::vector<SessionFrame> first, second;
    for (size_t f = 60; f <= 138; f += 3) first.push_back({f, dataset->frame(f).cameraToWorld});
    for (size_t f = 121; f <= 199; f += 3) second.push_back({f, elsewhere * dataset->frame(f).cameraToWorld});
    fuse(context(), *dataset, first, d / "first.vkmap");
    fuse(context(), *dataset, second, d / "second.vkmap");

    slam::JoinOptions options;
    options.merge.returnMesh = true;
    const slam::JoinReport report = slam::joinSessions(context(), {d / "first.vkmap", d / "second.vkmap"}, d / "joined.vkmap", options);
    ASSERT_EQ(report.registrations.size(), 1u);
    const slam::SessionRegistration& r = report.registrations[0];
    const Pose error = r.secondToFirst * elsewhere;   // identity when the transform is the truth
    EXPECT_LT(translationMetres(error), 0.005);
    EXPECT_LT(rotationDegrees(error), 0.3);
    EXPECT_GE(r.agreeing, 5u) << r.verified << " verified of " << r.registrations;
    EXPECT_EQ(report.framesMoved, second.size());
    EXPECT_EQ(report.merge.framesIntegrated, first.size() + second.size());
    EXPECT_EQ(report.merge.framesStored, first.size() + second.size());
    for (const auto& p : {d / "joined.vkmap.session2.vkmap", d / "joined.vkmap.session2.vkframes"})
        EXPECT_FALSE(fs::exists(p)) << p << ": the moved session is not left behind";

    // The one run: every frame at the pose the join gave it.
    std::vector<SessionFrame> all = first;
    for (const SessionFrame& f : second) all.push_back({f.frame, r.secondToFirst * f.pose});
    fuse(context(), *dataset, all, d / "one.vkmap");
    const auto one = gpu::GpuVolume::load(context(), d / "one.vkmap");
    const auto joined = gpu::GpuVolume::load(context(), d / "joined.vkmap");
    const Corners oneCorners = observedCorners(*one), joinedCorners = observedCorners(*joined);
    EXPECT_GT(oneCorners.size(), 500u);
    EXPECT_TRUE(oneCorners == joinedCorners) << oneCorners.size() << " and " << joinedCorners.size() << " observed blocks";
    const auto oneTriangles = canonicalTriangles(test::soupOf(one->exportMesh()));
    const auto joinedTriangles = canonicalTriangles(test::soupOf(joined->exportMesh()));
    EXPECT_GT(oneTriangles.size(), 20000u);
    EXPECT_EQ(countTriangleMismatches(oneTriangles, joinedTriangles, 0), 0u);
    fs::remove_all(d);
}

// Two places that have nothing in common (ICL-NUIM's office and TUM fr1/rpy's desk, same camera size) are not joined:
// the error says how many pairs were tried and verified, and nothing is written. A map without its frame store is
// refused naming it.
TEST_F(SessionJoinTest, SessionsOfDifferentPlacesAreRefused) {
    const auto root = test::sharedDatasetsDir();
    if (!root) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    const auto office = Dataset::open(*root / "iclnuim_office_traj0");
    const auto desk = Dataset::open(*root / "tum_fr1_rpy");
    const fs::path d = test::makeTempDir("sessions_apart");
    std::vector<SessionFrame> a, b;
    for (size_t f = 0; f < 24; f += 2) a.push_back({f, office->frame(f).cameraToWorld});
    for (size_t f = 0; f < 24; f += 2) b.push_back({f, desk->frame(f).cameraToWorld});
    fuse(context(), *office, a, d / "office.vkmap");
    fuse(context(), *desk, b, d / "desk.vkmap");

    const slam::JoinOptions options;
    try {
        slam::joinSessions(context(), {d / "office.vkmap", d / "desk.vkmap"}, d / "joined.vkmap", options);
        ADD_FAILURE() << "two different places were joined";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("desk.vkmap"), std::string::npos) << what;
        EXPECT_NE(what.find("could not be registered"), std::string::npos) << what;
        EXPECT_NE(what.find("pairs registered"), std::string::npos) << what;
    }
    EXPECT_FALSE(fs::exists(d / "joined.vkmap"));

    fs::remove(d / "desk.vkframes");
    try {
        slam::joinSessions(context(), {d / "office.vkmap", d / "desk.vkmap"}, d / "joined.vkmap", options);
        ADD_FAILURE() << "a map without its frames was joined";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("desk.vkmap has no frame store"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(d / "joined.vkmap"));
    fs::remove_all(d);
}

}  // namespace
}  // namespace vkmesh
