// Paging (docs/PAGING.md, GpuVolumeConfig::residentBlocks): a volume that keeps at most N blocks in GPU memory and
// the rest on the host ends with the map and the mesh of the volume that keeps them all, bit for bit (TSDF and colour
// words by coordinate, the triangle set, every vertex's position bits, age, refcount and colour), with blocks moved
// out and back in on the way; a correction of frames whose blocks are paged out gives the unpaged corrected map; a
// budget below what the view reaches keeps what it reaches and says so; settings that forget are refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>

#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "map_state.h"
#include "mesh_checks.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using test::GpuTest;
namespace fs = std::filesystem;

constexpr size_t kGalleryLap = 40;

// The gallery (a 13 m hall, the camera circling its middle looking outward at the walls, kGalleryLap frames a lap)
// or the room's orbit (24 frames a lap, looking inward), noisy, at 160 x 120.
struct Sequence {
    bool gallery = true;
    const synth::SyntheticScene& scene() const {
        static const synth::SyntheticScene hall = synth::SyntheticScene::gallery(), room = synth::SyntheticScene::defaultRoom();
        return gallery ? hall : room;
    }
    Intrinsics intrinsics() const { return synth::kinectIntrinsics(160, 120); }
    Pose pose(size_t i) const {
        static const auto hall = synth::cameraPath(kGalleryLap, synth::PathKind::GalleryLoop), room = synth::cameraPath(24, synth::PathKind::Orbit);
        const auto& poses = gallery ? hall : room;
        return poses[i % poses.size()];
    }
    DepthImage frame(size_t i, ColorImage& color) const {
        synth::RenderOptions options;
        options.noise = true;
        options.seed = uint32_t(i + 1);
        return scene().renderDepth(intrinsics(), pose(i), options, &color);
    }
};

struct PagingTotals {
    uint32_t in = 0, out = 0, peakPaged = 0, framesOverBudget = 0;
    uint64_t bytesIn = 0, bytesOut = 0;
    std::vector<std::string> warnings;
    void add(const gpu::FrameReport& r) {
        in += r.paging.blocksIn;
        out += r.paging.blocksOut;
        bytesIn += r.paging.bytesIn;
        bytesOut += r.paging.bytesOut;
        framesOverBudget += r.paging.overBudget > 0;
        peakPaged = std::max(peakPaged, r.paging.blocksPaged);
        warnings.insert(warnings.end(), r.warnings.begin(), r.warnings.end());
    }
};

PagingTotals fuse(gpu::GpuVolume& volume, const Sequence& s, size_t from, size_t to) {
    PagingTotals t;
    for (size_t i = from; i < to; ++i) {
        ColorImage color;
        const DepthImage depth = s.frame(i, color);
        t.add(volume.integrate(depth, &color, s.intrinsics(), s.pose(i)));
    }
    return t;
}

gpu::GpuVolumeConfig galleryConfig() {
    gpu::GpuVolumeConfig c = test::smallRoomConfig();   // 4 cm voxels
    c.params.maxDepth = 4.0f;
    return c;
}

// Brings every paged block back (the camera at every pose of a lap reaches all of them), for the checks that read
// the whole map from the GPU.
void pageEverythingIn(gpu::GpuVolume& volume, const Sequence& s) {
    for (size_t i = 0; i < kGalleryLap && volume.pagedBlocks() > 0; ++i) (void)volume.pageInView(s.pose(i), s.intrinsics());
    ASSERT_EQ(volume.pagedBlocks(), 0u);
}

TEST_F(GpuTest, TheGalleryPagedAtHalfItsBlocksIsTheUnpagedOneBitForBit) {
    const Sequence gallery;
    gpu::GpuVolumeConfig config = galleryConfig();
    gpu::GpuVolume whole(context(), config);
    EXPECT_TRUE(fuse(whole, gallery, 0, 50).warnings.empty());
    const uint32_t blocks = whole.readCounters().blocksInUse;
    ASSERT_GT(blocks, 2000u);

    config.residentBlocks = blocks / 2;
    gpu::GpuVolume paged(context(), config);
    const PagingTotals t = fuse(paged, gallery, 0, 50);   // a lap and a quarter: the first walls come back
    const gpu::Counters k = paged.readCounters();
    std::printf("%u blocks, budget %u: %u paged out, %u in (%.1f / %.1f MB), at most %u on the host, %u at the end, %u resident\n", blocks,
                config.residentBlocks, t.out, t.in, t.bytesOut / 1e6, t.bytesIn / 1e6, t.peakPaged, unsigned(paged.pagedBlocks()), k.blocksInUse);
    EXPECT_TRUE(t.warnings.empty()) << t.warnings.front();
    EXPECT_EQ(t.framesOverBudget, 0u) << "the camera reaches a sector of the hall: the budget holds";
    EXPECT_LE(k.blocksInUse, config.residentBlocks);
    EXPECT_GT(t.out, blocks / 2) << "blocks were paged out";
    EXPECT_GT(t.in, 200u) << "the second lap brought the first walls back";
    EXPECT_EQ(k.blocksInUse + paged.pagedBlocks(), blocks) << "every block resident or on the host, none twice";
    test::expectSameState(test::stateOf(whole), test::stateOf(paged));
    EXPECT_THROW(paged.saveMap(), Error) << "saving paged blocks is not built: refused, not a map without them";

    // Everything back: the mesh's invariants hold on the GPU (every vertex's owner points back at its edge slot, at
    // the block's new place in the pool), and the map is still the unpaged one.
    pageEverythingIn(paged, gallery);
    const auto problems = test::checkInvariants(paged.downloadMeshState(), paged.config());
    EXPECT_TRUE(problems.empty()) << problems.front();
    test::expectSameState(test::stateOf(whole), test::stateOf(paged));
}

TEST_F(GpuTest, CorrectingFramesWhoseBlocksArePagedOutGivesTheUnpagedCorrection) {
    const Sequence gallery;
    gpu::GpuVolumeConfig config = galleryConfig();
    gpu::GpuVolume whole(context(), config);
    fuse(whole, gallery, 0, 30);
    config.residentBlocks = whole.readCounters().blocksInUse / 2;
    gpu::GpuVolume paged(context(), config);
    fuse(paged, gallery, 0, 30);
    ASSERT_GT(paged.pagedBlocks(), 0u);
    // Frames 2-5, far behind the camera by frame 30: taken out at their poses and fused again 2 cm and 1 degree off.
    Pose shift = Pose::Identity();
    shift.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.0175, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    shift.topRightCorner<3, 1>() = Eigen::Vector3d(0.02, 0.0, 0.0);
    PagingTotals t;
    for (gpu::GpuVolume* v : {&whole, &paged}) {
        for (size_t i = 2; i < 6; ++i) {
            ColorImage color;
            const DepthImage depth = gallery.frame(i, color);
            const gpu::FrameReport out = v->deintegrate(depth, &color, gallery.intrinsics(), gallery.pose(i));
            EXPECT_EQ(out.counters.observationsDropped, 0u) << "the map held frame " << i;
            const gpu::FrameReport in = v->integrate(depth, &color, gallery.intrinsics(), shift * gallery.pose(i));
            if (v == &paged) t.add(out), t.add(in);
        }
    }
    EXPECT_GT(t.in, 100u) << "the corrected frames' blocks came back";
    fuse(whole, gallery, 30, 34);
    fuse(paged, gallery, 30, 34);
    test::expectSameState(test::stateOf(whole), test::stateOf(paged));
}

TEST_F(GpuTest, ABudgetBelowWhatTheViewReachesKeepsWhatItReachesAndSaysSoOnce) {
    // The room's orbit looks inward: the camera reaches most of the room, so most of it stays resident; the rest
    // goes out and comes back as the orbit (24 frames a lap) brings the far side into view. (Also CI's GPU-assisted validation run of the paging
    // passes: scripts/ci/20-portability.sh.)
    const Sequence room{false};
    gpu::GpuVolumeConfig config = test::smallRoomConfig();
    gpu::GpuVolume whole(context(), config);
    fuse(whole, room, 0, 10);
    config.residentBlocks = 10;
    gpu::GpuVolume paged(context(), config);
    const PagingTotals t = fuse(paged, room, 0, 10);
    std::printf("%u blocks out, %u in, %u frames over budget\n", t.out, t.in, t.framesOverBudget);
    ASSERT_EQ(t.warnings.size(), 1u);
    EXPECT_NE(t.warnings[0].find("--resident-blocks 10 is below what the view needs"), std::string::npos) << t.warnings[0];
    EXPECT_EQ(t.framesOverBudget, 10u);
    EXPECT_GT(t.out, 0u);
    EXPECT_GT(t.in, 0u);
    test::expectSameState(test::stateOf(whole), test::stateOf(paged));
}

TEST(PagingSettings, TheCliRefusesWhatPagingCannotDo) {
    const fs::path seq = test::makeMinimalTum("paging_options");   // refused before any frame is read
    const std::pair<const char*, const char*> refused[] = {
        {"--resident-blocks 0", "--resident-blocks 0: give the number of blocks"},
        {"--resident-blocks 100 --save m.vkmap", "saving the blocks paged out"},
        {"--resident-blocks 100 --keep-radius 2", "choose one"},
        {"--resident-blocks 100 --mode baseline", "needs the incremental mesh"},
    };
    for (const auto& [options, says] : refused) {
        const test::CliRun r = test::runCli("fuse " + seq.string() + " " + options + " -o /dev/null");
        EXPECT_NE(r.exitCode, 0) << options;
        EXPECT_NE(r.err.find(says), std::string::npos) << options << ": " << r.err;
    }
}

TEST(PagingSettings, SettingsThatForgetBlocksAreRefused) {
    gpu::GpuVolumeConfig config = test::smallRoomConfig();
    config.residentBlocks = 100;
    config.keepRadius = 2.0f;
    EXPECT_THROW(gpu::resolveConfig(config), Error);
    config.keepRadius = 0;
    config.recycle = true;
    EXPECT_THROW(gpu::resolveConfig(config), Error);
    config.recycle = false;
    EXPECT_NO_THROW(gpu::resolveConfig(config));
}

}  // namespace
}  // namespace vkmesh
