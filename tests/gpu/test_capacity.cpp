// Capacity exhaustion (issue 5, item 2): the hash table, the block pool, the vertex heap and the triangle-chunk
// heap are each forced full with tiny capacities. Every time: a warning with the counts, nothing crashes or
// hangs, the mesh built so far stays consistent and exportable (no index out of range, no dead vertex
// referenced), the blocks that were fused keep their TSDF bit for bit (against the CPU reference, which has
// no limits), and once there is room again the missing triangles appear.
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <string>

#include "core/mesh_analysis.h"
#include "cpu/reference_volume.h"
#include "gpu/gpu_volume.h"
#include "io/ply.h"
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

// Fixed capacities: these tests are about what is reported and kept when a capacity is exhausted
// (growCapacities off, as with `fuse --no-grow`); test_growth.cpp covers growing past them.
gpu::GpuVolumeConfig smallConfig() {
    gpu::GpuVolumeConfig c = test::smallRoomConfig();
    c.growCapacities = false;
    return c;
}

struct FusedRun {
    std::vector<gpu::FrameReport> reports;
};

// Fuses `frames` views of the room into the GPU volume and, when given, the CPU reference.
FusedRun fuseRoom(gpu::GpuVolume& volume, cpu::ReferenceVolume* reference, size_t frames, size_t firstFrame = 0) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    auto poses = synth::cameraPath(24, synth::PathKind::Orbit);
    FusedRun run;
    for (size_t i = firstFrame; i < firstFrame + frames; ++i) {
        synth::RenderOptions options;
        options.noise = true;
        options.seed = uint32_t(i + 1);
        const Pose& pose = poses[i % poses.size()];
        DepthImage depth = scene.renderDepth(intr, pose, options);
        run.reports.push_back(volume.integrate(depth, intr, pose));
        if (reference) reference->integrate(depth, intr, pose);
    }
    return run;
}

// The first warning of any frame that contains `needle`, or "".
std::string findWarning(const FusedRun& run, const std::string& needle) {
    for (const auto& r : run.reports)
        for (const auto& w : r.warnings)
            if (w.find(needle) != std::string::npos) return w;
    return "";
}

// Every block the GPU holds equals the reference's block of the same coordinate, bit for bit. With
// `sameSet`, the GPU holds every reference block too. Returns the number of GPU blocks compared.
size_t expectTsdfMatches(const gpu::GpuVolume& volume, const cpu::ReferenceVolume& reference, bool sameSet) {
    auto blocks = volume.downloadBlocks();
    size_t differing = 0, unknown = 0;
    for (const auto& b : blocks) {
        auto it = reference.blocks().find({b.coord.x(), b.coord.y(), b.coord.z()});
        if (it == reference.blocks().end()) { ++unknown; continue; }
        if (std::memcmp(b.sdf.data(), it->second.sdf.data(), sizeof(it->second.sdf)) != 0 ||
            std::memcmp(b.weight.data(), it->second.weight.data(), sizeof(it->second.weight)) != 0)
            ++differing;
    }
    EXPECT_EQ(unknown, 0u) << "GPU blocks the reference never allocated";
    EXPECT_EQ(differing, 0u) << "GPU blocks whose TSDF differs from the reference";
    if (sameSet) {
        EXPECT_EQ(blocks.size(), reference.blocks().size());
    }
    return blocks.size();
}

// The mesh is consistent and exportable: heap invariants, every index in range, every exported vertex used
// and alive.
gpu::ExportedMesh expectMeshExportable(gpu::GpuVolume& volume) {
    auto problems = checkInvariants(volume.downloadMeshState(), volume.config());
    EXPECT_TRUE(problems.empty()) << problems.front();
    gpu::ExportedMesh mesh = volume.exportMesh();
    EXPECT_EQ(mesh.unreferencedVertices, 0u);
    size_t outOfRange = 0, dead = 0;
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t) outOfRange += v >= mesh.vertices.size();
    for (const auto& v : mesh.vertices) dead += v.refcount == 0 || v.refcount == gpu::DEAD_REFCOUNT;
    EXPECT_EQ(outOfRange, 0u) << "triangle indices out of range";
    EXPECT_EQ(dead, 0u) << "exported vertices without triangles or freed";
    return mesh;
}

TEST_F(GpuTest, FullHashIsReportedAndFusedBlocksAreKept) {
    auto config = smallConfig();
    config.hashCapacity = 64;   // the room needs hundreds of blocks
    gpu::GpuVolume volume(context(), config);
    cpu::ReferenceVolume reference(config.params, config.minMeshWeight);
    FusedRun run = fuseRoom(volume, &reference, 6);
    EXPECT_GT(run.reports[0].counters.hashFull, 0u);
    const std::string w = findWarning(run, "found no free hash slot");
    ASSERT_FALSE(w.empty());
    EXPECT_NE(w.find(std::to_string(run.reports[0].counters.hashFull)), std::string::npos) << w;
    EXPECT_NE(w.find("hash capacity 64"), std::string::npos) << w;
    // A key that found no slot never will (nothing is removed), so every block got its memory at its first
    // touch and saw the same frames as the reference's.
    EXPECT_EQ(expectTsdfMatches(volume, reference, false), 64u);
    gpu::ExportedMesh mesh = expectMeshExportable(volume);
    EXPECT_GT(mesh.triangles.size(), 0u);
    volume.rebuildMesh();
    EXPECT_EQ(canonicalTriangles(soupOf(mesh)), canonicalTriangles(soupOf(volume.exportMesh())));
}

TEST_F(GpuTest, ExhaustedBlockPoolIsReportedAndFusedBlocksAreKept) {
    auto config = smallConfig();
    config.blockCapacity = 48;
    config.touchedCapacity = 4096;   // the pool is the limit here, not the frame's touched list
    gpu::GpuVolume volume(context(), config);
    cpu::ReferenceVolume reference(config.params, config.minMeshWeight);
    auto before = volume.downloadBlocks();
    FusedRun run = fuseRoom(volume, &reference, 6);
    EXPECT_GT(run.reports[0].counters.poolExhausted, 0u);
    const std::string w = findWarning(run, "block pool exhausted");
    ASSERT_FALSE(w.empty());
    EXPECT_NE(w.find(std::to_string(run.reports[0].counters.poolExhausted) + " new blocks got no memory"), std::string::npos) << w;
    EXPECT_EQ(run.reports.back().counters.blocksInUse, 48u);
    EXPECT_EQ(run.reports.back().counters.freeTop, 0u);
    // The pool never gets room again, so every block got memory at its first touch.
    EXPECT_EQ(expectTsdfMatches(volume, reference, false), 48u);
    // Exporting, counting and re-reading leave the TSDF alone.
    auto fused = volume.downloadBlocks();
    gpu::ExportedMesh mesh = expectMeshExportable(volume);
    volume.countBaselineVertices();
    auto after = volume.downloadBlocks();
    ASSERT_EQ(fused.size(), after.size());
    for (size_t i = 0; i < fused.size(); ++i) {
        EXPECT_EQ(fused[i].coord, after[i].coord);
        EXPECT_EQ(std::memcmp(fused[i].sdf.data(), after[i].sdf.data(), fused[i].sdf.size() * 4), 0);
        EXPECT_EQ(std::memcmp(fused[i].weight.data(), after[i].weight.data(), fused[i].weight.size() * 4), 0);
    }
    volume.rebuildMesh();
    EXPECT_EQ(canonicalTriangles(soupOf(mesh)), canonicalTriangles(soupOf(volume.exportMesh())));
}

// With a keep radius, blocks the camera leaves are freed: keys that got no memory while the pool was full get
// it when touched again, and the map is complete around the camera.
TEST_F(GpuTest, BlockPoolHasRoomAgainAfterRecycling) {
    auto config = smallConfig();
    config.blockCapacity = 64;       // 41 to 75 blocks lie within the radius along this path
    config.touchedCapacity = 4096;
    config.keepRadius = 1.8f;
    gpu::GpuVolume volume(context(), config);
    FusedRun run = fuseRoom(volume, nullptr, 27);
    uint64_t exhausted = 0;
    for (const auto& r : run.reports) exhausted += r.counters.poolExhausted;
    EXPECT_GT(exhausted, 0u) << "the test needs the pool to fill up";
    uint64_t freed = 0;
    for (const auto& r : run.reports) freed += r.counters.blocksFreed;
    EXPECT_GT(freed, 0u);
    // Where the camera has fewer surfaces within the radius than the pool holds, every touched key gets memory:
    // the last frames are served in full.
    size_t lastExhausted = run.reports.size();
    for (size_t i = 0; i < run.reports.size(); ++i)
        if (run.reports[i].counters.poolExhausted) lastExhausted = i;
    EXPECT_LT(lastExhausted + 1, run.reports.size()) << "the pool never had room again";
    gpu::ExportedMesh mesh = expectMeshExportable(volume);
    volume.rebuildMesh();
    EXPECT_EQ(canonicalTriangles(soupOf(mesh)), canonicalTriangles(soupOf(volume.exportMesh())));
}

void heapExhaustionAndGrowth(vk::Context& context, bool vertexHeap) {
    auto config = smallConfig();
    (vertexHeap ? config.vertexCapacity : config.chunkCapacity) = 256;
    config.refine = false;   // the complete mesh is compared with the (unrefined) baseline below
    gpu::GpuVolume volume(context, config);
    cpu::ReferenceVolume reference(config.params, config.minMeshWeight);
    FusedRun run = fuseRoom(volume, &reference, 4);
    const gpu::Counters& first = run.reports[0].counters;
    EXPECT_GT(vertexHeap ? first.vertexExhausted : first.chunkExhausted, 0u);
    EXPECT_GT(first.trianglesInvalid, 0u);
    const std::string w = findWarning(run, vertexHeap ? "vertex heap exhausted" : "triangle chunk heap exhausted");
    ASSERT_FALSE(w.empty());
    EXPECT_NE(w.find(std::to_string(vertexHeap ? first.vertexExhausted : first.chunkExhausted)), std::string::npos) << w;
    EXPECT_NE(w.find("capacity 256"), std::string::npos) << w;
    // The TSDF does not depend on the mesh heaps: all of it equals the reference.
    expectTsdfMatches(volume, reference, true);
    gpu::ExportedMesh partial = expectMeshExportable(volume);
    EXPECT_GT(partial.triangles.size(), 0u);

    // Room again: the heaps grow, and the next frame re-meshes every INCOMPLETE cube, not only those the
    // camera touches: the mesh is then exactly a from-scratch extraction.
    volume.growMeshHeaps(1u << 17, 1u << 17);
    EXPECT_EQ(volume.readCounters().vertexFreeTop + volume.readCounters().verticesInUse, 1u << 17);
    FusedRun more = fuseRoom(volume, &reference, 1, 4);
    EXPECT_TRUE(more.reports[0].warnings.empty()) << more.reports[0].warnings.front();
    EXPECT_GT(more.reports[0].counters.dirtyCount, more.reports[0].counters.touchedCount);
    expectTsdfMatches(volume, reference, true);
    gpu::ExportedMesh complete = expectMeshExportable(volume);
    EXPECT_GT(complete.triangles.size(), 4 * partial.triangles.size());
    gpu::TriangleSoup baseline = volume.extractBaselineMesh();
    EXPECT_EQ(canonicalTriangles(soupOf(complete)), canonicalTriangles(baseline.vertices));
    volume.rebuildMesh();
    gpu::ExportedMesh scratch = volume.exportMesh();
    EXPECT_EQ(complete.vertices.size(), scratch.vertices.size());
    EXPECT_EQ(canonicalTriangles(soupOf(complete)), canonicalTriangles(soupOf(scratch)));
}

TEST_F(GpuTest, ExhaustedVertexHeapIsReportedAndFilledInAfterGrowth) { heapExhaustionAndGrowth(context(), true); }

TEST_F(GpuTest, ExhaustedChunkHeapIsReportedAndFilledInAfterGrowth) { heapExhaustionAndGrowth(context(), false); }

// The CLI prints the warnings and its --stats JSON carries the counts (--no-grow: fixed capacities). By
// default the same tiny capacities grow: no warning, and the mesh of ample capacities.
TEST_F(GpuTest, CliReportsCapacityEvents) {
    auto dir = test::makeTempDir("capacity_cli");
    auto synthRun = test::runCli("synth " + (dir / "seq").string() + " --frames 3 --width 160 --height 120 --gt-spacing 0.05");
    ASSERT_EQ(synthRun.exitCode, 0) << synthRun.err;
    const std::string tiny = " --voxel 0.04 --vertices 256 --chunks 256 --blocks 64 -q";
    auto run = test::runCli("fuse " + (dir / "seq").string() + " -o " + (dir / "mesh.ply").string() + " --stats " +
                            (dir / "stats.json").string() + tiny + " --no-grow");
    ASSERT_EQ(run.exitCode, 0) << run.err;
    EXPECT_NE(run.err.find("block pool exhausted"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find("vertex heap exhausted"), std::string::npos) << run.err;
    const std::string stats = test::readText(dir / "stats.json");
    for (const char* key : {"\"pool_exhausted\"", "\"vertex_heap_exhausted\"", "\"chunk_heap_exhausted\"", "\"triangles_not_built\"",
                            "\"hash_full\"", "\"blocks_freed\"", "\"frames_deferred\"", "\"capacity_growth\""})
        EXPECT_NE(stats.find(key), std::string::npos) << key;
    auto grown = test::runCli("fuse " + (dir / "seq").string() + " -o " + (dir / "grown.ply").string() + " --stats " +
                              (dir / "grown.json").string() + tiny);
    ASSERT_EQ(grown.exitCode, 0) << grown.err;
    EXPECT_EQ(grown.err.find("warning"), std::string::npos) << grown.err;
    const std::string grownStats = test::readText(dir / "grown.json");
    EXPECT_NE(grownStats.find("block pool 64 -> "), std::string::npos) << grownStats;
    // The deprecated --grow-heaps is accepted and says so.
    auto ample = test::runCli("fuse " + (dir / "seq").string() + " -o " + (dir / "ample.ply").string() + " --voxel 0.04 -q --grow-heaps");
    ASSERT_EQ(ample.exitCode, 0) << ample.err;
    EXPECT_NE(ample.err.find("deprecated"), std::string::npos) << ample.err;
    Mesh a = readPly(dir / "grown.ply"), b = readPly(dir / "ample.ply");
    EXPECT_EQ(a.positions.size(), b.positions.size());
    EXPECT_EQ(canonicalTriangles(a), canonicalTriangles(b));
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace vkmesh
