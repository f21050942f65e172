// Mesh refinement (paper §V.F, docs/REFINEMENT.md) on a slanted plane: fewer irregular cube types and
// fewer sliver triangles, no cracks.
#include <gtest/gtest.h>

#include <cmath>

#include "api/exported_mesh.h"
#include "core/mesh_analysis.h"
#include "core/refinement.h"
#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using test::GpuTest;

constexpr int kWidth = 160, kHeight = 120;

struct PlaneRun {
    double irregularCubeShare, sliverShare, meanDistance;
    size_t vertices, triangles, boundaryEdges, coincidentVertices;
};

// A plane not aligned with any axis, seen by 24 noisy frames from cameras 1.2-1.8 m in front of it.
PlaneRun meshSlantedPlane(vk::Context& context, bool refine, float epsilonVoxels) {
    const Eigen::Vector3d normal = Eigen::Vector3d(0.3, 0.5, 1.0).normalized();
    const synth::SyntheticScene scene = synth::SyntheticScene::slantedPlane(normal, 0.0);
    gpu::GpuVolumeConfig config;
    config.params.voxelSize = 0.03f;
    config.params.maxDepth = 4.0f;
    config.blockCapacity = 4096;
    config.vertexCapacity = 1u << 17;
    config.chunkCapacity = 1u << 17;
    config.imageWidth = kWidth;
    config.imageHeight = kHeight;
    config.refine = refine;
    config.refineEpsilonVoxels = epsilonVoxels;
    gpu::GpuVolume volume(context, config);
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    const Eigen::Vector3d side = normal.cross(Eigen::Vector3d::UnitX()).normalized(), up = normal.cross(side);
    for (int i = 0; i < 24; ++i) {
        const double a = i * 0.26;
        const Eigen::Vector3d eye = normal * (1.2 + 0.025 * i) + 0.3 * (std::cos(a) * side + std::sin(a) * up);
        const Pose pose = test::lookAt(eye, 0.2 * (std::sin(a) * side + std::cos(a) * up));
        synth::RenderOptions options;
        options.noise = true;
        options.seed = uint32_t(i + 1);
        volume.integrate(scene.renderDepth(intr, pose, options), intr, pose);
    }
    gpu::ExportedMesh exported = volume.exportMesh();
    Mesh mesh = toMesh(exported);
    PlaneRun run{};
    auto types = volume.surfaceCubeTypes();
    uint64_t surface = 0, irregular = 0;
    for (int t = 0; t < 256; ++t) {
        surface += types[t];
        if (!isRegularType(t)) irregular += types[t];
    }
    run.irregularCubeShare = double(irregular) / double(surface);
    run.sliverShare = triangleRegularity(mesh).sliverShare();
    double sum = 0;
    for (const auto& p : mesh.positions) sum += std::abs(normal.dot(p.cast<double>()));
    run.meanDistance = sum / double(mesh.positions.size());
    run.vertices = mesh.positions.size();
    run.boundaryEdges = analyzeTopology(mesh).boundaryEdges;
    run.triangles = mesh.triangles.size();
    run.coincidentVertices = countDuplicatePositions(mesh);
    std::cout << (refine ? "refined (eps " + std::to_string(epsilonVoxels) + " voxel)" : "unrefined") << ": irregular cubes "
              << run.irregularCubeShare << ", slivers " << run.sliverShare << ", mean |distance| " << run.meanDistance
              << " m, " << run.vertices << " vertices, " << run.triangles << " triangles, " << run.boundaryEdges << " boundary edges\n";
    return run;
}

// Refinement (--refine) against --no-refine on the slanted plane: flips decided per corner keep the
// mesh whole (no boundary edge more than unrefined), with fewer irregular cube types and sliver triangles,
// at a bounded cost in accuracy. (The plane is steep against all three axes, the hard case: see the
// irregular-share bound in docs/REFINEMENT.md.)
TEST_F(GpuTest, RefinementOnASlantedPlaneKeepsTheMeshWhole) {
    const gpu::GpuVolumeConfig defaults;
    PlaneRun off = meshSlantedPlane(context(), false, defaults.refineEpsilonVoxels);
    PlaneRun on = meshSlantedPlane(context(), true, defaults.refineEpsilonVoxels);
    EXPECT_LE(on.boundaryEdges, off.boundaryEdges) << "refinement opened cracks";
    // One vertex per position (exact float equality): a vertex next to a flipped corner stays on its own edge.
    EXPECT_EQ(off.coincidentVertices, 0u);
    EXPECT_EQ(on.coincidentVertices, 0u) << "two vertices of the refined mesh share a position";
    // On this steep plane a crack-free snap within half a voxel can do little (docs/REFINEMENT.md: most of its
    // irregular types come from the slope, not from noise): slivers and accuracy as
    // unrefined within 2 % and 1 %; not more irregular cubes.
    EXPECT_LE(on.irregularCubeShare, off.irregularCubeShare);
    EXPECT_LE(on.sliverShare, 1.02 * off.sliverShare);
    EXPECT_LE(on.meanDistance, 1.01 * off.meanDistance);
}
}  // namespace
}  // namespace vkmesh
