// Mesh deltas (docs/DELTAS.md): a viewer that only ever receives the per-frame deltas holds exactly the
// mesh vkmesh holds, frame after frame, through vertex moves, removals, id reuse, list growth and a
// from-scratch rebuild; the stream file carries the same deltas and rejects a damaged file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "api/exported_mesh.h"
#include "core/mesh_analysis.h"
#include "core/mesh_delta.h"
#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "mesh_checks.h"
#include "io/delta_stream.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

constexpr int kWidth = 160, kHeight = 120;

gpu::GpuVolumeConfig deltaConfig() {
    gpu::GpuVolumeConfig c = test::smallRoomConfig();
    c.trackDeltas = true;
    return c;
}

class MeshDeltas : public test::GpuTest {
protected:
    // Integrates `count` noisy frames of the default room; checks the replica after each.
    void integrateAndCheck(gpu::GpuVolume& volume, MeshReplica& replica, size_t first, size_t count,
                           std::vector<MeshDelta>* deltas = nullptr) {
        static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
        const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
        const auto poses = synth::cameraPath(24);
        for (size_t i = first; i < first + count; ++i) {
            synth::RenderOptions options;
            options.noise = true;   // noise moves vertices from frame to frame: CHANGED records
            options.seed = uint32_t(i + 1);
            gpu::FrameReport report = volume.integrate(scene.renderDepth(intr, poses[i % poses.size()], options), intr, poses[i % poses.size()]);
            EXPECT_EQ(report.delta.frame, volume.frameNumber());
            replica.apply(report.delta);
            for (int k = 0; k < 3; ++k) kinds_[k] += report.delta.count(DeltaKind(k));
            exhausted_ += report.counters.vertexExhausted + report.counters.chunkExhausted;
            if (deltas) deltas->push_back(report.delta);
            expectSameMesh(volume, replica, "frame " + std::to_string(i + 1));
        }
    }

    void expectSameMesh(gpu::GpuVolume& volume, const MeshReplica& replica, const std::string& where) {
        gpu::ExportedMesh exported = volume.exportMesh();
        Mesh fromDeltas = replica.toMesh();
        EXPECT_EQ(fromDeltas.positions.size(), exported.vertices.size()) << where;
        EXPECT_EQ(fromDeltas.triangles.size(), exported.triangles.size()) << where;
        // Exact: the records carry the vertices' bits.
        EXPECT_EQ(countTriangleMismatches(canonicalTriangles(fromDeltas), canonicalTriangles(toMesh(exported)), 0), 0u) << where;
    }

    size_t kinds_[3] = {0, 0, 0};
    uint64_t exhausted_ = 0;
};

TEST_F(MeshDeltas, ReplicaFollowsTheMeshFrameByFrame) {
    gpu::GpuVolume volume(context(), deltaConfig());
    MeshReplica replica;
    integrateAndCheck(volume, replica, 0, 10);
    EXPECT_GT(kinds_[uint32_t(DeltaKind::Added)], 10000u);
    EXPECT_GT(kinds_[uint32_t(DeltaKind::Changed)], 0u) << "noisy frames move vertices";
    EXPECT_GT(kinds_[uint32_t(DeltaKind::Removed)], 0u) << "retyped cubes remove triangles";
    EXPECT_GT(replica.triangleCount(), 5000u);
}

TEST_F(MeshDeltas, RecordListsGrowWithoutLosingChanges) {
    gpu::GpuVolumeConfig config = deltaConfig();
    config.deltaRecordCapacity = 64;   // the first frame alone has thousands of records
    gpu::GpuVolume volume(context(), config);
    MeshReplica replica;
    integrateAndCheck(volume, replica, 0, 3);
    EXPECT_GT(kinds_[uint32_t(DeltaKind::Added)], 64u * 10);
}

TEST_F(MeshDeltas, FollowHeapExhaustionGrowthAndRecycling) {
    gpu::GpuVolumeConfig config = deltaConfig();
    config.vertexCapacity = 1024;   // exhausted on the first frames: triangles missing, then added after growth
    config.chunkCapacity = 512;
    config.keepRadius = 2.0f;       // blocks leave the map with their triangles: removals
    config.growCapacities = false;  // the heaps run out and are grown by hand (test_growth.cpp: by themselves)
    gpu::GpuVolume volume(context(), config);
    MeshReplica replica;
    integrateAndCheck(volume, replica, 0, 2);
    EXPECT_GT(exhausted_, 0u) << "the heaps must run out";
    volume.growMeshHeaps(1u << 17, 1u << 17);
    integrateAndCheck(volume, replica, 2, 6);
    EXPECT_GT(kinds_[uint32_t(DeltaKind::Removed)], 0u);
}

TEST_F(MeshDeltas, ARebuildIsReportedAsADelta) {
    gpu::GpuVolume volume(context(), deltaConfig());
    MeshReplica replica;
    integrateAndCheck(volume, replica, 0, 4);
    // A from-scratch rebuild re-creates every vertex and triangle under new ids; the next frame's delta
    // tells the viewer (removals of the old ids, additions of the new), nothing else is needed.
    volume.rebuildMesh();
    integrateAndCheck(volume, replica, 4, 2);
}

TEST_F(MeshDeltas, StreamFileRoundTripsAndRejectsDamage) {
    gpu::GpuVolume volume(context(), deltaConfig());
    MeshReplica live;
    std::vector<MeshDelta> deltas;
    integrateAndCheck(volume, live, 0, 5, &deltas);
    auto dir = test::makeTempDir("deltas");
    const auto path = dir / "mesh.deltas";
    {
        DeltaStreamWriter writer(path);
        for (const auto& d : deltas) writer.write(d);
    }
    MeshReplica replayed;
    size_t frames = 0;
    readDeltaStream(path, [&](const MeshDelta& d) {
        replayed.apply(d);
        ++frames;
    });
    EXPECT_EQ(frames, deltas.size());
    EXPECT_EQ(countTriangleMismatches(canonicalTriangles(replayed.toMesh()), canonicalTriangles(live.toMesh()), 0), 0u);

    // Truncated in the middle of the last frame: an error naming the file and the frame.
    std::filesystem::resize_file(path, std::filesystem::file_size(path) - 7);
    try {
        readDeltaStream(path, [](const MeshDelta&) {});
        FAIL() << "a truncated stream was read";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(path.filename().string()), std::string::npos) << e.what();
    }
    std::ofstream(dir / "not.deltas") << "hello";
    EXPECT_THROW(readDeltaStream(dir / "not.deltas", [](const MeshDelta&) {}), Error);
    EXPECT_THROW(readDeltaStream(dir / "missing.deltas", [](const MeshDelta&) {}), Error);
    std::filesystem::remove_all(dir);
}

TEST(MeshReplica, RejectsDeltasThatDoNotFit) {
    MeshReplica replica;
    MeshDelta d;
    d.frame = 1;
    d.triangles.push_back({0u | (gpu::DELTA_ADDED << gpu::DELTA_KIND_SHIFT), 0, 1, 2});   // no such vertices
    EXPECT_THROW(replica.apply(d), Error);
    MeshReplica fresh;
    MeshDelta removal;
    removal.frame = 1;
    removal.vertices.push_back({5u | (gpu::DELTA_REMOVED << gpu::DELTA_KIND_SHIFT), 0, 0, 0, 0, 0, 0, 0});
    EXPECT_THROW(fresh.apply(removal), Error);
    MeshDelta empty;
    empty.frame = 3;
    MeshReplica ordered;
    ordered.apply(empty);
    empty.frame = 2;
    EXPECT_THROW(ordered.apply(empty), Error) << "frames must increase";
}

}  // namespace
}  // namespace vkmesh
