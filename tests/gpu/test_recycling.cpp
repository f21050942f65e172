// Bounded maps (docs/MESH.md, "Recycling blocks"): blocks beyond the keep radius and starved idle blocks are
// freed with their TSDF, their triangles and their vertices. Checked against the CPU reference (the same
// blocks removed, the same starvation, TSDF bit for bit), against a from-scratch rebuild of the mesh on the
// remaining TSDF, and against the heap invariants, frame after frame, with the validation layer on.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <filesystem>
#include <cstring>
#include <iostream>
#include <map>
#include <set>

#include "core/mesh_analysis.h"
#include "core/refinement.h"
#include "cpu/reference_volume.h"
#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "mesh_checks.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using test::checkInvariants;
using test::GpuTest;
using test::soupOf;

constexpr int kWidth = 160, kHeight = 120;

gpu::GpuVolumeConfig recyclingConfig(float keepRadius, bool recycle) {
    gpu::GpuVolumeConfig c = test::smallRoomConfig();
    c.keepRadius = keepRadius;
    c.recycle = recycle;
    c.recycleAfterFrames = 4;   // short, so that a 36-frame run starves and frees blocks
    c.starveWeight = 3.0f;
    // Small, so that the tombstones of freed keys trigger hash rebuilds within the run.
    c.hashRebuildTombstoneFraction = 0.01f;
    return c;
}

// Compares the GPU's blocks with the reference's: the same coordinates, TSDF bit for bit. Returns problems.
std::vector<std::string> compareTsdf(const gpu::GpuVolume& volume, const cpu::ReferenceVolume& reference) {
    std::vector<std::string> problems;
    auto gpuBlocks = volume.downloadBlocks();
    std::map<cpu::BlockCoord, const gpu::BlockSnapshot*> byCoord;
    for (const auto& b : gpuBlocks) byCoord[{b.coord.x(), b.coord.y(), b.coord.z()}] = &b;
    if (byCoord.size() != reference.blocks().size())
        problems.push_back("GPU has " + std::to_string(byCoord.size()) + " blocks, reference " + std::to_string(reference.blocks().size()));
    for (const auto& [coord, block] : reference.blocks()) {
        auto it = byCoord.find(coord);
        if (it == byCoord.end()) {
            problems.push_back("block missing on the GPU");
            continue;
        }
        if (std::memcmp(it->second->sdf.data(), block.sdf.data(), sizeof(block.sdf)) != 0 ||
            std::memcmp(it->second->weight.data(), block.weight.data(), sizeof(block.weight)) != 0)
            problems.push_back("TSDF of a block differs");
        if (problems.size() > 5) break;
    }
    return problems;
}

struct RunTotals {
    uint64_t freed = 0, starved = 0, retired = 0, rebuilds = 0, outsideRadius = 0;
};

// Runs `frames` frames of the room along a revisiting path on the GPU and the CPU reference with the same
// recycling settings, checking TSDF, counters and mesh invariants as it goes.
RunTotals runAndCompare(vk::Context& context, const gpu::GpuVolumeConfig& config, size_t frames, size_t pathLength) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    gpu::GpuVolume volume(context, config);
    cpu::ReferenceVolume reference(config.params, config.minMeshWeight);
    reference.setRecycling(config.keepRadius, config.recycle ? config.recycleAfterFrames : 0u, config.starveWeight);
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    auto poses = synth::cameraPath(pathLength, synth::PathKind::Orbit);
    RunTotals totals;
    for (size_t i = 0; i < frames; ++i) {
        synth::RenderOptions options;
        options.noise = true;
        options.seed = uint32_t(i + 1);
        const Pose& pose = poses[i % poses.size()];
        DepthImage depth = scene.renderDepth(intr, pose, options);
        gpu::FrameReport r = volume.integrate(depth, intr, pose);
        cpu::ReferenceFrameStats s = reference.integrate(depth, intr, pose);
        const gpu::Counters& k = r.counters;
        EXPECT_TRUE(r.warnings.empty()) << "frame " << i << ": " << r.warnings.front();
        EXPECT_EQ(k.outsideRadius, s.outsideRadius) << "frame " << i;
        EXPECT_EQ(k.blocksRetired, s.blocksRetired) << "frame " << i;
        EXPECT_EQ(k.blocksStarved, s.blocksStarved) << "frame " << i;
        EXPECT_EQ(k.blocksFreed, s.blocksFreed) << "frame " << i;
        EXPECT_EQ(k.recycleDeferred, 0u) << "frame " << i << ": an empty block still owned mesh state after the mesh passes";
        EXPECT_EQ(k.rehashLost, 0u) << "frame " << i;
        EXPECT_EQ(k.freeTop + k.blocksInUse, config.blockCapacity) << "frame " << i;
        EXPECT_EQ(k.blocksInUse, reference.blocks().size()) << "frame " << i;
        EXPECT_EQ(k.hashEntries, k.blocksInUse) << "frame " << i << ": every key holds a block (the pool is ample)";
        totals.freed += k.blocksFreed;
        totals.starved += k.blocksStarved;
        totals.retired += k.blocksRetired;
        totals.rebuilds += k.hashRebuilt;
        totals.outsideRadius += k.outsideRadius;
        if (i % 6 == 5 || i + 1 == frames) {
            auto tsdf = compareTsdf(volume, reference);
            EXPECT_TRUE(tsdf.empty()) << "frame " << i << ": " << tsdf.front();
            gpu::MeshStateSnapshot state = volume.downloadMeshState();
            auto problems = checkInvariants(state, volume.config());
            EXPECT_TRUE(problems.empty()) << "frame " << i << ": " << problems.front();
            // Every live vertex sits on an edge of a live block: a freed block took its vertices with it.
            std::set<uint32_t> live;
            for (const auto& b : volume.downloadBlocks()) live.insert(b.index);
            size_t orphans = 0;
            for (uint32_t v = 0; v < state.vertices.size(); ++v)
                if (state.vertices[v].refcount != gpu::DEAD_REFCOUNT && !live.count(state.vertexOwner[v] / (3 * gpu::VOXELS_PER_BLOCK)))
                    ++orphans;
            EXPECT_EQ(orphans, 0u) << "frame " << i << ": vertices owned by freed blocks";
        }
    }
    std::cout << "  recycling totals: freed " << totals.freed << ", retired " << totals.retired << ", starved " << totals.starved
              << ", hash rebuilds " << totals.rebuilds << ", blocks left " << reference.blocks().size() << "\n";
    // The incremental mesh equals a from-scratch extraction of what is left.
    gpu::ExportedMesh incremental = volume.exportMesh();
    EXPECT_EQ(incremental.unreferencedVertices, 0u);
    volume.rebuildMesh();
    gpu::ExportedMesh scratch = volume.exportMesh();
    EXPECT_GT(scratch.triangles.size(), 100u);
    EXPECT_EQ(incremental.vertices.size(), scratch.vertices.size());
    EXPECT_EQ(canonicalTriangles(soupOf(incremental)), canonicalTriangles(soupOf(scratch)));
    // And, unrefined, the baseline of the reference's TSDF (the CPU removed the same blocks) is the same surface
    // (the baseline is plain MC; with refinement, on by default, incremental == from scratch above is the check).
    if (!config.refine) {
        EXPECT_EQ(canonicalTriangles(soupOf(incremental)), canonicalTriangles(reference.extractBaselineMesh()));
    }
    return totals;
}

TEST_F(GpuTest, KeepRadiusFreesBlocksConsistently) {
    RunTotals t = runAndCompare(context(), recyclingConfig(1.8f, false), 36, 24);
    EXPECT_GT(t.retired, 0u);
    EXPECT_GT(t.freed, 50u);
    EXPECT_GT(t.outsideRadius, 0u);
    EXPECT_EQ(t.starved, 0u);
    EXPECT_GT(t.rebuilds, 0u);
}

TEST_F(GpuTest, StarvationFreesIdleBlocksConsistently) {
    RunTotals t = runAndCompare(context(), recyclingConfig(0.0f, true), 36, 24);
    EXPECT_GT(t.starved, 0u);
    EXPECT_GT(t.freed, 0u);
    EXPECT_EQ(t.retired, 0u);
    EXPECT_EQ(t.outsideRadius, 0u);
}

TEST_F(GpuTest, RadiusAndStarvationTogether) {
    gpu::GpuVolumeConfig config = recyclingConfig(2.2f, true);
    config.refine = false;   // unrefined: also compared with the CPU reference's baseline mesh
    RunTotals t = runAndCompare(context(), config, 36, 24);
    EXPECT_GT(t.freed, 0u);
    EXPECT_GT(t.retired + t.starved, 0u);
}

// The paper's lock-free claims (4 parity-class passes) free the same blocks and keep the same invariants.
TEST_F(GpuTest, RecyclingWithLockFreeClaims) {
    auto config = recyclingConfig(2.2f, true);
    config.lockFree = true;
    RunTotals t = runAndCompare(context(), config, 24, 24);
    EXPECT_GT(t.freed, 0u);
}

// Off by default: no recycling counter moves and the hash keeps no tombstones.
TEST_F(GpuTest, RecyclingIsOffByDefault) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    gpu::GpuVolume volume(context(), recyclingConfig(0.0f, false));
    EXPECT_FALSE(volume.recycling());
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    auto poses = synth::cameraPath(24, synth::PathKind::Orbit);
    for (size_t i = 0; i < 8; ++i) {
        auto r = volume.integrate(scene.renderDepth(intr, poses[i], {}), intr, poses[i]);
        EXPECT_EQ(r.counters.blocksFreed + r.counters.blocksRetired + r.counters.blocksStarved + r.counters.outsideRadius, 0u);
        EXPECT_EQ(r.counters.hashTombstones, 0u);
        EXPECT_EQ(r.counters.hashEntries, r.counters.blocksInUse);
    }
}

// `vkmesh soak` writes one CSV row per frame with the occupancy columns, and `fuse --keep-radius --recycle`
// reports what recycling did in its --stats JSON.
TEST_F(GpuTest, CliSoakAndFuseWithBoundedMaps) {
    auto dir = test::makeTempDir("recycling_cli");
    auto soak = test::runCli("soak -o " + (dir / "soak.csv").string() + " --frames 40 --laps 2 --rooms 2 --keep-radius 2 --recycle");
    ASSERT_EQ(soak.exitCode, 0) << soak.err;
    const std::string csv = test::readText(dir / "soak.csv");
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 41);
    EXPECT_EQ(csv.rfind("frame,lap,hash_entries,hash_tombstones,hash_rebuilt,blocks_in_use,vertices_in_use,chunks_in_use", 0), 0u);
    EXPECT_NE(soak.out.find("high water per lap"), std::string::npos) << soak.out;
    auto synthRun = test::runCli("synth " + (dir / "seq").string() + " --frames 12 --width 160 --height 120 --gt-spacing 0.05");
    ASSERT_EQ(synthRun.exitCode, 0) << synthRun.err;
    auto fuse = test::runCli("fuse " + (dir / "seq").string() + " -o " + (dir / "mesh.ply").string() + " --stats " +
                             (dir / "stats.json").string() + " --voxel 0.04 --keep-radius 1.5 --recycle --recycle-after 3 -q");
    ASSERT_EQ(fuse.exitCode, 0) << fuse.err;
    const std::string stats = test::readText(dir / "stats.json");
    for (const char* key : {"\"keep_radius\": 1.5", "\"blocks_freed\"", "\"blocks_retired\"", "\"blocks_starved\"",
                            "\"hash_tombstones\"", "\"outside_keep_radius\""})
        EXPECT_NE(stats.find(key), std::string::npos) << key;
    std::filesystem::remove_all(dir);
}


// With refinement (on by default) the masks of the TSDF that decide_mesh_signs reads stay exact through fusion,
// starving, retiring, freeing and pool growth: every live block's masks equal those of its downloaded TSDF, a
// free block's are zero, and every live block's stored meshing signs equal the host twin of the GPU's word
// decision (refinedSignWord, itself tested against refinedCornerInside) over its downloaded neighbourhood.
TEST_F(GpuTest, RefinementMasksAndSignsFollowTheTsdfThroughRecyclingAndGrowth) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    gpu::GpuVolumeConfig config = recyclingConfig(1.5f, true);
    config.blockCapacity = 64;   // grows several times (masks and signs are copied with the TSDF)
    ASSERT_TRUE(config.refine);
    gpu::GpuVolume volume(context(), config);
    const float epsilon = config.refineEpsilonVoxels * config.params.voxelSize;
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    auto poses = synth::cameraPath(30, synth::PathKind::Orbit);
    uint64_t freed = 0, checkedBlocks = 0, flips = 0;
    for (size_t i = 0; i < poses.size(); ++i) {
        synth::RenderOptions options;
        options.noise = true;
        options.seed = uint32_t(i + 1);
        auto r = volume.integrate(scene.renderDepth(intr, poses[i], options), intr, poses[i]);
        freed += r.counters.blocksFreed;
        if (i % 6 != 5) continue;
        const std::vector<uint32_t> words = volume.downloadMeshSigns();
        const std::vector<gpu::BlockSnapshot> blocks = volume.downloadBlocks();
        std::map<cpu::BlockCoord, TsdfMasks> masks;
        std::vector<bool> live(words.size() / gpu::MESH_SIGN_WORDS, false);
        for (const gpu::BlockSnapshot& b : blocks) {
            live[b.index] = true;
            const TsdfMasks m = tsdfMasks(b.sdf.data(), b.weight.data(), config.minMeshWeight, epsilon);
            masks[{b.coord.x(), b.coord.y(), b.coord.z()}] = m;
            const uint32_t* w = &words[size_t(b.index) * gpu::MESH_SIGN_WORDS];
            for (uint32_t k = 0; k < gpu::MASK_WORDS; ++k) {
                ASSERT_EQ(w[gpu::MESH_SIGN_GROUP * k + gpu::MESH_SIGN_RAW], m.raw[k]) << "frame " << i << " block " << b.index << " word " << k;
                ASSERT_EQ(w[gpu::MESH_SIGN_GROUP * k + gpu::MESH_SIGN_NEAR], m.near[k]) << "frame " << i << " block " << b.index << " word " << k;
                ASSERT_EQ(w[gpu::MESH_SIGN_GROUP * k + gpu::MESH_SIGN_OBSERVED], m.observed[k]) << "frame " << i << " block " << b.index << " word " << k;
            }
        }
        for (size_t b = 0; b < live.size(); ++b) {
            if (live[b]) continue;
            for (uint32_t k = 0; k < gpu::MESH_SIGN_WORDS; ++k) ASSERT_EQ(words[b * gpu::MESH_SIGN_WORDS + k], 0u) << "free block " << b;
        }
        for (const gpu::BlockSnapshot& b : blocks) {
            std::array<const TsdfMasks*, 27> around{};
            for (int n = 0; n < 27; ++n) {
                auto it = masks.find({b.coord.x() + n % 3 - 1, b.coord.y() + (n / 3) % 3 - 1, b.coord.z() + n / 9 - 1});
                if (it != masks.end()) around[size_t(n)] = &it->second;
            }
            for (uint32_t k = 0; k < gpu::MASK_WORDS; ++k) {
                const uint32_t expected = refinedSignWord(around, k);
                ASSERT_EQ(words[size_t(b.index) * gpu::MESH_SIGN_WORDS + gpu::MESH_SIGN_GROUP * k + gpu::MESH_SIGN_MESHING], expected) << "frame " << i << " block " << b.index << " word " << k;
                flips += uint64_t(std::popcount(expected ^ masks[{b.coord.x(), b.coord.y(), b.coord.z()}].raw[k]));
            }
            ++checkedBlocks;
        }
    }
    std::cout << checkedBlocks << " blocks checked, " << flips << " refined corners, " << freed << " blocks freed, pool "
              << volume.config().blockCapacity << " blocks\n";
    EXPECT_GT(freed, 0u);
    EXPECT_GT(flips, 0u);
    EXPECT_GT(volume.config().blockCapacity, 64u);
}

}  // namespace
}  // namespace vkmesh
