// GPU allocation, fusion and baseline mesh against the CPU reference, on synthetic scenes.
#include <gtest/gtest.h>

#include <tuple>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include "cpu/reference_allocation.h"
#include "cpu/reference_volume.h"
#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "io/dataset.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using test::GpuTest;

constexpr int kWidth = 160, kHeight = 120;

gpu::GpuVolumeConfig smallConfig(float voxel = 0.04f) {
    gpu::GpuVolumeConfig c;
    c.params.voxelSize = voxel;
    c.params.truncVoxels = 4;
    c.params.maxDepth = 6.0f;
    c.blockCapacity = 8192;
    c.imageWidth = kWidth;
    c.imageHeight = kHeight;
    return c;
}

struct Frame {
    DepthImage depth;
    Pose pose;
};

std::vector<Frame> roomFrames(size_t count, bool noise) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    std::vector<Frame> frames;
    auto path = synth::cameraPath(24, synth::PathKind::Orbit);
    for (size_t i = 0; i < count; ++i) {
        synth::RenderOptions options;
        options.noise = noise;
        options.seed = uint32_t(i + 1);
        frames.push_back({scene.renderDepth(intr, path[i * 3 % path.size()], options), path[i * 3 % path.size()]});
    }
    return frames;
}

using BlockMap = std::map<cpu::BlockCoord, gpu::BlockSnapshot>;
BlockMap byCoord(std::vector<gpu::BlockSnapshot> blocks) {
    BlockMap out;
    for (auto& b : blocks) {
        cpu::BlockCoord c{b.coord.x(), b.coord.y(), b.coord.z()};
        EXPECT_TRUE(out.emplace(c, std::move(b)).second) << "block listed twice in the hash";
    }
    return out;
}

// Compares every TSDF corner; returns the number of corners that differ by more than `tolerance`.
size_t compareTsdf(const BlockMap& gpu, const cpu::ReferenceVolume& cpu, float tolerance) {
    size_t differing = 0;
    for (const auto& [coord, ref] : cpu.blocks()) {
        auto it = gpu.find(coord);
        if (it == gpu.end()) {
            ADD_FAILURE() << "block " << coord[0] << "," << coord[1] << "," << coord[2] << " missing on the GPU";
            continue;
        }
        for (uint32_t v = 0; v < gpu::VOXELS_PER_BLOCK; ++v) {
            if (std::abs(it->second.sdf[v] - ref.sdf[v]) > tolerance || it->second.weight[v] != ref.weight[v]) ++differing;
        }
    }
    return differing;
}

// (pixel stride, allocation by tiles)
class AllocationTest : public GpuTest, public ::testing::WithParamInterface<std::tuple<int, bool>> {};

TEST_P(AllocationTest, MatchesReferenceAndCountersConserve) {
    auto config = smallConfig();
    config.params.allocationStride = std::get<0>(GetParam());
    config.params.allocationTiles = std::get<1>(GetParam());
    VolumeParams perPixel = config.params;
    perPixel.allocationTiles = false;
    gpu::GpuVolume volume(context(), config);
    cpu::ReferenceVolume reference(config.params);
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    auto frames = roomFrames(3, false);
    uint32_t distinct = 0;
    for (const auto& f : frames) {
        gpu::FrameReport report = volume.integrate(f.depth, intr, f.pose);
        cpu::ReferenceFrameStats stats = reference.integrate(f.depth, intr, f.pose);
        const gpu::Counters& k = report.counters;
        EXPECT_TRUE(report.warnings.empty()) << report.warnings.front();
        EXPECT_EQ(k.validPixels, stats.validPixels);
        EXPECT_EQ(k.blockRequests, stats.blockRequests);
        EXPECT_EQ(k.touchedCount, stats.touchedCount);
        EXPECT_EQ(k.blocksInserted, stats.blocksInserted);
        // Every visit of a block is found, inserted, shared (the same invocation had just visited it for a
        // neighbouring pixel of its column), or counted as a failure: nothing vanishes. Most visits are shared.
        // The image is no whole number of columns high at either stride, so partial columns are covered too.
        EXPECT_EQ(k.blockRequests, k.blocksFound + k.blocksInserted + k.hashFull + k.outOfRange + k.blocksShared);
        EXPECT_GT(k.blocksShared, k.blocksFound + k.blocksInserted);
        EXPECT_EQ(k.allocRequests, k.blocksInserted);
        EXPECT_EQ(k.poolExhausted, 0u);
        EXPECT_EQ(k.fusedBlocks, k.touchedCount);
        EXPECT_EQ(k.updatedVoxels, stats.updatedVoxels);
        if (config.params.allocationTiles) {
            // Tiles covered by a plane: no block of the pixels' walks missing and, at stride 1, fewer visits (at
            // stride 4 a tile spans 32 x 32 pixels of this small image, and few planes fit).
            cpu::AllocationStats walked;
            const auto bands = cpu::touchedBlocks(f.depth, intr, f.pose, perPixel, 0.0f, &walked);
            if (config.params.allocationStride == 1) {
                EXPECT_LT(k.blockRequests, walked.blockRequests * 3 / 4);
            }
            EXPECT_GE(k.touchedCount, bands.size());
        }
        distinct += k.blocksInserted;
        EXPECT_EQ(k.blocksInUse, distinct);
        EXPECT_EQ(k.freeTop + k.blocksInUse, volume.config().blockCapacity);
    }
    BlockMap gpuBlocks = byCoord(volume.downloadBlocks());
    EXPECT_EQ(gpuBlocks.size(), reference.blocks().size());
    EXPECT_EQ(gpuBlocks.size(), distinct);
    EXPECT_EQ(compareTsdf(gpuBlocks, reference, 1e-6f), 0u);
}

INSTANTIATE_TEST_SUITE_P(PixelStride, AllocationTest, ::testing::Combine(::testing::Values(1, 4), ::testing::Bool()), [](const auto& info) {
    return "Stride" + std::to_string(std::get<0>(info.param)) + (std::get<1>(info.param) ? "Tiles" : "");
});

// A wall seen obliquely at the image's right side, z = a x + g (camera frame) with g < 0: its extension crosses
// the optical axis behind the camera, so D = 1 - a x' < 0 on every ray that meets it, and the rest of the image
// has no depth. allocate_tiles covers both kinds of tile (a plane with g < 0 by |D|, a tile without depth with
// nothing to walk) and must decide them, and claim the same blocks, as the CPU twin; with the first rules (a map
// written by the build that introduced tiles) it leaves both to the pixels, as that build did.
TEST_F(GpuTest, AllocationByTilesCoversObliqueWallsAndEmptyTilesLikeTheReference) {
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    const float a = 10.0f, g = -2.5f;
    DepthImage oblique{kWidth, kHeight, std::vector<float>(size_t(kWidth) * kHeight, 0.0f)};
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            const float ray = (float(x) - intr.cx) / intr.fx;
            if (ray > 0.28f) oblique.meters[size_t(y) * kWidth + x] = g / (1.0f - a * ray);   // 1.4 .. 0.5 m
        }
    const Pose pose = roomFrames(1, false).front().pose;
    for (const uint32_t rules : {gpu::ALLOC_TILE_RULES, gpu::ALLOC_TILE_RULES_FIRST}) {
        SCOPED_TRACE("tile rules " + std::to_string(rules));
        auto config = smallConfig();
        config.params.allocationStride = 1;
        config.params.allocationTiles = true;
        config.params.allocationTileRules = int(rules);
        // The CPU twin covers some of the wall's tiles with a plane (g < 0) and every tile without depth; with the
        // first rules, none of either.
        const gpu::FramePush push = makeFramePush(intr, pose, config.params, 1);
        size_t wallTiles = 0, wallCovered = 0, emptyTiles = 0, emptyCovered = 0;
        for (int y = 0; y + 7 < kHeight; y += 8)
            for (int x = 0; x + 7 < kWidth; x += 8) {
                size_t claimed = 0;
                const bool covered = cpu::walkTileSlab(oblique, push, config.params, x, y, x + 7, y + 7,
                                                       [&](const cpu::BlockCoord&) { ++claimed; }, nullptr);
                const bool wall = oblique.at(x, y) > 0.0f && oblique.at(x + 7, y) > 0.0f;
                const bool empty = oblique.at(x + 7, y) == 0.0f;
                wallTiles += wall, wallCovered += wall && covered && claimed > 0;
                emptyTiles += empty, emptyCovered += empty && covered && claimed == 0;
            }
        ASSERT_GT(wallTiles, 0u);
        if (rules == gpu::ALLOC_TILE_RULES) {
            EXPECT_GT(wallCovered, wallTiles / 2) << wallCovered << " of " << wallTiles << " wall tiles covered";
            EXPECT_EQ(emptyCovered, emptyTiles);
        } else {
            EXPECT_EQ(wallCovered, 0u);
            EXPECT_EQ(emptyCovered, 0u);
        }
        gpu::GpuVolume volume(context(), config);
        cpu::ReferenceVolume reference(config.params);
        const gpu::FrameReport report = volume.integrate(oblique, intr, pose);
        const cpu::ReferenceFrameStats stats = reference.integrate(oblique, intr, pose);
        EXPECT_TRUE(report.warnings.empty()) << report.warnings.front();
        EXPECT_EQ(report.counters.validPixels, stats.validPixels);
        EXPECT_EQ(report.counters.blockRequests, stats.blockRequests);
        EXPECT_EQ(report.counters.touchedCount, stats.touchedCount);
        EXPECT_EQ(report.counters.updatedVoxels, stats.updatedVoxels);
        VolumeParams perPixel = config.params;
        perPixel.allocationTiles = false;
        cpu::AllocationStats walked;
        const auto bands = cpu::touchedBlocks(oblique, intr, pose, perPixel, 0.0f, &walked);
        if (rules == gpu::ALLOC_TILE_RULES) EXPECT_LT(report.counters.blockRequests, walked.blockRequests / 2);
        else EXPECT_EQ(report.counters.blockRequests, walked.blockRequests) << "every tile walked by its pixels";
        BlockMap gpuBlocks = byCoord(volume.downloadBlocks());
        EXPECT_EQ(gpuBlocks.size(), reference.blocks().size());
        for (const auto& c : bands) EXPECT_EQ(gpuBlocks.count(c), 1u) << c[0] << "," << c[1] << "," << c[2];
        EXPECT_EQ(compareTsdf(gpuBlocks, reference, 1e-6f), 0u);
    }
}

TEST_F(GpuTest, FusedTsdfMatchesReference) {
    gpu::GpuVolume volume(context(), smallConfig());
    cpu::ReferenceVolume reference(smallConfig().params);
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    for (const auto& f : roomFrames(6, true)) {
        volume.integrate(f.depth, intr, f.pose);
        reference.integrate(f.depth, intr, f.pose);
    }
    BlockMap gpuBlocks = byCoord(volume.downloadBlocks());
    ASSERT_EQ(gpuBlocks.size(), reference.blocks().size());
    size_t observed = 0;
    for (const auto& [c, b] : reference.blocks())
        observed += std::count_if(b.weight.begin(), b.weight.end(), [](float w) { return w > 0; });
    EXPECT_GT(observed, 10000u) << "the scene should give the test something to compare";
    EXPECT_EQ(compareTsdf(gpuBlocks, reference, 1e-6f), 0u);
}

// Canonical form of a triangle soup: each triangle rotated to start at its smallest vertex (keeping its
// orientation), vertices rounded to 1 µm, then sorted.
std::vector<std::array<long, 9>> canonicalTriangles(const std::vector<Eigen::Vector3f>& soup) {
    std::vector<std::array<long, 9>> out;
    for (size_t t = 0; t + 2 < soup.size(); t += 3) {
        std::array<std::array<long, 3>, 3> v;
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) v[i][k] = std::lround(double(soup[t + i][k]) * 1e6);
        int first = int(std::min_element(v.begin(), v.end()) - v.begin());
        std::array<long, 9> tri;
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) tri[i * 3 + k] = v[(first + i) % 3][k];
        out.push_back(tri);
    }
    std::sort(out.begin(), out.end());
    return out;
}

TEST_F(GpuTest, BaselineMeshMatchesReference) {
    auto config = smallConfig();
    config.meshVertexCapacity = 1024;   // forces the grow-and-rerun path
    gpu::GpuVolume volume(context(), config);
    cpu::ReferenceVolume reference(config.params);
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    for (const auto& f : roomFrames(4, false)) {
        volume.integrate(f.depth, intr, f.pose);
        reference.integrate(f.depth, intr, f.pose);
    }
    gpu::TriangleSoup gpuMesh = volume.extractBaselineMesh();
    std::vector<Eigen::Vector3f> cpuMesh = reference.extractBaselineMesh();
    ASSERT_GT(cpuMesh.size(), 3000u);
    ASSERT_EQ(gpuMesh.vertices.size(), cpuMesh.size());
    auto a = canonicalTriangles(gpuMesh.vertices), b = canonicalTriangles(cpuMesh);
    size_t mismatched = 0;
    for (size_t i = 0; i < a.size(); ++i)
        for (int k = 0; k < 9; ++k)
            if (std::abs(a[i][k] - b[i][k]) > 1) { ++mismatched; break; }
    EXPECT_EQ(mismatched, 0u);
    EXPECT_EQ(volume.readCounters().meshVerticesDropped, 0u);
}

TEST_F(GpuTest, PoolExhaustionIsCountedAndKeepsFusedBlocks) {
    auto config = smallConfig();
    config.growCapacities = false;   // what a fixed pool reports (test_growth.cpp: growing past it)
    config.blockCapacity = 40;
    config.hashCapacity = 4096;
    config.touchedCapacity = 4096;
    gpu::GpuVolume volume(context(), config);
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    auto frames = roomFrames(2, false);
    gpu::FrameReport first = volume.integrate(frames[0].depth, intr, frames[0].pose);
    const gpu::Counters& k = first.counters;
    EXPECT_GT(k.touchedCount, 40u);
    EXPECT_EQ(k.blocksInUse, 40u);
    EXPECT_EQ(k.freeTop, 0u);
    EXPECT_EQ(k.poolExhausted, k.allocRequests - 40u);
    ASSERT_FALSE(first.warnings.empty());
    EXPECT_NE(first.warnings.front().find("pool exhausted"), std::string::npos) << first.warnings.front();
    auto before = byCoord(volume.downloadBlocks());
    EXPECT_EQ(before.size(), 40u);
    // A second frame fuses into the 40 blocks it has and keeps every one of them.
    gpu::FrameReport second = volume.integrate(frames[1].depth, intr, frames[1].pose);
    EXPECT_EQ(second.counters.blocksInUse, 40u);
    auto after = byCoord(volume.downloadBlocks());
    EXPECT_EQ(after.size(), 40u);
    for (const auto& [c, b] : before) EXPECT_TRUE(after.count(c));
}

TEST_F(GpuTest, HashFullIsCountedNeverSilent) {
    auto config = smallConfig();
    config.growCapacities = false;
    config.hashCapacity = 64;   // far fewer slots than blocks a frame touches
    gpu::GpuVolume volume(context(), config);
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    auto frames = roomFrames(1, false);
    gpu::FrameReport report = volume.integrate(frames[0].depth, intr, frames[0].pose);
    const gpu::Counters& k = report.counters;
    EXPECT_EQ(k.blocksInserted, 64u);
    EXPECT_GT(k.hashFull, 0u);
    EXPECT_EQ(k.blockRequests, k.blocksFound + k.blocksInserted + k.hashFull + k.outOfRange + k.blocksShared);
    ASSERT_FALSE(report.warnings.empty());
    EXPECT_NE(report.warnings.front().find("hash"), std::string::npos);
    EXPECT_EQ(volume.downloadBlocks().size(), 64u);
}

TEST_F(GpuTest, HeavyContentionInsertsEachKeyOnce) {
    // A wall 0.4 m in front of the camera: all 19,200 pixels walk into the same few blocks at once (pixel by pixel:
    // tiles would claim the wall's blocks once per tile).
    auto config = smallConfig(0.05f);
    config.params.allocationStride = 1;
    config.params.allocationTiles = false;
    gpu::GpuVolume volume(context(), config);
    cpu::ReferenceVolume reference(config.params);
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    DepthImage wall{kWidth, kHeight, std::vector<float>(size_t(kWidth) * kHeight, 0.4f)};
    for (int i = 0; i < 3; ++i) {
        Pose pose = Pose::Identity();
        pose(0, 3) = 0.01 * i;
        gpu::FrameReport r = volume.integrate(wall, intr, pose);
        cpu::ReferenceFrameStats stats = reference.integrate(wall, intr, pose);
        EXPECT_EQ(r.counters.blockRequests, stats.blockRequests);
        EXPECT_GE(r.counters.blockRequests, 2u * kWidth * kHeight);   // every pixel crosses >= 2 blocks
        EXPECT_EQ(r.counters.blocksInserted, stats.blocksInserted);
        EXPECT_EQ(r.counters.touchedCount, stats.touchedCount);
        EXPECT_EQ(r.counters.blockRequests,
                  r.counters.blocksFound + r.counters.blocksInserted + r.counters.hashFull + r.counters.outOfRange +
                      r.counters.blocksShared);
    }
    BlockMap blocks = byCoord(volume.downloadBlocks());   // fails on a key listed twice
    EXPECT_EQ(blocks.size(), reference.blocks().size());
    EXPECT_LT(blocks.size(), 64u);
    EXPECT_EQ(compareTsdf(blocks, reference, 1e-6f), 0u);
}

TEST_F(GpuTest, RealIclNuimFramesMatchReference) {
    // ICL-NUIM's negative fy and real depth noise, through the same comparison.
    auto root = test::sharedDatasetsDir();
    if (!root) GTEST_SKIP() << "shared datasets not found at ../shared/datasets (or $VKMESH_DATASETS)";
    DatasetOptions options;
    options.maxFrames = 3;
    options.maxDepth = 4.0f;
    auto dataset = Dataset::open(*root / "iclnuim_office_traj0", options);
    const Intrinsics& intr = dataset->intrinsics();
    ASSERT_LT(intr.fy, 0.0f);
    auto config = smallConfig(0.03f);
    config.imageWidth = intr.width;
    config.imageHeight = intr.height;
    config.params.maxDepth = 4.0f;
    gpu::GpuVolume volume(context(), config);
    cpu::ReferenceVolume reference(config.params);
    for (size_t i = 0; i < dataset->size(); ++i) {
        DepthImage depth = dataset->loadDepth(i);
        gpu::FrameReport r = volume.integrate(depth, intr, dataset->frame(i).cameraToWorld);
        cpu::ReferenceFrameStats stats = reference.integrate(depth, intr, dataset->frame(i).cameraToWorld);
        EXPECT_EQ(r.counters.touchedCount, stats.touchedCount);
        EXPECT_EQ(r.counters.updatedVoxels, stats.updatedVoxels);
    }
    BlockMap blocks = byCoord(volume.downloadBlocks());
    ASSERT_EQ(blocks.size(), reference.blocks().size());
    EXPECT_GT(blocks.size(), 100u);
    EXPECT_EQ(compareTsdf(blocks, reference, 1e-6f), 0u);
}

TEST_F(GpuTest, RejectsMismatchedImages) {
    gpu::GpuVolume volume(context(), smallConfig());
    DepthImage wrong{kWidth / 2, kHeight, std::vector<float>(kWidth / 2 * kHeight, 1.0f)};
    EXPECT_THROW(volume.integrate(wrong, synth::kinectIntrinsics(kWidth, kHeight), Pose::Identity()), Error);
}

TEST(GpuVolumeConfig, RejectsAbsurdVoxelSize) {
    vk::Context context;
    auto config = smallConfig(50.0f);
    try {
        gpu::GpuVolume volume(context, config);
        FAIL() << "a 50 m voxel was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("voxel size"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace vkmesh
