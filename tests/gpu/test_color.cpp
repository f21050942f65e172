// Colour through the shared-vertex mesh (docs/COLOR.md): the fused corner colours equal the CPU reference's
// bit for bit (both modes, frames with and without colour), vertex colours equal the reference mesher's and a
// from-scratch rebuild's, follow the true surface colour, reach a delta replica, and colour off costs nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>

#include "api/exported_mesh.h"
#include "core/mesh_analysis.h"
#include "core/mesh_delta.h"
#include "core/voxel_color.h"
#include "cpu/reference_mesher.h"
#include "cpu/reference_volume.h"
#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "mesh_checks.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using test::GpuTest;

constexpr int kWidth = 160, kHeight = 120;

using ColorField = std::function<std::array<float, 3>(const Eigen::Vector3d&)>;

// A smooth colour over the room (a few decimetres per period), values in [28, 228].
std::array<float, 3> smoothField(const Eigen::Vector3d& p) {
    return {float(128 + 100 * std::sin(3.0 * p.x())), float(128 + 100 * std::sin(2.5 * p.y() + 1.0)),
            float(128 + 100 * std::cos(2.0 * p.z()))};
}

// The colour image a camera at `pose` sees when the surface at each pixel's depth has colour field(point),
// plus deterministic per-pixel noise of +-noise (0: exact). Pixels without depth are black.
ColorImage colorImageOf(const DepthImage& depth, const Intrinsics& intr, const Pose& pose, const ColorField& field, int noise,
                        uint32_t seed) {
    ColorImage image;
    image.width = depth.width;
    image.height = depth.height;
    image.rgb.assign(size_t(depth.width) * depth.height * 3, 0);
    uint32_t state = seed * 2654435761u + 1;
    for (int y = 0; y < depth.height; ++y)
        for (int x = 0; x < depth.width; ++x) {
            const float d = depth.at(x, y);
            if (!(d > 0)) continue;
            Eigen::Vector4d cam((x - intr.cx) / intr.fx * d, (y - intr.cy) / intr.fy * d, d, 1.0);
            const Eigen::Vector3d world = (pose * cam).head<3>();
            const auto c = field(world);
            for (int k = 0; k < 3; ++k) {
                state = state * 1664525u + 1013904223u;
                const int jitter = noise ? int(state >> 16) % (2 * noise + 1) - noise : 0;
                image.rgb[(size_t(y) * depth.width + x) * 3 + k] = uint8_t(std::clamp(int(std::lround(c[k])) + jitter, 0, 255));
            }
        }
    return image;
}

struct ColorFrame {
    DepthImage depth;
    ColorImage color;   // empty: a frame without colour
    Pose pose;
};

// Noisy (or exact) frames of the synthetic room along its orbit; frame `withoutColorAt` has no colour.
std::vector<ColorFrame> roomFrames(size_t count, bool noise, int colorNoise, size_t withoutColorAt = size_t(-1)) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    const auto path = synth::cameraPath(24, synth::PathKind::Orbit);
    std::vector<ColorFrame> frames;
    for (size_t i = 0; i < count; ++i) {
        synth::RenderOptions options;
        options.noise = noise;
        options.seed = uint32_t(i + 1);
        const Pose& pose = path[(i * 2) % path.size()];
        ColorFrame f{scene.renderDepth(intr, pose, options), {}, pose};
        if (i != withoutColorAt) f.color = colorImageOf(f.depth, intr, pose, smoothField, colorNoise, uint32_t(i + 7));
        frames.push_back(std::move(f));
    }
    return frames;
}

gpu::GpuVolumeConfig colorConfig(ColorFusion mode) {
    gpu::GpuVolumeConfig c = test::smallRoomConfig();
    c.refine = false;   // vertex colours are compared with a from-scratch rebuild (no cube history)
    c.params.colorFusion = mode;
    return c;
}

// Vertex colour by position (positions are bit-identical between the GPU and the CPU reference).
std::map<std::array<float, 3>, uint32_t> colorByPosition(const std::vector<gpu::Vertex>& vertices) {
    std::map<std::array<float, 3>, uint32_t> out;
    for (const auto& v : vertices) out[{v.px, v.py, v.pz}] = v.color;
    return out;
}

class ColorFusionTest : public GpuTest, public ::testing::WithParamInterface<ColorFusion> {};

TEST_P(ColorFusionTest, CornerColoursMatchTheReferenceBitForBit) {
    const auto config = colorConfig(GetParam());
    gpu::GpuVolume volume(context(), config);
    cpu::ReferenceVolume reference(config.params, config.minMeshWeight);
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    for (const ColorFrame& f : roomFrames(6, true, 12, 3)) {
        volume.integrate(f.depth, f.color.empty() ? nullptr : &f.color, intr, f.pose);
        reference.integrate(f.depth, intr, f.pose, f.color.empty() ? nullptr : &f.color);
    }
    size_t compared = 0, coloured = 0, differing = 0;
    for (const gpu::BlockSnapshot& b : volume.downloadBlocks()) {
        auto it = reference.blocks().find({b.coord.x(), b.coord.y(), b.coord.z()});
        ASSERT_NE(it, reference.blocks().end());
        ASSERT_EQ(b.color.size(), size_t(gpu::VOXELS_PER_BLOCK));
        for (uint32_t v = 0; v < gpu::VOXELS_PER_BLOCK; ++v) {
            EXPECT_EQ(b.weight[v], it->second.weight[v]);
            if (b.weight[v] == 0.0f) continue;   // a corner without weight has no colour that counts
            ++compared;
            coloured += hasVoxelColor(b.color[v]);
            differing += b.color[v] != it->second.color[v];
        }
    }
    EXPECT_EQ(differing, 0u) << "of " << compared << " observed corners";
    // Nearly every observed corner got a colour: all but those seen only by the frame without colour.
    EXPECT_GT(double(coloured), 0.95 * double(compared));
    EXPECT_LT(coloured, compared);
    EXPECT_GT(compared, 10000u);
}

INSTANTIATE_TEST_SUITE_P(Modes, ColorFusionTest, ::testing::Values(ColorFusion::Average, ColorFusion::Recent),
                         [](const auto& info) { return info.param == ColorFusion::Average ? "Average" : "Recent"; });

TEST_F(GpuTest, VertexColoursMatchReferenceMesherAndRebuild) {
    const auto config = colorConfig(ColorFusion::Average);
    gpu::GpuVolume volume(context(), config);
    cpu::ReferenceVolume referenceVolume(config.params, config.minMeshWeight);
    cpu::ReferenceMesher mesher(config.params, config.minMeshWeight, config.vertexCapacity, config.chunkCapacity);
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    uint32_t frame = 0;
    for (const ColorFrame& f : roomFrames(5, true, 12, 2)) {
        ++frame;
        volume.integrate(f.depth, f.color.empty() ? nullptr : &f.color, intr, f.pose);
        referenceVolume.integrate(f.depth, intr, f.pose, f.color.empty() ? nullptr : &f.color);
        mesher.update(referenceVolume, referenceVolume.lastTouched(), frame);
    }
    const gpu::ExportedMesh incremental = volume.exportMesh();
    const Mesh cpuMesh = mesher.exportMesh(frame), gpuMesh = toMesh(incremental);
    ASSERT_EQ(gpuMesh.positions.size(), cpuMesh.positions.size());
    ASSERT_EQ(gpuMesh.colors.size(), gpuMesh.positions.size());
    ASSERT_EQ(cpuMesh.colors.size(), cpuMesh.positions.size());
    std::map<std::array<float, 3>, std::array<uint8_t, 3>> cpuColors;
    for (size_t i = 0; i < cpuMesh.positions.size(); ++i)
        cpuColors[{cpuMesh.positions[i].x(), cpuMesh.positions[i].y(), cpuMesh.positions[i].z()}] = cpuMesh.colors[i];
    size_t differing = 0, missing = 0;
    for (size_t i = 0; i < gpuMesh.positions.size(); ++i) {
        auto it = cpuColors.find({gpuMesh.positions[i].x(), gpuMesh.positions[i].y(), gpuMesh.positions[i].z()});
        if (it == cpuColors.end()) ++missing;
        else differing += it->second != gpuMesh.colors[i];
    }
    EXPECT_EQ(missing, 0u);
    EXPECT_EQ(differing, 0u) << "of " << gpuMesh.positions.size() << " vertices";
    // Vertices whose corners only the colourless frame saw have none; the rest have one.
    const size_t withColor = std::count_if(incremental.vertices.begin(), incremental.vertices.end(),
                                           [](const gpu::Vertex& v) { return vertexHasColor(v.color); });
    EXPECT_GT(double(withColor), 0.9 * double(incremental.vertices.size()));
    EXPECT_LT(withColor, incremental.vertices.size());

    // Colours are a function of the corners: rebuilding the mesh from scratch gives every vertex the same one.
    volume.rebuildMesh();
    const auto before = colorByPosition(incremental.vertices), after = colorByPosition(volume.exportMesh().vertices);
    EXPECT_EQ(before, after);
}

TEST_F(GpuTest, VertexColoursFollowTheSurfaceColour) {
    const auto config = colorConfig(ColorFusion::Average);
    gpu::GpuVolume volume(context(), config);
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    for (const ColorFrame& f : roomFrames(8, false, 0)) volume.integrate(f.depth, &f.color, intr, f.pose);
    const Mesh mesh = toMesh(volume.exportMesh());
    ASSERT_EQ(mesh.colors.size(), mesh.positions.size());
    ASSERT_GT(mesh.positions.size(), 3000u);
    // The field varies by at most ~300 units per metre: a vertex within a few mm of the surface, and a
    // corner colour taken from the pixel a corner projects to (up to a voxel away), stay within a few units.
    double sum = 0;
    size_t far = 0;
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const auto truth = smoothField(mesh.positions[i].cast<double>());
        for (int k = 0; k < 3; ++k) {
            const double e = std::abs(double(mesh.colors[i][k]) - truth[k]);
            sum += e;
            far += e > 30;
        }
    }
    const double mae = sum / (3.0 * mesh.positions.size());
    EXPECT_LT(mae, 6.0);
    EXPECT_LT(double(far), 0.01 * 3.0 * mesh.positions.size());
}

TEST_F(GpuTest, DeltaReplicaCarriesTheColours) {
    auto config = colorConfig(ColorFusion::Average);
    config.trackDeltas = true;
    gpu::GpuVolume volume(context(), config);
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    MeshReplica replica;
    size_t changed = 0;
    for (const ColorFrame& f : roomFrames(4, true, 12)) {
        gpu::FrameReport r = volume.integrate(f.depth, &f.color, intr, f.pose);
        changed += r.delta.count(DeltaKind::Changed);
        replica.apply(r.delta);
    }
    EXPECT_GT(changed, 0u);
    const Mesh viewer = replica.toMesh();
    const gpu::ExportedMesh exported = volume.exportMesh();
    ASSERT_EQ(viewer.colors.size(), viewer.positions.size());
    const auto truth = colorByPosition(exported.vertices);
    ASSERT_EQ(truth.size(), viewer.positions.size());
    size_t differing = 0;
    for (size_t i = 0; i < viewer.positions.size(); ++i) {
        auto it = truth.find({viewer.positions[i].x(), viewer.positions[i].y(), viewer.positions[i].z()});
        ASSERT_NE(it, truth.end());
        differing += vertexColorRgb(it->second) != viewer.colors[i];
    }
    EXPECT_EQ(differing, 0u);
}

TEST_F(GpuTest, ColourOffKeepsNoColour) {
    const auto frames = roomFrames(3, true, 12);
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    auto pools = [](const gpu::GpuVolume& v) {
        std::map<std::string, uint64_t> out;
        for (const auto& p : v.pools()) out[p.name] = p.bytes;
        return out;
    };
    gpu::GpuVolume off(context(), colorConfig(ColorFusion::Off));
    gpu::GpuVolume on(context(), colorConfig(ColorFusion::Average));
    for (const ColorFrame& f : frames) {
        off.integrate(f.depth, &f.color, intr, f.pose);   // the colour is ignored
        on.integrate(f.depth, intr, f.pose);              // no colour given: depth only
    }
    EXPECT_LE(pools(off)["voxel colour (off)"], 16u);
    EXPECT_EQ(pools(on)["voxel colour"], uint64_t(on.config().blockCapacity) * gpu::VOXELS_PER_BLOCK * 4);
    const gpu::ExportedMesh a = off.exportMesh(), b = on.exportMesh();
    EXPECT_TRUE(toMesh(a).colors.empty());
    EXPECT_TRUE(toMesh(b).colors.empty()) << "no frame had colour";
    // Colour never changes the geometry.
    EXPECT_EQ(canonicalTriangles(test::soupOf(a)), canonicalTriangles(test::soupOf(b)));
}

TEST_F(GpuTest, ColourOfTheWrongSizeIsAnError) {
    gpu::GpuVolume volume(context(), colorConfig(ColorFusion::Average));
    const auto frames = roomFrames(1, false, 0);
    ColorImage small;
    small.width = kWidth / 2;
    small.height = kHeight / 2;
    small.rgb.assign(size_t(small.width) * small.height * 3, 100);
    try {
        volume.integrate(frames[0].depth, &small, synth::kinectIntrinsics(kWidth, kHeight), frames[0].pose);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("colour image is 80x60"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace vkmesh
