// The CPU reference's stages one at a time, on inputs small enough to know the answer: allocation (the band
// walk and the touched list, with and without the hash), fusion (the update rule, flipped corners, the cubes
// around them), recycling, the baseline mesh, and the incremental mesher's passes (claim, vertex update,
// triangulation, garbage collection).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "core/camera.h"
#include "core/tsdf_corner.h"
#include "cpu/reference_allocation.h"
#include "cpu/reference_baseline.h"
#include "cpu/reference_fusion.h"
#include "cpu/reference_mesher.h"
#include "cpu/reference_recycling.h"
#include "cpu/reference_volume.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using cpu::BlockCoord;

using test::joined;

// A camera at the origin looking along +z at a wall at `depth` metres filling the image.
struct WallView {
    Intrinsics intrinsics{100.0f, 100.0f, 64.0f, 64.0f, 128, 128};
    Pose pose = Pose::Identity();
    DepthImage depth;
    explicit WallView(float wall) : depth{128, 128, std::vector<float>(128 * 128, wall)} {}
};

VolumeParams smallVoxels() {
    VolumeParams p;
    p.voxelSize = 0.05f;
    p.allocationStride = 1;
    return p;
}

// ---- allocation ---------------------------------------------------------------------------------

TEST(ReferenceAllocation, BandWalkVisitsTheBlocksAlongAnAxis) {
    std::vector<BlockCoord> cells;
    EXPECT_TRUE(cpu::walkBand({0.5f, 0.5f, 0.5f}, {3.5f, 0.5f, 0.5f}, [&](const BlockCoord& c) { cells.push_back(c); }));
    EXPECT_EQ(cells, (std::vector<BlockCoord>{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}}));
    cells.clear();
    EXPECT_TRUE(cpu::walkBand({-0.5f, 2.2f, 0.1f}, {-0.5f, 0.7f, 0.1f}, [&](const BlockCoord& c) { cells.push_back(c); }));
    EXPECT_EQ(cells, (std::vector<BlockCoord>{{-1, 2, 0}, {-1, 1, 0}, {-1, 0, 0}}));
}

TEST(ReferenceAllocation, BandWalkStepsToFaceNeighboursAndStopsAtTheBound) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> coord(-4.0f, 4.0f);
    for (int i = 0; i < 200; ++i) {
        const Eigen::Vector3f a(coord(rng), coord(rng), coord(rng)), b(coord(rng), coord(rng), coord(rng));
        std::vector<BlockCoord> cells;
        const bool complete = cpu::walkBand(a, b, [&](const BlockCoord& c) { cells.push_back(c); });
        ASSERT_FALSE(cells.empty());
        EXPECT_EQ(cells.front(), (BlockCoord{int(std::floor(a.x())), int(std::floor(a.y())), int(std::floor(a.z()))}));
        EXPECT_TRUE(complete) << "at most 3 * 8 + 1 blocks between two points of an 8-block cube";
        for (size_t k = 1; k < cells.size(); ++k) {
            int steps = 0;
            for (int axis = 0; axis < 3; ++axis) steps += std::abs(cells[k][axis] - cells[k - 1][axis]);
            EXPECT_EQ(steps, 1) << "walk " << i << " step " << k;
        }
    }
    std::vector<BlockCoord> cells;
    EXPECT_FALSE(cpu::walkBand({0.5f, 0.5f, 0.5f}, {40.5f, 0.5f, 0.5f}, [&](const BlockCoord& c) { cells.push_back(c); }));
    EXPECT_EQ(cells.size(), gpu::RAY_MAX_BLOCKS);
}

// Allocation by tiles claims a superset of what the sampled pixels' band walks claim (allocate_tiles.comp's
// argument), on noisy depth of the synthetic room (tilted walls, floor, furniture: depth edges) seen from several
// poses, at the default stride and at stride 1, and covers most tiles there.
TEST(ReferenceAllocation, TileSlabsCoverThePixelsBands) {
    const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
    const Intrinsics intrinsics = synth::kinectIntrinsics(320, 240);
    const auto poses = synth::cameraPath(12);
    size_t tilesCovered = 0, tilesWithDepth = 0, framesChecked = 0;
    for (int stride : {2, 1}) {
        VolumeParams perPixel;
        perPixel.voxelSize = 0.03f;
        perPixel.maxDepth = 4.0f;
        perPixel.allocationStride = stride;
        perPixel.allocationTiles = false;
        VolumeParams byTiles = perPixel;
        byTiles.allocationTiles = true;
        for (size_t i = 0; i < poses.size(); i += 3) {
            synth::RenderOptions noisy;
            noisy.noise = true;
            noisy.seed = uint32_t(7 + i);
            const DepthImage depth = room.renderDepth(intrinsics, poses[i], noisy);
            cpu::AllocationStats walked, tiled;
            const auto bands = cpu::touchedBlocks(depth, intrinsics, poses[i], perPixel, 0.0f, &walked);
            const auto slabs = cpu::touchedBlocks(depth, intrinsics, poses[i], byTiles, 0.0f, &tiled);
            const std::set<BlockCoord> claimed(slabs.begin(), slabs.end());
            size_t missing = 0;
            for (const BlockCoord& c : bands) missing += claimed.count(c) == 0;
            EXPECT_EQ(missing, 0u) << "stride " << stride << ", frame " << i << ": blocks a band crosses that no slab claims";
            EXPECT_EQ(tiled.validPixels, walked.validPixels) << "every valid sample counted once, in a slab or a walk";
            EXPECT_LT(tiled.blockRequests, walked.blockRequests / 2) << "the slabs visit far fewer blocks than the walks";
            EXPECT_LT(slabs.size(), bands.size() * 5 / 4) << "the slabs add a few blocks, not many";
            ++framesChecked;
            // Which tiles a plane covered, straight from walkTileSlab.
            const gpu::FramePush push = makeFramePush(intrinsics, poses[i], byTiles, 1);
            const int side = int(gpu::ALLOC_TILE) * stride;
            for (int y = 0; y < depth.height; y += side)
                for (int x = 0; x < depth.width; x += side) {
                    const int lastX = std::min(x + side - stride, (depth.width - 1) / stride * stride);
                    const int lastY = std::min(y + side - stride, (depth.height - 1) / stride * stride);
                    bool anyDepth = false;
                    for (int v = y; v <= lastY; v += stride)
                        for (int u = x; u <= lastX; u += stride) anyDepth = anyDepth || depth.at(u, v) > 0.0f;
                    if (!anyDepth) continue;
                    ++tilesWithDepth;
                    tilesCovered += cpu::walkTileSlab(depth, push, byTiles, x, y, lastX, lastY, [](const BlockCoord&) {}, nullptr);
                }
        }
    }
    EXPECT_EQ(framesChecked, 8u);
    EXPECT_GT(tilesCovered, tilesWithDepth / 2) << tilesCovered << " of " << tilesWithDepth << " tiles covered by a plane";
}

// A tile across a depth edge, with too few depths, or seen edge-on is left to its pixels' walks; a tilted plane is
// covered, and its slab claims the blocks its bands cross.
TEST(ReferenceAllocation, TileSlabsLeaveEdgesAndHolesToThePixels) {
    VolumeParams params = smallVoxels();
    params.voxelSize = 0.03f;
    const Intrinsics intrinsics{100.0f, 100.0f, 64.0f, 64.0f, 128, 128};
    const gpu::FramePush push = makeFramePush(intrinsics, Pose::Identity(), params, 1);
    auto covered = [&](const DepthImage& depth, int x, int y) {
        return cpu::walkTileSlab(depth, push, params, x, y, x + 7, y + 7, [](const BlockCoord&) {}, nullptr);
    };
    // A plane tilted 60 degrees about the y axis: z = 1.5 + tan(60) x.
    DepthImage tilted{128, 128, std::vector<float>(128 * 128)};
    for (int y = 0; y < 128; ++y)
        for (int x = 0; x < 128; ++x) {
            const float ray = (float(x) - 64.0f) / 100.0f;
            tilted.meters[size_t(y) * 128 + x] = 1.5f / (1.0f - std::tan(1.0472f) * ray * 0.5f);
        }
    EXPECT_TRUE(covered(tilted, 40, 40));
    VolumeParams perPixel = params;
    perPixel.allocationTiles = false;
    const auto bands = cpu::touchedBlocks(tilted, intrinsics, Pose::Identity(), perPixel, 0.0f);
    const auto slabs = cpu::touchedBlocks(tilted, intrinsics, Pose::Identity(), params, 0.0f);
    const std::set<BlockCoord> claimed(slabs.begin(), slabs.end());
    for (const BlockCoord& c : bands) EXPECT_EQ(claimed.count(c), 1u) << c[0] << "," << c[1] << "," << c[2];
    // The same with a negative focal length (ICL-NUIM's fy): the tile's rays are ordered, not assumed increasing.
    const Intrinsics flipped{100.0f, -100.0f, 64.0f, 64.0f, 128, 128};
    EXPECT_TRUE(cpu::walkTileSlab(tilted, makeFramePush(flipped, Pose::Identity(), params, 1), params, 40, 40, 47, 47,
                                  [](const BlockCoord&) {}, nullptr));
    const auto flippedBands = cpu::touchedBlocks(tilted, flipped, Pose::Identity(), perPixel, 0.0f);
    const auto flippedSlabs = cpu::touchedBlocks(tilted, flipped, Pose::Identity(), params, 0.0f);
    const std::set<BlockCoord> flippedClaimed(flippedSlabs.begin(), flippedSlabs.end());
    for (const BlockCoord& c : flippedBands) EXPECT_EQ(flippedClaimed.count(c), 1u) << c[0] << "," << c[1] << "," << c[2];
    // A step from 1 m to 2 m through the tile.
    DepthImage step{128, 128, std::vector<float>(128 * 128, 1.0f)};
    for (int y = 0; y < 128; ++y)
        for (int x = 44; x < 128; ++x) step.meters[size_t(y) * 128 + x] = 2.0f;
    EXPECT_TRUE(covered(step, 24, 40));
    EXPECT_FALSE(covered(step, 40, 40)) << "the tile across the edge";
    // Holes: a third of the tile without depth.
    DepthImage holes{128, 128, std::vector<float>(128 * 128, 1.0f)};
    for (int y = 40; y < 48; ++y)
        for (int x = 40; x < 43; ++x) holes.meters[size_t(y) * 128 + x] = 0.0f;
    EXPECT_FALSE(covered(holes, 40, 40)) << "fewer than " << gpu::ALLOC_TILE_MIN_VALID << " valid depths";
    // A tile without any depth has nothing for its pixels to walk either: covered, and nothing claimed.
    for (int y = 40; y < 48; ++y)
        for (int x = 40; x < 48; ++x) holes.meters[size_t(y) * 128 + x] = 0.0f;
    size_t claimedByEmpty = 0;
    EXPECT_TRUE(cpu::walkTileSlab(holes, push, params, 40, 40, 47, 47, [&](const BlockCoord&) { ++claimedByEmpty; }, nullptr));
    EXPECT_EQ(claimedByEmpty, 0u);
    VolumeParams firstRules = params;   // a map of the first rules left it to the pixels
    firstRules.allocationTileRules = int(gpu::ALLOC_TILE_RULES_FIRST);
    EXPECT_FALSE(cpu::walkTileSlab(holes, push, firstRules, 40, 40, 47, 47, [](const BlockCoord&) {}, nullptr));
    perPixel = params;
    perPixel.allocationTiles = false;
    cpu::AllocationStats walkedHoles, tiledHoles;
    const auto holeBands = cpu::touchedBlocks(holes, intrinsics, Pose::Identity(), perPixel, 0.0f, &walkedHoles);
    const auto holeSlabs = cpu::touchedBlocks(holes, intrinsics, Pose::Identity(), params, 0.0f, &tiledHoles);
    const std::set<BlockCoord> holeClaimed(holeSlabs.begin(), holeSlabs.end());
    for (const BlockCoord& c : holeBands) EXPECT_EQ(holeClaimed.count(c), 1u) << c[0] << "," << c[1] << "," << c[2];
    EXPECT_EQ(tiledHoles.validPixels, walkedHoles.validPixels);
    // A wall seen edge-on, the plane x = 0.3 m (camera frame) along the optical axis: no z = a x + b y + g fits it.
    DepthImage edgeOn{128, 128, std::vector<float>(128 * 128, 0.0f)};
    for (int y = 0; y < 128; ++y)
        for (int x = 100; x < 128; ++x) edgeOn.meters[size_t(y) * 128 + x] = 0.3f / ((float(x) - 64.0f) / 100.0f);
    EXPECT_FALSE(covered(edgeOn, 100, 40));
}

// A plane whose extension crosses the optical axis behind the camera (z = a x + g with g < 0: a wall seen
// obliquely, at the side of the image) meets the tile's rays where D = 1 - a x' < 0; the slab's argument holds with
// |D|, so such a tile is covered too, and claims every block its pixels' bands cross.
TEST(ReferenceAllocation, TileSlabsCoverPlanesCrossingTheAxisBehindTheCamera) {
    VolumeParams params = smallVoxels();
    params.voxelSize = 0.03f;
    const float a = 3.0f, g = -0.5f;
    for (const float fy : {100.0f, -100.0f}) {
        const Intrinsics intrinsics{100.0f, fy, 64.0f, 64.0f, 128, 128};
        DepthImage oblique{128, 128, std::vector<float>(128 * 128, 0.0f)};
        for (int y = 0; y < 128; ++y)
            for (int x = 104; x < 128; ++x) {   // x' > 0.4, where 1 - a x' < 0 and the plane lies in front
                const float ray = (float(x) - 64.0f) / 100.0f;
                oblique.meters[size_t(y) * 128 + x] = g / (1.0f - a * ray);
            }
        const gpu::FramePush push = makeFramePush(intrinsics, Pose::Identity(), params, 1);
        size_t claimed = 0;
        EXPECT_TRUE(cpu::walkTileSlab(oblique, push, params, 112, 40, 119, 47, [&](const BlockCoord&) { ++claimed; }, nullptr))
            << "fy " << fy;
        EXPECT_GT(claimed, 0u);
        VolumeParams firstRules = params;   // a map of the first rules left it to the pixels
        firstRules.allocationTileRules = int(gpu::ALLOC_TILE_RULES_FIRST);
        EXPECT_FALSE(cpu::walkTileSlab(oblique, push, firstRules, 112, 40, 119, 47, [](const BlockCoord&) {}, nullptr));
        VolumeParams perPixel = params;
        perPixel.allocationTiles = false;
        const auto bands = cpu::touchedBlocks(oblique, intrinsics, Pose::Identity(), perPixel, 0.0f);
        const auto slabs = cpu::touchedBlocks(oblique, intrinsics, Pose::Identity(), params, 0.0f);
        const std::set<BlockCoord> claimedSet(slabs.begin(), slabs.end());
        size_t missing = 0;
        for (const BlockCoord& c : bands) missing += claimedSet.count(c) == 0;
        EXPECT_EQ(missing, 0u) << "fy " << fy;
    }
}

TEST(ReferenceAllocation, TouchedBlocksInsertIntoTheHashOnceAndStampIt) {
    const WallView view(1.1f);
    const VolumeParams params = smallVoxels();
    cpu::ReferenceHash hash(4096);
    cpu::AllocationStats first, second, plain;
    const auto touched = cpu::touchedBlocks(view.depth, view.intrinsics, view.pose, params, 0.0f, &first, &hash, 1);
    ASSERT_GT(touched.size(), 4u);
    EXPECT_EQ(first.validPixels, 128u * 128u);
    EXPECT_EQ(first.touchedCount, touched.size());
    EXPECT_EQ(first.blocksInserted, touched.size());
    EXPECT_EQ(first.hashFull, 0u);
    EXPECT_EQ(first.blocksFound + first.blocksInserted, first.blockRequests - first.outOfRange - first.outsideRadius);
    EXPECT_GT(first.blocksFound, first.blocksInserted) << "most pixels' bands cross blocks other pixels inserted";
    EXPECT_EQ(hash.entries(), touched.size());
    std::set<int> layers;
    for (const auto& c : touched) {
        const uint32_t slot = hash.find(c);
        ASSERT_NE(slot, gpu::NO_BLOCK);
        EXPECT_EQ(hash.stamp(slot), 1u);
        layers.insert(c[2]);
    }
    // The wall at z = 1.1 m with a 0.2 m band: z from 0.9 to 1.3 m, blocks of 0.4 m: block layers 2 and 3.
    EXPECT_EQ(layers, (std::set<int>{2, 3}));
    EXPECT_EQ(cpu::touchedBlocks(view.depth, view.intrinsics, view.pose, params, 0.0f, &second, &hash, 2), touched);
    EXPECT_EQ(second.blocksInserted, 0u);
    EXPECT_EQ(second.blocksFound, first.blocksFound + first.blocksInserted);
    for (const auto& c : touched) EXPECT_EQ(hash.stamp(hash.find(c)), 2u);
    // Without a hash: the same blocks in the same order.
    EXPECT_EQ(cpu::touchedBlocks(view.depth, view.intrinsics, view.pose, params, 0.0f, &plain), touched);
    EXPECT_EQ(plain.blocksFound + plain.blocksInserted + plain.hashFull, 0u);
}

TEST(ReferenceAllocation, AFullHashLeavesBlocksUntouchedAndCountsThem) {
    const WallView view(1.0f);
    cpu::ReferenceHash hash(4);
    cpu::AllocationStats stats;
    const auto touched = cpu::touchedBlocks(view.depth, view.intrinsics, view.pose, smallVoxels(), 0.0f, &stats, &hash, 1);
    EXPECT_EQ(touched.size(), 4u);
    EXPECT_GT(stats.hashFull, 0u);
    EXPECT_EQ(hash.entries(), 4u);
    for (const auto& c : touched) EXPECT_NE(hash.find(c), gpu::NO_BLOCK);
}

TEST(ReferenceAllocation, KeepRadiusLeavesFarBlocksOut) {
    const WallView view(2.0f);
    VolumeParams params = smallVoxels();
    cpu::AllocationStats all, near;
    const auto every = cpu::touchedBlocks(view.depth, view.intrinsics, view.pose, params, 0.0f, &all);
    const float radius = 2.2f;
    const auto kept = cpu::touchedBlocks(view.depth, view.intrinsics, view.pose, params, radius, &near);
    EXPECT_EQ(all.outsideRadius, 0u);
    EXPECT_GT(near.outsideRadius, 0u);
    EXPECT_LT(kept.size(), every.size());
    EXPECT_GT(kept.size(), 0u);
    const std::set<BlockCoord> everySet(every.begin(), every.end());
    for (const auto& c : kept) {
        EXPECT_TRUE(everySet.count(c));
        double d2 = 0;
        for (int k = 0; k < 3; ++k) d2 += std::pow((c[k] + 0.5) * 0.4, 2);
        EXPECT_LE(std::sqrt(d2), radius + 1e-4);
    }
}

// ---- fusion -------------------------------------------------------------------------------------

TEST(ReferenceFusion, CornerFlipRule) {
    cpu::FusionRule rule;
    rule.minMeshWeight = 1.0f;
    EXPECT_TRUE(cpu::cornerFlipped(0.1f, 0.0f, 0.1f, 1.0f, rule)) << "becomes observed";
    EXPECT_TRUE(cpu::cornerFlipped(0.1f, 2.0f, 0.1f, 0.5f, rule)) << "no longer observed";
    EXPECT_FALSE(cpu::cornerFlipped(0.1f, 1.0f, 0.05f, 2.0f, rule));
    EXPECT_TRUE(cpu::cornerFlipped(0.1f, 1.0f, -0.05f, 2.0f, rule)) << "sign change";
    EXPECT_FALSE(cpu::cornerFlipped(0.1f, 0.0f, -0.05f, 0.5f, rule)) << "sign change while unobserved";
    EXPECT_FALSE(cpu::cornerFlipped(0.1f, 1.0f, 0.01f, 2.0f, rule)) << "near the surface, same sign (refinement is the mesher's)";
}

TEST(ReferenceFusion, FusingAWallAveragesTruncatedDistances) {
    const VolumeParams params = smallVoxels();
    const cpu::FusionRule rule{params.voxelSize, params.truncation(), 1.0f};
    const TsdfFixedPoint fixed = tsdfFixedPoint(params.truncation());
    const WallView view(1.0f);
    const gpu::FramePush push = makeFramePush(view.intrinsics, view.pose, params, 1);
    cpu::ReferenceBlock block;
    const BlockCoord coord{0, 0, 2};   // corners at z = 0.80 .. 1.15 m: all within the band
    std::vector<std::array<int, 3>> flipped;
    EXPECT_EQ(cpu::fuseBlock(block, coord, view.depth, push, rule, &flipped).updated, gpu::VOXELS_PER_BLOCK);
    EXPECT_EQ(flipped.size(), gpu::VOXELS_PER_BLOCK) << "every corner becomes observed";
    EXPECT_EQ(flipped.front(), (std::array<int, 3>{0, 0, 16}));
    for (uint32_t v = 0; v < gpu::VOXELS_PER_BLOCK; ++v) {
        const float z = float(16 + cpu::localCoords(v)[2]) * params.voxelSize;
        EXPECT_EQ(block.weight[v], 1.0f);
        // The distance rounded to a whole step (truncation / 4096), and the metres kept beside the sum.
        const float exact = std::min(1.0f - z, params.truncation());
        EXPECT_EQ(block.sdfSum[v], tsdfSteps(exact, fixed.stepsPerMetre)) << v;
        EXPECT_NEAR(block.sdf[v], exact, 0.5001f * fixed.metresPerStep) << v;
        EXPECT_EQ(block.sdf[v], tsdfMean(block.sdfSum[v], 1.0f, fixed.metresPerStep)) << v;
    }
    // The same frame again: the average stays, the weights grow, nothing flips.
    const cpu::ReferenceBlock once = block;
    flipped.clear();
    EXPECT_EQ(cpu::fuseBlock(block, coord, view.depth, push, rule, &flipped).updated, gpu::VOXELS_PER_BLOCK);
    EXPECT_TRUE(flipped.empty());
    for (uint32_t v = 0; v < gpu::VOXELS_PER_BLOCK; ++v) {
        EXPECT_EQ(block.weight[v], 2.0f);
        EXPECT_EQ(block.sdf[v], once.sdf[v]);
    }
    // A nearer wall: the corners more than a truncation behind it (z = 1.10 and 1.15 m) keep their values.
    const WallView nearer(0.88f);
    EXPECT_EQ(cpu::fuseBlock(block, coord, nearer.depth, push, rule, nullptr).updated, gpu::VOXELS_PER_BLOCK - 128);
    for (uint32_t v = 0; v < gpu::VOXELS_PER_BLOCK; ++v)
        EXPECT_EQ(block.weight[v], cpu::localCoords(v)[2] >= 6 ? 2.0f : 3.0f) << v;
    // Behind the camera nothing is updated.
    cpu::ReferenceBlock behind;
    EXPECT_EQ(cpu::fuseBlock(behind, {0, 0, -1}, view.depth, push, rule, nullptr).updated, 0u);
}

TEST(ReferenceFusion, DeintegratingAFrameRestoresEveryBitInAnyOrder) {
    const VolumeParams params = smallVoxels();
    const cpu::FusionRule rule{params.voxelSize, params.truncation(), 1.0f};
    const WallView a(1.0f), b(0.93f), c(1.04f);
    const gpu::FramePush push = makeFramePush(a.intrinsics, a.pose, params, 1);
    const BlockCoord coord{0, 0, 2};
    cpu::ReferenceBlock ac;   // a and c only
    cpu::fuseBlock(ac, coord, a.depth, push, rule, nullptr);
    cpu::fuseBlock(ac, coord, c.depth, push, rule, nullptr);
    cpu::ReferenceBlock block;   // a, b, c, then b taken out again
    for (const WallView* view : {&a, &b, &c}) cpu::fuseBlock(block, coord, view->depth, push, rule, nullptr);
    std::vector<std::array<int, 3>> flipped;
    const cpu::FusionCount out = cpu::fuseBlock(block, coord, b.depth, push, rule, &flipped, nullptr, true);
    EXPECT_GT(out.updated, 0u);
    EXPECT_EQ(out.dropped, 0u);
    EXPECT_EQ(block.sdfSum, ac.sdfSum);
    EXPECT_EQ(block.weight, ac.weight);
    EXPECT_EQ(block.sdf, ac.sdf) << "bit for bit, though b was fused between a and c";
    // Taking out the rest, in another order, leaves nothing; one more de-integration finds nothing to take.
    cpu::fuseBlock(block, coord, a.depth, push, rule, nullptr, nullptr, true);
    flipped.clear();
    cpu::fuseBlock(block, coord, c.depth, push, rule, &flipped, nullptr, true);
    EXPECT_EQ(flipped.size(), gpu::VOXELS_PER_BLOCK) << "every corner becomes unobserved";
    EXPECT_EQ(block.sdfSum, cpu::ReferenceBlock{}.sdfSum);
    EXPECT_EQ(block.weight, cpu::ReferenceBlock{}.weight);
    EXPECT_EQ(cpu::fuseBlock(block, coord, c.depth, push, rule, nullptr, nullptr, true).dropped, gpu::VOXELS_PER_BLOCK);
}

TEST(ReferenceFusion, CubesAroundAFlippedCornerInTheBlocksThatExist) {
    std::map<BlockCoord, cpu::ReferenceBlock> blocks;
    blocks[{0, 0, 0}];
    auto cubes = cpu::cubesAroundCorners({{0, 0, 0}}, blocks);
    ASSERT_EQ(cubes.size(), 1u) << "the 7 other cubes lie in blocks that do not exist";
    EXPECT_EQ(cubes.at({0, 0, 0}).count(), 1u);
    EXPECT_TRUE(cubes.at({0, 0, 0}).test(0));
    for (int o = 1; o < 8; ++o) blocks[{-(o & 1), -((o >> 1) & 1), -((o >> 2) & 1)}];
    cubes = cpu::cubesAroundCorners({{0, 0, 0}}, blocks);
    EXPECT_EQ(cubes.size(), 8u);
    EXPECT_TRUE(cubes.at({-1, -1, -1}).test(cpu::localIndex(7, 7, 7)));
    EXPECT_TRUE(cubes.at({-1, 0, 0}).test(cpu::localIndex(7, 0, 0)));
    // An interior corner: its 8 cubes in its own block.
    cubes = cpu::cubesAroundCorners({{3, 4, 5}}, blocks);
    ASSERT_EQ(cubes.size(), 1u);
    EXPECT_EQ(cubes.at({0, 0, 0}).count(), 8u);
    EXPECT_TRUE(cubes.at({0, 0, 0}).test(cpu::localIndex(2, 3, 4)));
    EXPECT_TRUE(cubes.at({0, 0, 0}).test(cpu::localIndex(3, 4, 5)));
}

// ---- recycling ----------------------------------------------------------------------------------

TEST(ReferenceRecycling, KeepRadiusMeasuresFromTheBlockCentre) {
    const float atOrigin[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
    // Block (0,0,0) of 0.8 m has its centre at (0.4, 0.4, 0.4): 0.69 m away.
    EXPECT_TRUE(cpu::blockOutsideKeepRadius({0, 0, 0}, 0.1f, 0.6f, atOrigin));
    EXPECT_FALSE(cpu::blockOutsideKeepRadius({0, 0, 0}, 0.1f, 0.7f, atOrigin));
    EXPECT_FALSE(cpu::blockOutsideKeepRadius({50, 0, 0}, 0.1f, 0.0f, atOrigin)) << "0: no radius";
    const float away[3][4] = {{1, 0, 0, 40.4f}, {0, 1, 0, 0.4f}, {0, 0, 1, 0.4f}};
    EXPECT_FALSE(cpu::blockOutsideKeepRadius({50, 0, 0}, 0.1f, 0.1f, away));
}

TEST(ReferenceRecycling, StarvingBlocksLoseWeightUntilFreed) {
    const float camera[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
    const cpu::RecyclingRule rule{0.0f, 2, 1.0f};
    std::map<BlockCoord, cpu::ReferenceBlock> blocks;
    std::map<BlockCoord, uint32_t> lastTouched;
    blocks[{0, 0, 0}].weight.fill(3.0f);
    blocks[{1, 0, 0}].weight.fill(3.0f);
    blocks[{1, 0, 0}].weight[5] = 0.5f;
    lastTouched[{0, 0, 0}] = 1;
    lastTouched[{1, 0, 0}] = 1;
    auto s = cpu::recycleBlocks(blocks, lastTouched, 2, rule, 0.1f, 0.0001f, camera);
    EXPECT_EQ(s.blocksStarved, 0u) << "idle for 1 frame < 2";
    s = cpu::recycleBlocks(blocks, lastTouched, 3, rule, 0.1f, 0.0001f, camera);
    EXPECT_EQ(s.blocksStarved, 2u);
    EXPECT_EQ(blocks.at({0, 0, 0}).weight[0], 2.0f);
    EXPECT_EQ(blocks.at({1, 0, 0}).weight[5], 0.0f) << "clamped at 0";
    lastTouched[{1, 0, 0}] = 4;   // touched again: it stops starving
    s = cpu::recycleBlocks(blocks, lastTouched, 4, rule, 0.1f, 0.0001f, camera);
    EXPECT_EQ(s.blocksStarved, 1u);
    EXPECT_EQ(s.blocksFreed, 0u);
    s = cpu::recycleBlocks(blocks, lastTouched, 5, rule, 0.1f, 0.0001f, camera);
    EXPECT_EQ(s.blocksStarved, 1u);
    EXPECT_EQ(s.blocksFreed, 1u);
    EXPECT_EQ(blocks.count({0, 0, 0}), 0u);
    EXPECT_EQ(lastTouched.count({0, 0, 0}), 0u);
    EXPECT_EQ(blocks.at({1, 0, 0}).weight[0], 2.0f);
}

TEST(ReferenceRecycling, RetiredBlocksAreZeroedAndFreed) {
    const float camera[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
    std::map<BlockCoord, cpu::ReferenceBlock> blocks;
    std::map<BlockCoord, uint32_t> lastTouched;
    blocks[{0, 0, 0}].weight.fill(5.0f);
    blocks[{20, 0, 0}].weight.fill(5.0f);
    lastTouched[{0, 0, 0}] = lastTouched[{20, 0, 0}] = 1;
    EXPECT_EQ(cpu::recycleBlocks(blocks, lastTouched, 2, {}, 0.1f, 0.0001f, camera).blocksRetired, 0u) << "recycling off";
    EXPECT_EQ(blocks.size(), 2u);
    const auto s = cpu::recycleBlocks(blocks, lastTouched, 2, {3.0f, 0, 0.0f}, 0.1f, 0.0001f, camera);
    EXPECT_EQ(s.blocksRetired, 1u);
    EXPECT_EQ(s.blocksFreed, 1u);
    EXPECT_EQ(blocks.count({20, 0, 0}), 0u);
    EXPECT_EQ(blocks.at({0, 0, 0}).weight[0], 5.0f);
}

// ---- baseline and incremental mesh on a plane -------------------------------------------------

// A block whose TSDF is the plane z = planeZ (voxel units, local), every corner observed.
cpu::ReferenceBlock planeBlock(float planeZ, float voxelSize, float weight = 1.0f) {
    cpu::ReferenceBlock b;
    for (uint32_t v = 0; v < gpu::VOXELS_PER_BLOCK; ++v) {
        b.sdf[v] = (float(cpu::localCoords(v)[2]) - planeZ) * voxelSize;
        b.weight[v] = weight;
    }
    return b;
}

TEST(ReferenceBaseline, APlaneGivesTwoTrianglesPerCubeItCrosses) {
    const float voxel = 0.05f;
    std::map<BlockCoord, cpu::ReferenceBlock> blocks;
    blocks[{0, 0, 0}] = planeBlock(3.5f, voxel);
    auto soup = cpu::baselineMesh(blocks, voxel, 1.0f);
    // Without neighbours only the cubes with local x, y <= 6 have 8 corners: 7 x 7 cubes in the z = 3 layer.
    EXPECT_EQ(soup.size(), 3u * 2u * 49u);
    for (const auto& p : soup) EXPECT_EQ(p.z(), 3.5f * voxel);
    blocks[{0, 0, 0}].weight[cpu::localIndex(3, 3, 3)] = 0.5f;   // unobserved: its 4 surface cubes go
    EXPECT_EQ(cpu::baselineMesh(blocks, voxel, 1.0f).size(), 3u * 2u * 45u);
    EXPECT_EQ(cpu::baselineMesh(blocks, voxel, 0.5f).size(), 3u * 2u * 49u);
    blocks[{0, 0, 0}] = planeBlock(3.5f, voxel);
    blocks[{1, 0, 0}] = planeBlock(3.5f, voxel);   // the +x neighbour completes the cubes at local x = 7
    EXPECT_EQ(cpu::baselineMesh(blocks, voxel, 1.0f).size(), 3u * 2u * (49u + 7u + 49u));
}

TEST(ReferenceMesherPasses, ClaimUpdateTriangulateAndCollectOnAPlane) {
    VolumeParams params;
    params.voxelSize = 0.05f;
    cpu::ReferenceVolume volume(params);
    const BlockCoord coord{0, 0, 0};
    volume.setBlock(coord, planeBlock(3.5f, params.voxelSize));
    cpu::ReferenceMesher mesher(params, 1.0f, 1024, 1024);

    // Claim + triangulate: 49 cubes of 2 triangles share the 8 x 8 vertices on the z edges at z = 3.
    // The 3 x 49 cubes below the plane take type 255 (all corners inside), which has no triangles.
    auto s = mesher.updateAll(volume, 1);
    EXPECT_EQ(s.dirtyBlocks, 1u);
    EXPECT_EQ(s.cubesRetyped, 4u * 49u);
    EXPECT_EQ(s.verticesAllocated, 64u);
    EXPECT_EQ(s.trianglesCreated, 98u);
    EXPECT_EQ(s.chunksAllocated, 49u);
    EXPECT_EQ(s.verticesFreed, 0u);
    EXPECT_EQ(mesher.liveVertices(), 64u);
    EXPECT_EQ(mesher.liveChunks(), 49u);
    auto problems = mesher.checkInvariants();
    EXPECT_TRUE(problems.empty()) << joined(problems);
    Mesh mesh = mesher.exportMesh(1);
    ASSERT_EQ(mesh.positions.size(), 64u);
    EXPECT_EQ(mesh.triangles.size(), 98u);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        EXPECT_EQ(mesh.positions[i].z(), 3.5f * params.voxelSize);
        EXPECT_EQ(mesh.normals[i], Eigen::Vector3f(0, 0, 1)) << "the gradient of d = z - 3.5";
        EXPECT_EQ(mesh.vertexAge[i], 0u);
    }

    // Vertex update: the plane moves within the same cubes; no cube changes type, every vertex moves.
    volume.setBlock(coord, planeBlock(3.25f, params.voxelSize));
    s = mesher.update(volume, {coord}, 2, cpu::RetypeScope::AllCubes);
    EXPECT_EQ(s.cubesListed, gpu::VOXELS_PER_BLOCK);
    EXPECT_EQ(s.cubesRetyped, 0u);
    EXPECT_EQ(s.trianglesCreated + s.trianglesReleased + s.verticesAllocated, 0u);
    mesh = mesher.exportMesh(2);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        EXPECT_EQ(mesh.positions[i].z(), 3.25f * params.voxelSize);
        EXPECT_EQ(mesh.vertexAge[i], 1u);
    }

    // Garbage collection: the corners lose their observations; every triangle, vertex and chunk goes back.
    volume.setBlock(coord, planeBlock(3.25f, params.voxelSize, 0.0f));
    s = mesher.update(volume, {coord}, 3, cpu::RetypeScope::AllCubes);
    EXPECT_EQ(s.cubesRetyped, 4u * 49u);
    EXPECT_EQ(s.trianglesReleased, 98u);
    EXPECT_EQ(s.verticesFreed, 64u);
    EXPECT_EQ(s.chunksFreed, 49u);
    EXPECT_EQ(mesher.liveVertices(), 0u);
    EXPECT_EQ(mesher.liveChunks(), 0u);
    EXPECT_EQ(mesher.vertexHighWater(), 64u);
    for (uint32_t slot : mesher.blockStates().at(coord).edgeVertex) EXPECT_EQ(slot, gpu::EMPTY_SLOT);
    problems = mesher.checkInvariants();
    EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST(ReferenceMesherPasses, ExhaustedHeapsLeaveIncompleteCubesAndConsistentState) {
    VolumeParams params;
    params.voxelSize = 0.05f;
    cpu::ReferenceVolume volume(params);
    volume.setBlock({0, 0, 0}, planeBlock(3.5f, params.voxelSize));

    cpu::ReferenceMesher fewChunks(params, 1.0f, 1024, 5);
    auto s = fewChunks.updateAll(volume, 1);
    EXPECT_EQ(s.chunksAllocated, 5u);
    EXPECT_EQ(s.chunkExhausted, 44u);
    EXPECT_EQ(s.trianglesCreated, 10u);
    EXPECT_EQ(s.trianglesInvalid, 88u);
    EXPECT_EQ(fewChunks.incompleteCubes(), 44u);
    auto problems = fewChunks.checkInvariants();
    EXPECT_TRUE(problems.empty()) << joined(problems);

    cpu::ReferenceMesher fewVertices(params, 1.0f, 10, 1024);
    s = fewVertices.updateAll(volume, 1);
    EXPECT_EQ(s.verticesAllocated, 10u);
    EXPECT_GT(s.vertexExhausted, 0u);
    EXPECT_GT(s.trianglesInvalid, 0u);
    EXPECT_LT(s.trianglesCreated, 98u);
    EXPECT_GT(fewVertices.incompleteCubes(), 0u);
    EXPECT_LE(fewVertices.liveVertices(), 10u);
    problems = fewVertices.checkInvariants();
    EXPECT_TRUE(problems.empty()) << joined(problems);
}

}  // namespace
}  // namespace vkmesh
