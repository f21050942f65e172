// Exact de-integration (docs/CORRECTION.md): a frame taken out of the map at the pose it was fused at restores
// every corner's bits; the GPU against the CPU reference; every frame taken out in another order leaves an empty
// map with whole free lists; and a map fused at drifted poses, corrected frame by frame to the true poses, equals
// the map fused at the true poses from the start (TSDF bits, triangle set, vertex positions).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <tuple>

#include <Eigen/Geometry>

#include "core/mesh_analysis.h"
#include "cpu/reference_volume.h"
#include "gpu/gpu_volume.h"
#include "gpu/map_corrector.h"
#include "gpu_fixture.h"
#include "mesh_checks.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using test::GpuTest;

constexpr int kWidth = 160, kHeight = 120;

struct Frame {
    DepthImage depth;
    ColorImage color;
    Pose pose;
};

// Noisy frames of the synthetic room along an orbit, with the textures' colour.
std::vector<Frame> roomFrames(size_t count) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    const auto path = synth::cameraPath(24, synth::PathKind::Orbit);
    std::vector<Frame> frames;
    for (size_t i = 0; i < count; ++i) {
        synth::RenderOptions options;
        options.noise = true;
        options.seed = uint32_t(i + 1);
        Frame f;
        f.pose = path[i * 2 % path.size()];
        f.depth = scene.renderDepth(intr, f.pose, options, &f.color);
        frames.push_back(std::move(f));
    }
    return frames;
}

Intrinsics intrinsics() { return synth::kinectIntrinsics(kWidth, kHeight); }

// A slow drift, as a tracker's: frame i's pose turned by i x 0.4 degrees about a tilted axis and moved by i x 6 mm.
Pose drifted(const Pose& truth, size_t i) {
    Pose drift = Pose::Identity();
    drift.topLeftCorner<3, 3>() = Eigen::AngleAxisd(double(i) * 0.4 * M_PI / 180.0, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
    drift.topRightCorner<3, 1>() = double(i) * Eigen::Vector3d(0.006, -0.002, 0.003);
    return drift * truth;
}

// Every live block's corners as stored (step sums, weights) and colour words, by coordinate. A block without
// an observation holds nothing, and whether one is live depends on the order of the frames, not on what they
// fused: allocation by tiles claims blocks around a slab that no corner update may reach, and a de-integrating
// frame frees the empty blocks it touches, also those another frame's slab claimed. Such blocks are left out
// unless `withEmpty` (against the CPU reference, which allocates and frees alike).
using Corners = std::map<std::tuple<int, int, int>, std::tuple<std::vector<int32_t>, std::vector<float>, std::vector<uint32_t>>>;
Corners cornersOf(const gpu::GpuVolume& volume, bool withEmpty = false) {
    Corners out;
    for (auto& b : volume.downloadBlocks())
        if (withEmpty || std::any_of(b.weight.begin(), b.weight.end(), [](float w) { return w != 0.0f; }))
            out[{b.coord.x(), b.coord.y(), b.coord.z()}] = {b.sdfSum, b.weight, b.color};
    return out;
}

size_t differingBlocks(const Corners& a, const Corners& b, bool withColor) {
    size_t differing = 0;
    for (const auto& [coord, values] : a) {
        auto it = b.find(coord);
        if (it == b.end()) { ++differing; continue; }
        const bool same = std::get<0>(values) == std::get<0>(it->second) &&
                          std::memcmp(std::get<1>(values).data(), std::get<1>(it->second).data(), std::get<1>(values).size() * 4) == 0 &&
                          (!withColor || std::get<2>(values) == std::get<2>(it->second));
        differing += !same;
    }
    return differing + (b.size() > a.size() ? b.size() - a.size() : 0);
}

gpu::GpuVolumeConfig config(bool refine) {
    gpu::GpuVolumeConfig c = test::smallRoomConfig();
    c.refine = refine;
    c.blockCapacity = 1024;   // grows while the map is built: de-integration must find blocks that moved nowhere
    return c;
}

class DeintegrationTest : public GpuTest {};

TEST_F(DeintegrationTest, GpuMatchesTheCpuReferenceBitForBit) {
    const std::vector<Frame> frames = roomFrames(5);
    gpu::GpuVolumeConfig c = config(true);
    gpu::GpuVolume volume(context(), c);
    cpu::ReferenceVolume reference(c.params, c.minMeshWeight);
    for (const Frame& f : frames) {
        volume.integrate(f.depth, &f.color, intrinsics(), f.pose);
        reference.integrate(f.depth, intrinsics(), f.pose, &f.color);
    }
    for (size_t i : {1u, 3u}) {
        const gpu::FrameReport r = volume.deintegrate(frames[i].depth, &frames[i].color, intrinsics(), frames[i].pose);
        const cpu::ReferenceFrameStats s = reference.deintegrate(frames[i].depth, intrinsics(), frames[i].pose, &frames[i].color);
        EXPECT_EQ(r.counters.observationsDropped, 0u) << "the map holds frame " << i;
        EXPECT_EQ(s.observationsDropped, 0u);
        EXPECT_EQ(r.counters.updatedVoxels, s.updatedVoxels) << "frame " << i;
        EXPECT_GT(s.updatedVoxels, 10000u);
    }
    const Corners gpuCorners = cornersOf(volume, true);
    size_t compared = 0, differing = 0, colored = 0;
    for (const auto& [coord, block] : reference.blocks()) {
        auto it = gpuCorners.find({coord[0], coord[1], coord[2]});
        if (it == gpuCorners.end()) {
            // A block the de-integration emptied and the GPU freed is not in the reference either.
            ADD_FAILURE() << "block " << coord[0] << "," << coord[1] << "," << coord[2] << " missing on the GPU";
            continue;
        }
        const auto& [sums, weights, colors] = it->second;
        for (uint32_t v = 0; v < gpu::VOXELS_PER_BLOCK; ++v) {
            ++compared;
            differing += sums[v] != block.sdfSum[v] || weights[v] != block.weight[v] || colors[v] != block.color[v];
            colored += block.color[v] != 0;
        }
    }
    EXPECT_EQ(gpuCorners.size(), reference.blocks().size());
    EXPECT_EQ(differing, 0u) << "of " << compared << " corners";
    EXPECT_GT(colored, 10000u) << "colour was fused and folded out";
}

class RoundTripTest : public GpuTest, public ::testing::WithParamInterface<bool /* refine */> {};

TEST_P(RoundTripTest, EveryFrameTakenOutInAnotherOrderLeavesNothing) {
    const std::vector<Frame> frames = roomFrames(8);
    const gpu::GpuVolumeConfig c = config(GetParam());
    gpu::GpuVolume volume(context(), c);
    for (const Frame& f : frames) volume.integrate(f.depth, &f.color, intrinsics(), f.pose);
    const gpu::Counters full = volume.readCounters();
    ASSERT_GT(full.liveTriangles, 5000u);
    ASSERT_GT(full.blocksInUse, 100u);
    uint32_t freed = 0;
    for (size_t i : {5u, 0u, 7u, 2u, 4u, 1u, 6u, 3u}) {
        const gpu::FrameReport r = volume.deintegrate(frames[i].depth, &frames[i].color, intrinsics(), frames[i].pose);
        EXPECT_EQ(r.counters.observationsDropped, 0u) << "frame " << i;
        EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
        freed += r.counters.blocksFreed;
        const auto problems = test::checkInvariants(volume.downloadMeshState(), volume.config());
        EXPECT_TRUE(problems.empty()) << "after frame " << i << ": " << problems.front();
    }
    const gpu::Counters k = volume.readCounters();
    EXPECT_EQ(freed, full.blocksInUse) << "every block freed by the de-integration that emptied it";
    EXPECT_EQ(k.blocksInUse, 0u);
    EXPECT_EQ(k.freeTop, volume.config().blockCapacity) << "the block free list is whole";
    EXPECT_EQ(k.hashEntries, 0u);
    EXPECT_EQ(k.verticesInUse, 0u);
    EXPECT_EQ(k.vertexFreeTop, volume.config().vertexCapacity) << "the vertex free stack is whole";
    EXPECT_EQ(k.chunksInUse, 0u);
    EXPECT_EQ(k.chunkFreeTop, volume.config().chunkCapacity) << "the chunk free stack is whole";
    EXPECT_EQ(k.liveTriangles, 0u);
    EXPECT_TRUE(volume.downloadBlocks().empty());
    EXPECT_EQ(volume.exportMesh().triangles.size(), 0u);
    // The emptied map fuses again like a new one: the same corners as a fresh volume given the same frames.
    gpu::GpuVolume fresh(context(), c);
    for (size_t i : {2u, 6u}) {
        volume.integrate(frames[i].depth, &frames[i].color, intrinsics(), frames[i].pose);
        fresh.integrate(frames[i].depth, &frames[i].color, intrinsics(), frames[i].pose);
    }
    EXPECT_EQ(differingBlocks(cornersOf(volume), cornersOf(fresh), true), 0u);
}

INSTANTIATE_TEST_SUITE_P(Refine, RoundTripTest, ::testing::Bool(), [](const auto& info) { return info.param ? "Refined" : "Unrefined"; });

// The mesh as a set of triangles and the vertex positions (bits), order-free.
struct MeshState {
    std::vector<CanonicalTriangle> triangles;
    std::vector<std::array<uint32_t, 3>> positions;
};
MeshState meshOf(gpu::GpuVolume& volume) {
    MeshState m;
    const gpu::ExportedMesh mesh = volume.exportMesh();
    m.triangles = canonicalTriangles(test::soupOf(mesh));
    for (const gpu::Vertex& v : mesh.vertices) {
        std::array<uint32_t, 3> p;
        std::memcpy(p.data(), &v.px, 12);
        m.positions.push_back(p);
    }
    std::sort(m.positions.begin(), m.positions.end());
    return m;
}

class CorrectionTest : public GpuTest, public ::testing::WithParamInterface<std::tuple<bool /* refine */, bool /* tiles */>> {};

TEST_P(CorrectionTest, DriftedMapCorrectedToTheTruePosesEqualsTheTrueMap) {
    const std::vector<Frame> frames = roomFrames(10);
    gpu::GpuVolumeConfig c = config(std::get<0>(GetParam()));
    c.params.allocationTiles = std::get<1>(GetParam());   // with tiles: blocks no update reaches (cornersOf)
    c.params.colorFusion = ColorFusion::Off;   // colour is folded out within a bound, not exactly (docs/CORRECTION.md)
    gpu::GpuVolume truth(context(), c), corrected(context(), c);
    for (size_t i = 0; i < frames.size(); ++i) {
        truth.integrate(frames[i].depth, intrinsics(), frames[i].pose);
        corrected.integrate(frames[i].depth, intrinsics(), drifted(frames[i].pose, i));
    }
    const size_t before = differingBlocks(cornersOf(truth), cornersOf(corrected), false);
    ASSERT_GT(before, 50u) << "the drift changes the map";
    // Largest drift first, as Reconstructor::correct orders them; frame 0 did not drift.
    for (size_t i = frames.size() - 1; i >= 1; --i) {
        const gpu::FrameReport out = corrected.deintegrate(frames[i].depth, nullptr, intrinsics(), drifted(frames[i].pose, i));
        EXPECT_EQ(out.counters.observationsDropped, 0u);
        corrected.integrate(frames[i].depth, intrinsics(), frames[i].pose);
    }
    EXPECT_EQ(differingBlocks(cornersOf(truth), cornersOf(corrected), false), 0u) << "TSDF bits (sums and weights)";
    const MeshState a = meshOf(truth), b = meshOf(corrected);
    EXPECT_GT(a.triangles.size(), 3000u);
    EXPECT_EQ(a.triangles.size(), b.triangles.size());
    EXPECT_EQ(countTriangleMismatches(a.triangles, b.triangles, 0), 0u) << "the same triangles";
    EXPECT_TRUE(a.positions == b.positions) << "the same vertex position bits";
    const auto problems = test::checkInvariants(corrected.downloadMeshState(), corrected.config());
    EXPECT_TRUE(problems.empty()) << problems.front();
}

INSTANTIATE_TEST_SUITE_P(Refine, CorrectionTest, ::testing::Combine(::testing::Bool(), ::testing::Bool()), [](const auto& info) {
    return std::string(std::get<0>(info.param) ? "Refined" : "Unrefined") + (std::get<1>(info.param) ? "Tiles" : "");
});

TEST_F(DeintegrationTest, ABoundedMapRefusesAndAFrameItDoesNotHoldIsCounted) {
    const std::vector<Frame> frames = roomFrames(2);
    gpu::GpuVolumeConfig bounded = config(false);
    bounded.keepRadius = 3.0f;
    gpu::GpuVolume recycling(context(), bounded);
    recycling.integrate(frames[0].depth, intrinsics(), frames[0].pose);
    try {
        recycling.deintegrate(frames[0].depth, nullptr, intrinsics(), frames[0].pose);
        ADD_FAILURE() << "a bounded map must refuse";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("bounded map"), std::string::npos) << e.what();
    }
    // A frame that was never fused: where it would take out what is not there, that is counted, never silent
    // (the frame store's bookkeeping keeps this from happening: Reconstructor::correct).
    gpu::GpuVolume volume(context(), config(false));
    volume.integrate(frames[0].depth, intrinsics(), frames[0].pose);
    const gpu::FrameReport r = volume.deintegrate(frames[1].depth, nullptr, intrinsics(), frames[1].pose);
    EXPECT_GT(r.counters.observationsDropped, 0u);
}

}  // namespace
}  // namespace vkmesh

namespace vkmesh {
namespace {

// The ranking of corrections: metres plus the geodesic angle, exactly 0 for an unchanged pose (so it is not
// queued), and right near pi, where Euler angles wrap.
TEST(PoseChange, MetresPlusGeodesicRadians) {
    const Pose a = drifted(synth::cameraPath(24, synth::PathKind::Orbit)[3], 5);
    EXPECT_EQ(gpu::poseChange(a, a), 0.0);
    Pose b = a;
    b.topRightCorner<3, 1>() += Eigen::Vector3d(0.03, 0.0, -0.04);
    EXPECT_NEAR(gpu::poseChange(a, b), 0.05, 1e-12);
    for (double degrees : {1e-4, 0.5, 90.0, 179.9}) {
        Pose c = a;
        c.topLeftCorner<3, 3>() = a.topLeftCorner<3, 3>() * Eigen::AngleAxisd(degrees * M_PI / 180.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
        EXPECT_NEAR(gpu::poseChange(a, c), degrees * M_PI / 180.0, 1e-9) << degrees;
    }
}

// The corrector keeps frames on a worker thread (MapCorrector::keep): whatever reads the store then finds every
// frame kept before, bit for bit and in order, and an error of the store (here a frame kept twice) is thrown by the
// next call, naming the frame, with nothing kept before it lost.
TEST(MapCorrectorKeep, FramesCompressedOnTheWorkerAreAllThereAndErrorsReachTheCaller) {
    const std::vector<Frame> frames = roomFrames(3);
    gpu::MapCorrector corrector{FrameStore()};
    constexpr uint32_t kKept = 3 * gpu::MapCorrector::kMaxQueued;   // more than the queue holds: keep() waits
    for (uint32_t i = 0; i < kKept; ++i) {
        const Frame& f = frames[i % frames.size()];
        corrector.keep(i, 0.1 * i, intrinsics(), drifted(f.pose, i), f.depth, i % 2 ? &f.color : nullptr);
    }
    const FrameStore& store = corrector.store();
    ASSERT_EQ(store.size(), kKept);
    for (uint32_t i = 0; i < kKept; ++i) {
        const StoredFrame s = store.get(i);
        const Frame& f = frames[i % frames.size()];
        EXPECT_EQ(s.pose, drifted(f.pose, i));
        ASSERT_EQ(s.depth.meters.size(), f.depth.meters.size());
        EXPECT_EQ(std::memcmp(s.depth.meters.data(), f.depth.meters.data(), f.depth.meters.size() * sizeof(float)), 0) << "frame " << i;
        EXPECT_EQ(s.color.rgb, i % 2 ? f.color.rgb : std::vector<uint8_t>{}) << "frame " << i;
    }
    // Frame 5 again: refused by the store on the worker; the error reaches the caller at its next call.
    corrector.keep(5, 9.0, intrinsics(), frames[0].pose, frames[0].depth, nullptr);
    const std::string why = test::errorMessageOf([&] { (void)corrector.store(); });
    EXPECT_NE(why.find("frame 5"), std::string::npos) << why;
    EXPECT_NE(why.find("already stored"), std::string::npos) << why;
    corrector.keep(kKept, 9.0, intrinsics(), frames[0].pose, frames[0].depth, nullptr);   // and the corrector goes on
    EXPECT_EQ(corrector.store().size(), kKept + 1);
    EXPECT_DOUBLE_EQ(corrector.store().timestamp(5), 0.5);   // the first frame 5 stays
}

}  // namespace
}  // namespace vkmesh
