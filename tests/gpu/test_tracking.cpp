// Camera tracking (src/gpu/tracking, shaders_comp/track, docs/TRACKING.md): the GPU passes against the CPU
// reference (src/cpu/reference_tracking.h), the model maps against exact ray casts, and the tracker over
// synthetic sequences with exact ground truth. GpuTest: the validation layer is on and any message fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <numbers>
#include <set>

#include "api/reconstructor.h"
#include "core/camera.h"
#include "core/icp_solve.h"
#include "cpu/reference_tracking.h"
#include "gpu/tracking/camera_tracker.h"
#include "gpu/tracking/pose_tracker.h"
#include "gpu_fixture.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"

namespace vkmesh {
namespace {

using gpu::CameraTracker;
using gpu::PoseTracker;
using gpu::TrackerOptions;

constexpr int kWidth = 320, kHeight = 240;

const synth::SyntheticScene& room() {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    return scene;
}

// Poses of a 360-frame orbit of the room: about 2.4 cm and 1 degree from one frame to the next.
const std::vector<Pose>& orbit() {
    static const std::vector<Pose> poses = synth::cameraPath(360);
    return poses;
}

DepthImage roomDepth(size_t frame, bool noise) {
    synth::RenderOptions options;
    options.noise = noise;
    options.seed = uint32_t(frame + 1);
    options.maxRange = 5.0f;
    return room().renderDepth(synth::kinectIntrinsics(kWidth, kHeight), orbit()[frame], options);
}

gpu::GpuVolumeConfig volumeConfig(float voxel) {
    gpu::GpuVolumeConfig config;
    config.params.voxelSize = voxel;
    config.params.maxDepth = 5.0f;
    config.imageWidth = kWidth;
    config.imageHeight = kHeight;
    config.blockCapacity = 8192;
    config.vertexCapacity = 1u << 18;
    config.chunkCapacity = 1u << 17;
    config.publishMesh = true;
    return config;
}

// A host mesh in GPU buffers that the tracker's draw reads as it reads vkmesh's own (MeshBuffers).
struct UploadedMesh {
    vk::Buffer vertices, indices, indirect;
    gpu::MeshBuffers buffers() const {
        gpu::MeshBuffers b;
        b.vertices = vertices.handle();
        b.indices = indices.handle();
        b.drawIndirect = indirect.handle();
        return b;
    }
};
UploadedMesh upload(const vk::Context& context, const std::vector<gpu::Vertex>& vertices, const std::vector<uint32_t>& indices) {
    UploadedMesh m;
    m.vertices = vk::Buffer(context, vertices.size() * sizeof(gpu::Vertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, vk::MemoryUse::Upload, "test vertices");
    m.indices = vk::Buffer(context, indices.size() * 4, VK_BUFFER_USAGE_INDEX_BUFFER_BIT, vk::MemoryUse::Upload, "test indices");
    m.indirect = vk::Buffer(context, sizeof(VkDrawIndexedIndirectCommand), VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, vk::MemoryUse::Upload, "test draw");
    std::memcpy(m.vertices.mapped(), vertices.data(), vertices.size() * sizeof(gpu::Vertex));
    std::memcpy(m.indices.mapped(), indices.data(), indices.size() * 4);
    VkDrawIndexedIndirectCommand draw{uint32_t(indices.size()), 1, 0, 0, 0};
    std::memcpy(m.indirect.mapped(), &draw, sizeof(draw));
    return m;
}

// A square of side 2 * half in the world plane z = depth, normal -z (facing a camera at the origin looking
// along +z), split into n x n quads wound as the mesh's: counter-clockwise seen from the side the normal
// points to (free space). `seenFromBehind`: the normal +z and the winding reversed, a back face for that camera.

void planeMesh(float depth, float half, int n, std::vector<gpu::Vertex>& vertices, std::vector<uint32_t>& indices,
               bool seenFromBehind = false) {
    const float normalZ = seenFromBehind ? 1.0f : -1.0f;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            vertices.push_back(gpu::Vertex{-half + 2 * half * i / n, -half + 2 * half * j / n, depth, 1u, 0, 0, normalZ, 0, 0});
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;   // a b: +x; a c: +y
            if (seenFromBehind) indices.insert(indices.end(), {a, b, d, a, d, c});
            else indices.insert(indices.end(), {a, d, b, a, c, d});   // (d - a) x (b - a) points to -z
        }
}

std::vector<Eigen::Vector4f> levelOf(const std::vector<Eigen::Vector4f>& all, const CameraTracker& t, int level) {
    const size_t n = size_t(kWidth >> level) * size_t(kHeight >> level);
    return {all.begin() + t.pixelOffset(level), all.begin() + t.pixelOffset(level) + n};
}

class Tracking : public test::GpuTest {};

TEST_F(Tracking, PyramidMatchesCpuReference) {
    const DepthImage depth = roomDepth(10, /*noise=*/true);   // dropouts and edges, so every rejection is exercised
    const Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
    TrackerOptions options;
    CameraTracker tracker(context(), kWidth, kHeight, options);
    tracker.prepare(depth, k, gpu::MeshBuffers{}, orbit()[10]);
    const CameraTracker::Maps gpuMaps = tracker.downloadMaps();
    const auto reference = cpu::referenceTrackingPyramid(depth, k, gpu::trackParamsFor(options));
    for (int l = 0; l < int(gpu::TRACK_LEVELS); ++l) {
        const cpu::TrackingLevel& ref = reference[l];
        size_t depthMismatch = 0, pointMismatch = 0, normalMismatch = 0, normals = 0;
        for (size_t i = 0; i < ref.depth.size(); ++i) {
            const size_t g = tracker.pixelOffset(l) + i;
            // exp() differs in the last bits between the GPU and libm: 1e-5 relative, and no pixel may gain
            // or lose its measurement.
            if ((ref.depth[i] > 0) != (gpuMaps.depth[g] > 0) || std::abs(ref.depth[i] - gpuMaps.depth[g]) > 1e-5f * ref.depth[i])
                ++depthMismatch;
            if ((ref.points[i] - gpuMaps.points[g]).norm() > 1e-4f) ++pointMismatch;
            normals += ref.normals[i].w() != 0;
            if (ref.normals[i].w() != gpuMaps.normals[g].w() ||
                (ref.normals[i].w() != 0 && ref.normals[i].head<3>().dot(gpuMaps.normals[g].head<3>()) < 0.9999f))
                ++normalMismatch;
        }
        EXPECT_EQ(depthMismatch, 0u) << "level " << l;
        EXPECT_EQ(pointMismatch, 0u) << "level " << l;
        // A normal on the edge gate's boundary may go either way with rounding: at most 0.1 % of them.
        EXPECT_LE(normalMismatch, normals / 1000) << "level " << l << ": " << normals << " normals";
        EXPECT_GT(normals, ref.depth.size() / 3) << "level " << l;
    }
}

TEST_F(Tracking, ModelMapsOfAPlaneAreItsRayIntersections) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    std::vector<gpu::Vertex> vertices;
    std::vector<uint32_t> indices;
    const float depth = 2.0f;
    planeMesh(depth, 1.0f, 8, vertices, indices);
    UploadedMesh mesh = upload(context(), vertices, indices);
    for (float fySign : {1.0f, -1.0f}) {   // ICL-NUIM's negative fy mirrors the picture vertically
        Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
        k.fy *= fySign;
        CameraTracker tracker(context(), kWidth, kHeight);
        DepthImage none;
        none.width = kWidth, none.height = kHeight;
        none.meters.assign(size_t(kWidth) * kHeight, 0.0f);
        tracker.prepare(none, k, mesh.buffers(), Pose::Identity());
        const CameraTracker::Maps maps = tracker.downloadMaps();
        size_t inside = 0, wrong = 0, outsideWithModel = 0;
        for (int y = 0; y < kHeight; ++y) {
            for (int x = 0; x < kWidth; ++x) {
                const Eigen::Vector4f& p = maps.modelPositions[size_t(y) * kWidth + x];
                const Eigen::Vector4f& n = maps.modelNormals[size_t(y) * kWidth + x];
                // The ray through pixel centre (x, y) meets the plane at depth 2.
                const Eigen::Vector3f expected((x - k.cx) / k.fx * depth, (y - k.cy) / k.fy * depth, depth);
                const bool onPlane = std::abs(expected.x()) < 0.99f && std::abs(expected.y()) < 0.99f;
                const bool offPlane = std::abs(expected.x()) > 1.01f || std::abs(expected.y()) > 1.01f;
                if (onPlane) {
                    ++inside;
                    if (p.w() != 1.0f || (p.head<3>() - expected).norm() > 1e-4f || (n.head<3>() - Eigen::Vector3f(0, 0, -1)).norm() > 1e-5f)
                        ++wrong;
                } else if (offPlane && p.w() != 0.0f) {
                    ++outsideWithModel;
                }
            }
        }
        EXPECT_GT(inside, 10000u);
        EXPECT_EQ(wrong, 0u) << "fy " << k.fy;
        EXPECT_EQ(outsideWithModel, 0u) << "fy " << k.fy;
        // The same plane seen from behind (its normal and winding away from the camera) is a back face: not drawn,
        // as a ray cast of the TSDF would not stop there.
        {
            std::vector<gpu::Vertex> backVertices;
            std::vector<uint32_t> backIndices;
            planeMesh(depth, 1.0f, 8, backVertices, backIndices, /*seenFromBehind=*/true);
            UploadedMesh back = upload(context(), backVertices, backIndices);
            tracker.prepare(none, k, back.buffers(), Pose::Identity());
            const CameraTracker::Maps backMaps = tracker.downloadMaps();
            size_t drawn = 0;
            for (int i = 0; i < kWidth * kHeight; ++i) drawn += backMaps.modelPositions[size_t(i)].w() != 0.0f;
            EXPECT_EQ(drawn, 0u) << "fy " << k.fy;
            tracker.prepare(none, k, mesh.buffers(), Pose::Identity());
        }
        // The coarser levels: the CPU reference's downsampling of the GPU's level 0.
        std::vector<Eigen::Vector4f> positions = levelOf(maps.modelPositions, tracker, 0), normals = levelOf(maps.modelNormals, tracker, 0);
        for (int l = 1; l < int(gpu::TRACK_LEVELS); ++l) {
            std::vector<Eigen::Vector4f> coarseP, coarseN;
            cpu::referenceDownsampleModel(positions, normals, kWidth >> (l - 1), kHeight >> (l - 1), gpu::trackParamsFor(TrackerOptions{}), coarseP, coarseN);
            const auto gpuP = levelOf(maps.modelPositions, tracker, l);
            size_t mismatch = 0;
            for (size_t i = 0; i < coarseP.size(); ++i)
                if (coarseP[i].w() != gpuP[i].w() || (coarseP[i] - gpuP[i]).norm() > 1e-5f) ++mismatch;
            EXPECT_EQ(mismatch, 0u) << "level " << l;
            positions = coarseP, normals = coarseN;
        }
    }
}

DepthImage roomFrame(size_t frame, ColorImage* color) {
    synth::RenderOptions options;
    options.noise = true;
    options.seed = uint32_t(frame + 1);
    options.maxRange = 5.0f;
    return room().renderDepth(synth::kinectIntrinsics(kWidth, kHeight), orbit()[frame], options, color);
}

// Tracking draws a volume's mesh through the list of the triangles of its blocks in view (GpuVolume::recordModelView,
// shaders_comp/model_view). The model maps are those of the whole mesh, bit for bit, at every pose: views of part of
// the map, of all of it, of none of it, mirrored; the list holds each live triangle of a block in view once, as the CPU
// reference decides (cpu::referenceBlockViewSlack), and none of the others.
TEST_F(Tracking, ModelMapsOfTheTrianglesInViewAreThoseOfTheWholeMesh) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    const float voxel = 0.03f;
    gpu::GpuVolumeConfig config = volumeConfig(voxel);   // publishMesh: the whole mesh, to compare with
    config.params.colorFusion = ColorFusion::Average;
    gpu::GpuVolume volume(context(), config);
    const Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
    for (size_t i = 0; i < 90; i += 6) {   // a quarter of the orbit: the rest of the room is not mapped
        ColorImage color;
        const DepthImage depth = roomFrame(i, &color);
        volume.integrate(depth, &color, k, orbit()[i]);
    }
    const gpu::MeshStateSnapshot state = volume.downloadMeshState();
    std::map<std::array<uint32_t, 3>, Eigen::Vector3i> liveBlocks;   // each live triangle's block (its centroid's)
    for (const auto& t : state.liveTriangles) {
        Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
        for (uint32_t v : t) centroid += Eigen::Vector3d(state.vertices[v].px, state.vertices[v].py, state.vertices[v].pz) / 3.0;
        const Eigen::Vector3d b = (centroid / (voxel * gpu::BLOCK_SIDE)).array().floor();
        liveBlocks[t] = b.cast<int>();
    }
    ASSERT_GT(liveBlocks.size(), 10000u);

    Intrinsics mirrored = k;
    mirrored.fy = -k.fy;   // ICL-NUIM's negative fy
    Pose away = orbit()[45];
    away.block<3, 3>(0, 0) = away.block<3, 3>(0, 0) * Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitY()).toRotationMatrix();
    struct View {
        Pose pose;
        Intrinsics intrinsics;
        size_t frame;   // the depth image seen there (it sets the far plane)
    };
    size_t partial = 0;
    CameraTracker tracker(context(), kWidth, kHeight);
    for (const View& view : {View{orbit()[0], k, 0}, View{orbit()[45], k, 45}, View{orbit()[45], mirrored, 45}, View{orbit()[150], k, 150},
                             View{orbit()[270], k, 270}, View{away, k, 45}}) {
        SCOPED_TRACE("view " + std::to_string(view.frame) + (view.intrinsics.fy < 0 ? " mirrored" : "") +
                     (view.pose.isApprox(away) ? " turned away" : ""));
        const DepthImage depth = roomDepth(view.frame, false);
        tracker.prepare(depth, view.intrinsics, volume.meshBuffers(), view.pose);
        const CameraTracker::Maps whole = tracker.downloadMaps();
        tracker.prepare(depth, view.intrinsics, volume, view.pose);
        const CameraTracker::Maps inView = tracker.downloadMaps();
        const size_t pixels = size_t(kWidth) * kHeight;
        size_t differ = 0, drawn = 0;
        for (size_t i = 0; i < pixels; ++i) {
            differ += whole.modelPositions[i] != inView.modelPositions[i] || whole.modelNormals[i] != inView.modelNormals[i] ||
                      std::memcmp(&whole.modelIntensity[i], &inView.modelIntensity[i], sizeof(float)) != 0;
            drawn += whole.modelPositions[i].w() != 0.0f;
        }
        EXPECT_EQ(differ, 0u) << "of " << drawn << " pixels with model";

        // The list, from the same near and far planes as the tracker's draw, against the reference.
        const float nearDepth = 0.2f, farDepth = 3.0f;
        vk::CommandRecorder recorder(context());
        volume.recordModelView(recorder.begin(), view.pose, view.intrinsics, kWidth, kHeight, nearDepth, farDepth);
        recorder.submitAndWait();
        const std::vector<std::array<uint32_t, 3>> listed = volume.downloadModelView();
        std::set<std::array<uint32_t, 3>> listedSet(listed.begin(), listed.end());
        EXPECT_EQ(listedSet.size(), listed.size()) << "a triangle listed twice";
        size_t notLive = 0, wrong = 0, inViewCount = 0;
        for (const auto& t : listedSet) notLive += liveBlocks.count(t) == 0;
        for (const auto& [t, block] : liveBlocks) {
            const double slack = cpu::referenceBlockViewSlack(block, voxel * gpu::BLOCK_SIDE, view.pose, view.intrinsics, kWidth, kHeight,
                                                              nearDepth, farDepth);
            inViewCount += slack >= 0;
            if ((slack >= 0) != (listedSet.count(t) != 0) && std::abs(slack) > 1e-4) ++wrong;
        }
        EXPECT_EQ(notLive, 0u);
        EXPECT_EQ(wrong, 0u) << inViewCount << " in view by the reference, " << listed.size() << " listed";
        // Each view leaves some of the map out; turned away from it, all of it.
        EXPECT_LT(listed.size(), liveBlocks.size());
        if (view.pose.isApprox(away)) EXPECT_EQ(listed.size(), 0u);
        else EXPECT_GT(listed.size(), 0u);
        if (listed.size() > 0 && listed.size() < liveBlocks.size() * 6 / 10) ++partial;
    }
    EXPECT_GE(partial, 2u) << "views that list less than 60 % of the map";

    // The older map (loop closure's: docs/LOOP_CLOSURE.md, "Loops against the older map"): of the triangles in view,
    // exactly those whose three vertices the frames before `createdBefore` created.
    const uint32_t createdBefore = 8;   // the first 7 of the 15 frames (frame numbers start at 1)
    vk::CommandRecorder recorder(context());
    volume.recordModelView(recorder.begin(), orbit()[45], k, kWidth, kHeight, 0.2f, 3.0f);
    recorder.submitAndWait();
    const std::vector<std::array<uint32_t, 3>> all = volume.downloadModelView();
    volume.recordModelView(recorder.begin(), orbit()[45], k, kWidth, kHeight, 0.2f, 3.0f, createdBefore);
    recorder.submitAndWait();
    const std::vector<std::array<uint32_t, 3>> older = volume.downloadModelView();
    std::set<std::array<uint32_t, 3>> expected;
    for (const auto& t : all)
        if (std::all_of(t.begin(), t.end(), [&](uint32_t v) { return state.vertices[v].createdFrame < createdBefore; })) expected.insert(t);
    const std::set<std::array<uint32_t, 3>> olderSet(older.begin(), older.end());
    EXPECT_EQ(olderSet, expected);
    EXPECT_EQ(older.size(), expected.size()) << "a triangle listed twice";
    EXPECT_GT(expected.size(), 1000u);
    EXPECT_LT(expected.size(), all.size() * 9 / 10) << "the later frames made some of the surface in view";
}

// The ICP sums at every level: the GPU's against the CPU reference fed with the GPU's own maps, for a frame
// one orbit step away from the model pose; geometry only, and with the photometric term against the mesh's
// fused colours.
TEST_F(Tracking, IcpSumsMatchCpuReference) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    gpu::GpuVolumeConfig config = volumeConfig(0.03f);
    config.params.colorFusion = ColorFusion::Average;
    gpu::GpuVolume volume(context(), config);
    const Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
    ColorImage color0, color2;
    const DepthImage depth0 = roomFrame(0, &color0), depth2 = roomFrame(2, &color2);
    volume.integrate(depth0, &color0, k, orbit()[0]);
    // Both ways of splitting the pixels among invocations (a GPU's 16, a CPU device's 64), both weights, and
    // both ways of reading the maps (texel buffers; storage buffers, the fallback of a device whose
    // maxTexelBufferElements is below the pyramid).
    // And the finest level's checkerboard (half its pixels).
    struct Case {
        float colorWeight;
        uint32_t perInvocation;
        bool texelReads, checkerboard;
    };
    for (auto [colorWeight, perInvocation, texelReads, checkerboard] :
         {Case{0.0f, 16u, true, false}, Case{0.05f, 64u, true, false}, Case{0.05f, 16u, false, false}, Case{0.05f, 64u, false, false},
          Case{0.05f, 64u, true, true}, Case{0.0f, 16u, false, true}}) {
        TrackerOptions options;
        options.colorWeight = colorWeight;
        options.pixelsPerInvocation = perInvocation;
        options.texelReads = texelReads;
        options.checkerboard = checkerboard;
        CameraTracker tracker(context(), kWidth, kHeight, options);
        EXPECT_EQ(tracker.readsTexels(), texelReads);   // lavapipe's limit holds a 320 x 240 pyramid
        EXPECT_EQ(tracker.checkerboardUsed(), checkerboard);   // 320 pixels wide
        tracker.prepare(depth2, k, volume.meshBuffers(), orbit()[0], &color2);
        const CameraTracker::Maps maps = tracker.downloadMaps();
        const gpu::TrackParamsGpu params = gpu::trackParamsFor(options);
        const auto frame = cpu::referenceTrackingPyramid(depth2, k, params);
        for (int l = 0; l < int(gpu::TRACK_LEVELS); ++l) {
            SCOPED_TRACE("colour weight " + std::to_string(colorWeight) + ", " + std::to_string(perInvocation) +
                         " pixels per invocation, " + (texelReads ? "texel" : "buffer") + " reads" +
                         (checkerboard ? ", checkerboard" : "") + ", level " + std::to_string(l));
            cpu::TrackingLevel level = frame[l];
            level.points = levelOf(maps.points, tracker, l);   // the GPU's own maps: this checks the ICP pass alone
            level.normals = levelOf(maps.normals, tracker, l);
            const size_t n = level.points.size();
            const std::vector<float> frameIntensity(maps.intensity.begin() + tracker.pixelOffset(l), maps.intensity.begin() + tracker.pixelOffset(l) + n);
            const std::vector<float> modelIntensity(maps.modelIntensity.begin() + tracker.pixelOffset(l),
                                                    maps.modelIntensity.begin() + tracker.pixelOffset(l) + n);
            cpu::PhotometricLevel photometric{&frameIntensity, &modelIntensity, colorWeight, options.colorHuber};
            if (colorWeight > 0) {   // the maps hold intensities: the frame's everywhere, the model's where it is coloured
                EXPECT_GT(std::count_if(frameIntensity.begin(), frameIntensity.end(), [](float i) { return i >= 0; }), long(n * 9 / 10));
                EXPECT_GT(std::count_if(modelIntensity.begin(), modelIntensity.end(), [](float i) { return i >= 0; }), long(n / 3));
            }
            for (const Pose& estimate : {orbit()[0], orbit()[1]}) {
                const IcpSums gpuSums = tracker.sums(l, estimate);
                const IcpSums ref = cpu::referenceIcpSums(level, levelOf(maps.modelPositions, tracker, l), levelOf(maps.modelNormals, tracker, l),
                                                          estimate, orbit()[0], gpu::icpGatesFor(options, l), photometric,
                                                          checkerboard && l == 0);
                ASSERT_GT(ref[gpu::TRACK_SUM_INLIERS], 100);
                // Counts: the same pixels pass the same gates (computed the same way in float).
                EXPECT_EQ(gpuSums[gpu::TRACK_SUM_VALID], ref[gpu::TRACK_SUM_VALID]);
                EXPECT_NEAR(gpuSums[gpu::TRACK_SUM_MODEL_HITS], ref[gpu::TRACK_SUM_MODEL_HITS], 2);
                EXPECT_NEAR(gpuSums[gpu::TRACK_SUM_INLIERS], ref[gpu::TRACK_SUM_INLIERS], 2 + ref[gpu::TRACK_SUM_INLIERS] * 1e-3);
                // Float sums of up to 76,800 terms against double ones: 1e-3 of the largest term's scale.
                double scale = 0;
                for (uint32_t i = 0; i < gpu::TRACK_SUM_JTR; ++i) scale = std::max(scale, std::abs(ref[i]));
                for (uint32_t i = 0; i < gpu::TRACK_SUM_WEIGHTED_ERROR; ++i)
                    EXPECT_NEAR(gpuSums[i], ref[i], 1e-3 * scale + 1e-3 * std::abs(ref[i])) << "sum " << i;
                EXPECT_NEAR(gpuSums[gpu::TRACK_SUM_SQUARED_ERROR], ref[gpu::TRACK_SUM_SQUARED_ERROR], 1e-3 * ref[gpu::TRACK_SUM_SQUARED_ERROR] + 1e-9);
                EXPECT_NEAR(gpuSums[gpu::TRACK_SUM_WEIGHTED_ERROR], ref[gpu::TRACK_SUM_WEIGHTED_ERROR], 1e-3 * ref[gpu::TRACK_SUM_WEIGHTED_ERROR] + 1e-9);
                // And the steps solved from them agree.
                const IcpStep a = solveIcpStep(icpSystem(gpuSums)), b = solveIcpStep(icpSystem(ref));
                ASSERT_TRUE(a.solved && b.solved);
                EXPECT_LT((a.twist - b.twist).norm(), 1e-3 * b.twist.norm() + 1e-6);
            }
        }
    }
}

struct TrackedRun {
    std::vector<Pose> poses;
    std::vector<gpu::TrackingReport> reports;
};

// Fuses `frames` frames of the orbit, every pose after the first tracked (the systems solved on the host, or
// on the GPU with the fusion in the same submission: one per frame).
TrackedRun trackOrbit(const vk::Context& context, size_t frames, bool noise, float voxel, bool solveOnGpu = false, int downsample = 1,
                      TrackerOptions options = {}) {
    gpu::GpuVolume volume(context, volumeConfig(voxel));
    const Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
    options.maxDepth = 5.0f;
    options.solveOnGpu = solveOnGpu;
    options.downsample = downsample;
    PoseTracker tracker(context, options);
    TrackedRun run;
    for (size_t i = 0; i < frames; ++i) {
        const DepthImage depth = roomDepth(i, noise);
        if (i == 0) {
            run.reports.push_back(tracker.start(orbit()[0]));
            volume.integrate(depth, k, orbit()[0]);
        } else {
            gpu::TrackedFusion f = tracker.trackAndFuse(volume, depth, k, nullptr, nullptr);
            EXPECT_EQ(f.fused.has_value(), f.tracking.tracked) << "frame " << i;
            EXPECT_EQ(f.oneSubmission, solveOnGpu);
            run.reports.push_back(f.tracking);
        }
        run.poses.push_back(run.reports.back().cameraToWorld);
    }
    EXPECT_EQ(volume.framesIntegrated(), uint32_t(std::count_if(run.reports.begin(), run.reports.end(), [](const auto& r) { return r.tracked; })));
    return run;
}

double positionRmse(const std::vector<Pose>& estimated) {
    double sum = 0;
    for (size_t i = 0; i < estimated.size(); ++i) sum += (estimated[i].block<3, 1>(0, 3) - orbit()[i].block<3, 1>(0, 3)).squaredNorm();
    return std::sqrt(sum / double(estimated.size()));
}

class TrackingModes : public Tracking, public ::testing::WithParamInterface<bool> {};

TEST_P(TrackingModes, NoiselessSequenceTrackedFromItsFirstPoseWithinTwoMillimetres) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    const bool onGpu = GetParam();
    const TrackedRun run = trackOrbit(context(), 30, /*noise=*/false, 0.02f, onGpu);
    for (size_t i = 0; i < run.reports.size(); ++i) {
        EXPECT_TRUE(run.reports[i].tracked) << "frame " << i << ": " << run.reports[i].lostReason;
        if (i > 0) { EXPECT_EQ(run.reports[i].submissions, onGpu ? 1u : uint32_t(run.reports[i].iterations) + 1u) << "frame " << i; }
    }
    // Against the exact poses, without any alignment (the first pose is the true one).
    const double rmse = positionRmse(run.poses);
    double worstDegrees = 0;
    for (size_t i = 0; i < run.poses.size(); ++i) worstDegrees = std::max(worstDegrees, rotationDegrees(inverseRigid(orbit()[i]) * run.poses[i]));
    std::printf("30 noiseless frames, 2 cm voxels, 320x240, systems solved on the %s: position RMSE %.3f mm, worst rotation error %.4f degrees\n",
                onGpu ? "GPU" : "host", rmse * 1e3, worstDegrees);
    EXPECT_LT(rmse, 0.002);
    EXPECT_LT(worstDegrees, 0.3);
}

// Tracking on frames downsampled by 2 (160 x 120 here; fusion keeps 320 x 240): still within a few millimetres
// on the noiseless orbit, in one submission per frame. Bad factors are refused.
TEST_F(Tracking, DownsampledFramesStillTrackTheNoiselessSequence) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    const TrackedRun run = trackOrbit(context(), 15, /*noise=*/false, 0.02f, /*solveOnGpu=*/true, /*downsample=*/2);
    for (size_t i = 0; i < run.reports.size(); ++i) EXPECT_TRUE(run.reports[i].tracked) << "frame " << i << ": " << run.reports[i].lostReason;
    const double rmse = positionRmse(run.poses);
    std::printf("15 noiseless frames tracked at 160x120 (fused at 320x240): position RMSE %.3f mm\n", rmse * 1e3);
    EXPECT_LT(rmse, 0.004);
    EXPECT_GT(run.reports.back().validPixels, 0);
    EXPECT_LE(run.reports.back().validPixels, double(kWidth / 2) * (kHeight / 2)) << "tracked at the downsampled size";
    TrackerOptions bad;
    bad.downsample = 3;
    EXPECT_THROW(PoseTracker(context(), bad), Error);
}

// Reused model maps (TrackerOptions::modelReuse*): a frame predicted close to where the maps were drawn is
// associated with them instead of a new draw, at most modelReuseFrames frames in a row; the noiseless orbit is
// still tracked within a few millimetres, in both solve modes.
TEST_P(TrackingModes, ReusedModelMapsStillTrackTheNoiselessSequence) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    TrackerOptions options;
    options.modelReuseFrames = 2;
    options.modelReuseMetres = 0.05;   // the orbit moves about 1 cm and 1 degree per frame
    options.modelReuseDegrees = 5.0;
    const TrackedRun run = trackOrbit(context(), 20, /*noise=*/false, 0.02f, GetParam(), 1, options);
    size_t draws = 0, reusedInARow = 0, longestReuse = 0;
    for (size_t i = 1; i < run.reports.size(); ++i) {
        EXPECT_TRUE(run.reports[i].tracked) << "frame " << i << ": " << run.reports[i].lostReason;
        draws += run.reports[i].modelDrawn;
        reusedInARow = run.reports[i].modelDrawn ? 0 : reusedInARow + 1;
        longestReuse = std::max(longestReuse, reusedInARow);
    }
    const double rmse = positionRmse(run.poses);
    std::printf("20 noiseless frames, maps reused up to 2 frames in a row: %zu draws for %zu tracked frames, position RMSE %.3f mm\n", draws,
                run.reports.size() - 1, rmse * 1e3);
    EXPECT_EQ(longestReuse, 2u);                       // the bound holds, and reuse happened
    EXPECT_LE(draws, (run.reports.size() - 1) / 2);   // the frame after the first draws, then 2 reuse, ...
    EXPECT_LT(rmse, 0.003);
    // Reuse off: every tracked frame draws the mesh.
    TrackerOptions off;
    off.modelReuseFrames = 0;
    const TrackedRun fresh = trackOrbit(context(), 4, /*noise=*/false, 0.02f, GetParam(), 1, off);
    for (size_t i = 1; i < fresh.reports.size(); ++i) EXPECT_TRUE(fresh.reports[i].modelDrawn) << "frame " << i;
}

// `vkmesh soak --track`: every lap tracked in a new copy of the room (its first frame placed), the map growing lap
// after lap; the CSV gains the tracking columns and the summary the per-lap medians (the flat-cost check).
TEST_F(Tracking, SoakTracksEveryLapInANewCopyOfTheRoom) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // tracking draws the mesh
    const std::filesystem::path d = test::makeTempDir("soak_track");
    const test::CliRun r = test::runCli("soak -o " + (d / "soak.csv").string() + " --frames 120 --laps 3 --track --summary " +
                                        (d / "summary.json").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string csv = test::readText(d / "soak.csv");
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 121);
    EXPECT_NE(csv.substr(0, csv.find('\n')).find(",ms_other,track_ms,track_gpu_ms,tracked,track_error_m"), std::string::npos);
    const std::string summary = test::readText(d / "summary.json");
    EXPECT_NE(summary.find("\"rooms\": 3"), std::string::npos) << summary;   // a room per lap
    EXPECT_NE(summary.find("\"last_over_first\""), std::string::npos) << summary;
    EXPECT_NE(summary.find("\"lost_frames\": 0"), std::string::npos) << summary;
    // 39 tracked frames per lap (the first is placed; 9 degrees of the orbit apart), each within the 5 cm voxels'
    // reach of the truth.
    size_t lap = 0;
    for (size_t at = summary.find("\"tracked_frames\": "); at != std::string::npos; at = summary.find("\"tracked_frames\": ", at + 1), ++lap)
        EXPECT_EQ(std::stoi(summary.substr(at + 18)), 39) << "lap " << lap;
    EXPECT_EQ(lap, 3u);
    for (size_t at = summary.find("\"max_position_error_m\": "); at != std::string::npos; at = summary.find("\"max_position_error_m\": ", at + 1))
        EXPECT_LT(std::stod(summary.substr(at + 24)), 0.05);
    std::filesystem::remove_all(d);
}

// A colour image of the wrong size is refused before anything is recorded, also when the frame would be fused in
// tracking's submission, and the volume takes the next frame as if nothing had happened.
TEST_P(TrackingModes, BadColourIsRefusedAndTheNextFrameTracks) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    gpu::GpuVolume volume(context(), volumeConfig(0.03f));
    const Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
    TrackerOptions options;
    options.solveOnGpu = GetParam();
    PoseTracker tracker(context(), options);
    tracker.start(orbit()[0]);
    volume.integrate(roomDepth(0, false), k, orbit()[0]);
    ColorImage small;
    small.width = kWidth / 2;
    small.height = kHeight / 2;
    small.rgb.assign(size_t(small.width) * small.height * 3, 128);
    try {
        tracker.trackAndFuse(volume, roomDepth(1, false), k, &small, nullptr);
        ADD_FAILURE() << "a " << small.width << "x" << small.height << " colour image was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("colour image"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(volume.framePending());
    EXPECT_EQ(volume.frameNumber(), 1u);
    const gpu::TrackedFusion next = tracker.trackAndFuse(volume, roomDepth(1, false), k, nullptr, nullptr);
    EXPECT_TRUE(next.tracking.tracked) << next.tracking.lostReason;
    EXPECT_EQ(volume.framesIntegrated(), 2u);
    EXPECT_EQ(volume.frameNumber(), 2u);
}

INSTANTIATE_TEST_SUITE_P(SolvedOn, TrackingModes, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) { return info.param ? "Gpu" : "Host"; });

// The GPU-solved mode's first iteration against the host's: the same sums bit for bit (the same passes read the
// same estimate), and the float solve's step against the double one.
TEST_F(Tracking, GpuSolvedStepMatchesTheHostSolve) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    gpu::GpuVolume volume(context(), volumeConfig(0.03f));
    const Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
    ColorImage color0, color3;
    const DepthImage depth0 = roomFrame(0, &color0), depth3 = roomFrame(3, &color3);
    volume.integrate(depth0, k, orbit()[0]);
    TrackerOptions options;
    options.iterations = {1, 0, 0};   // one iteration, at level 0
    options.stopRotation = options.stopTranslation = 0;
    CameraTracker tracker(context(), kWidth, kHeight, options);
    const gpu::IcpResult onGpu = tracker.trackInOneSubmission(depth3, k, volume.meshBuffers(), orbit()[0], orbit()[0]);
    EXPECT_EQ(onGpu.iterations, 1);
    EXPECT_EQ(onGpu.submissions, 1u);
    ASSERT_TRUE(onGpu.solved);
    const IcpSums sums = tracker.sums(0, orbit()[0]);   // the maps are still those of trackInOneSubmission's frame
    const IcpSystem host = icpSystem(sums);
    EXPECT_EQ(onGpu.finalSystem.jtj, host.jtj);
    EXPECT_EQ(onGpu.finalSystem.jtr, host.jtr);
    EXPECT_EQ(onGpu.finalSystem.inliers, host.inliers);
    const IcpStep step = solveIcpStep(host);
    ASSERT_TRUE(step.solved);
    const Pose expected = applyTwist(step.twist, orbit()[0]);
    // The step is about 6 cm and 1.5 degrees (frame 3 against the pose of frame 0); the float solve agrees to
    // 1e-7 (measured: 7e-8 m, 5e-8 rad); asserted to 1e-5.
    const double moved = translationMetres(inverseRigid(orbit()[0]) * expected);
    const double translationError = (onGpu.cameraToWorld.block<3, 1>(0, 3) - expected.block<3, 1>(0, 3)).norm();
    const double rotationError = rotationDegrees(inverseRigid(expected) * onGpu.cameraToWorld) * std::numbers::pi / 180.0;
    std::printf("step %.4f m, %.4f degrees; GPU against host: %.3g m, %.3g rad\n", moved, rotationDegrees(inverseRigid(orbit()[0]) * expected),
                translationError, rotationError);
    EXPECT_GT(moved, 0.003);
    EXPECT_LT(translationError, 1e-5);
    EXPECT_LT(rotationError, 1e-5);
    EXPECT_LT((onGpu.cameraToWorld.block<3, 3>(0, 0).transpose() * onGpu.cameraToWorld.block<3, 3>(0, 0) - Eigen::Matrix3d::Identity()).norm(), 1e-12);
}

// Every sum is formed in a fixed order (no float atomics) and the model maps do not depend on the order of
// the mesh's triangles (which the fusion's atomics change from run to run: two volumes fused from the same
// frames hold the same triangles in another order), so the same frames give the same poses bit for bit.
// Before the maps were drawn order-independently, two runs differed at frame 5 of these 10 in two runs of three
// (one pixel where a front and a back face met at the same depth; docs/TRACKING.md, "Determinism").
TEST_P(TrackingModes, SameFramesGiveTheSameTrajectoryBitForBit) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    const TrackedRun a = trackOrbit(context(), 10, /*noise=*/true, 0.03f, GetParam());
    const TrackedRun b = trackOrbit(context(), 10, /*noise=*/true, 0.03f, GetParam());
    ASSERT_EQ(a.poses.size(), b.poses.size());
    for (size_t i = 0; i < a.poses.size(); ++i) {
        EXPECT_TRUE(a.reports[i].tracked) << "frame " << i;
        const double difference = (a.poses[i] - b.poses[i]).cwiseAbs().maxCoeff();
        EXPECT_EQ(std::memcmp(a.poses[i].data(), b.poses[i].data(), sizeof(double) * 16), 0) << "frame " << i << ", differs by " << difference;
    }
}

TEST_P(TrackingModes, JumpPastTheBoundIsRejectedAndTrackingPicksUpAgain) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    gpu::GpuVolume volume(context(), volumeConfig(0.03f));
    const Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
    TrackerOptions options;
    options.maxJumpMetres = 0.05;   // frame 4 lies about 10 cm from frame 0
    options.solveOnGpu = GetParam();
    PoseTracker tracker(context(), options);
    tracker.start(orbit()[0]);
    volume.integrate(roomDepth(0, false), k, orbit()[0]);
    const map::MapData before = volume.saveMap();
    const gpu::TrackedFusion jump = tracker.trackAndFuse(volume, roomDepth(4, false), k, nullptr, nullptr);
    EXPECT_FALSE(jump.tracking.tracked);
    EXPECT_FALSE(jump.fused.has_value());
    EXPECT_NE(jump.tracking.lostReason.find("jump"), std::string::npos) << jump.tracking.lostReason;
    EXPECT_TRUE(jump.tracking.cameraToWorld.isApprox(orbit()[0], 1e-12)) << "a lost frame gets the predicted pose";
    EXPECT_TRUE(map::serialize(volume.saveMap()) == map::serialize(before)) << "the rejected frame changed the map";
    const gpu::TrackedFusion next = tracker.trackAndFuse(volume, roomDepth(1, false), k, nullptr, nullptr);
    EXPECT_TRUE(next.tracking.tracked) << next.tracking.lostReason;
    EXPECT_TRUE(next.fused.has_value());
    EXPECT_EQ(volume.framesIntegrated(), 2u);
    EXPECT_EQ(volume.frameNumber(), 2u) << "the rejected frame took no frame number";
    EXPECT_LT((next.tracking.cameraToWorld.block<3, 1>(0, 3) - orbit()[1].block<3, 1>(0, 3)).norm(), 0.005);
}

// Frames tracking cannot use: no depth at all, NaN everywhere, another scene. Each is lost with its reason,
// nothing is fused, and the map is bit-identical afterwards; a good frame then tracks again. With the systems
// solved on the GPU the loss is decided there, in the submission that would have fused the frame.
TEST_P(TrackingModes, UnusableFramesAreLostAndLeaveTheMapBitIdentical) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    ReconstructorOptions options;
    options.volume = volumeConfig(0.03f);
    options.device.validation = true;
    options.tracker.solveOnGpu = GetParam();
    Reconstructor rec(options);
    const Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
    ASSERT_FALSE(rec.integrate(roomDepth(0, false), nullptr, k).lost());   // the first frame: fused at identity
    const Pose start = rec.trajectory().back();
    EXPECT_TRUE(start.isApprox(Pose::Identity()));
    const map::MapData before = rec.volume()->saveMap();
    const auto mapBytes = [](const map::MapData& m) { return map::serialize(m); };

    DepthImage empty = roomDepth(1, false);
    std::fill(empty.meters.begin(), empty.meters.end(), 0.0f);
    DepthImage nan = empty;
    std::fill(nan.meters.begin(), nan.meters.end(), std::numeric_limits<float>::quiet_NaN());
    const DepthImage other = synth::SyntheticScene::singleSphere(Eigen::Vector3d(0, 0, 2.5), 0.2).renderDepth(k, Pose::Identity());
    for (const auto& [name, depth] : {std::pair<const char*, const DepthImage*>{"no depth", &empty}, {"NaN", &nan}, {"another scene", &other}}) {
        const TrackedFrame f = rec.integrate(*depth, nullptr, k);
        EXPECT_TRUE(f.lost()) << name;
        EXPECT_FALSE(f.tracking.lostReason.empty()) << name;
        EXPECT_TRUE(f.cameraToWorld.isApprox(start, 1e-9)) << name;
        EXPECT_TRUE(mapBytes(rec.volume()->saveMap()) == mapBytes(before)) << name << ": the map changed";
    }
    EXPECT_EQ(rec.trajectory().size(), 4u);
    // The room seen from the start pose again (the camera did not move): tracked, but after a frame that disagreed
    // with the map (another scene) tracking that picks up again is tentative until confirmFrames more frames agree
    // (MapperOptions::Relocalisation): not fused until then, the map still bit-identical; then fused.
    const int confirm = MapperOptions{}.relocalisation.confirmFrames;
    for (int i = 0; i <= confirm; ++i) {
        const TrackedFrame again = rec.integrate(roomDepth(0, false), nullptr, k);
        EXPECT_LT(translationMetres(again.cameraToWorld), 0.002) << i;
        if (i < confirm) {
            EXPECT_TRUE(again.lost()) << i;
            EXPECT_NE(again.tracking.lostReason.find("tentative"), std::string::npos) << again.tracking.lostReason;
            EXPECT_TRUE(mapBytes(rec.volume()->saveMap()) == mapBytes(before)) << i << ": a tentative frame was fused";
        } else {
            EXPECT_FALSE(again.lost()) << again.tracking.lostReason;
        }
    }
}

// track_decide (the loss policy on the GPU, in the submission that fuses the frame) against its CPU reference,
// trackingLoss() in double, on the same ICP results: one frame per verdict. The tracked frame is fused at the
// GPU's estimate: its TSDF against the host path's fusion at that pose (the float inverse of the pose differs
// from the double one in the last bits).
TEST_F(Tracking, GpuLossDecisionMatchesTheHostPolicy) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;   // these tests draw the mesh
    const Intrinsics k = synth::kinectIntrinsics(kWidth, kHeight);
    TrackerOptions options;
    options.maxDepth = 5.0f;
    options.minErrorForRise = 0.0;   // so that a tiny recent error makes this frame's "rise"
    // The wall's fused mesh bends at its border, which constrains it a little (conditioning 3e-4, measured); the
    // room's frames are at 2e-2.
    options.minConditioning = 1e-3;
    CameraTracker tracker(context(), kWidth, kHeight, options);
    const DepthImage depth0 = roomDepth(0, false), depth1 = roomDepth(1, false);
    DepthImage empty = depth1;
    std::fill(empty.meters.begin(), empty.meters.end(), 0.0f);
    // A small ball 1.5 m in front of the camera, where the room has nothing.
    const Eigen::Vector3d ball = orbit()[0].block<3, 3>(0, 0) * Eigen::Vector3d(0, 0, 1.5) + orbit()[0].block<3, 1>(0, 3);
    const DepthImage other = synth::SyntheticScene::singleSphere(ball, 0.2).renderDepth(k, orbit()[0]);
    // A wall straight ahead and nothing else: the motion along it is barely constrained (the wall fused first).
    DepthImage wall = depth1;
    std::fill(wall.meters.begin(), wall.meters.end(), 2.0f);
    Pose turned = orbit()[0];
    turned.block<3, 3>(0, 0) = turned.block<3, 3>(0, 0) * Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitY()).toRotationMatrix();
    Pose moved = orbit()[0];
    moved(0, 3) += 1.0;
    struct Case {
        const char* name;
        const DepthImage* depth;
        const DepthImage* fusedFirst;
        Pose lastTracked;
        gpu::RecentFrames recent;
        uint32_t expected;
    };
    const Case cases[] = {
        {"tracked", &depth1, &depth0, orbit()[0], {}, gpu::TRACK_TRACKED},
        {"no depth", &empty, &depth0, orbit()[0], {}, gpu::TRACK_LOST_NO_DEPTH},
        {"another scene", &other, &depth0, orbit()[0], {}, gpu::TRACK_LOST_FEW_INLIERS},
        {"one plane", &wall, &wall, orbit()[0], {}, gpu::TRACK_LOST_ILL_CONDITIONED},
        {"jump", &depth1, &depth0, moved, {}, gpu::TRACK_LOST_JUMP},
        {"turn", &depth1, &depth0, turned, {}, gpu::TRACK_LOST_TURN},
        {"error rose", &depth1, &depth0, orbit()[0], {1e-7, 0.0}, gpu::TRACK_LOST_ERROR_ROSE},
        // Recent frames matched over almost twice the pixels this one can (a share of 1.9 is impossible: the check
        // is inliers < 0.5 * 1.9 * valid pixels, true for any share below 0.95).
        {"share fell", &depth1, &depth0, orbit()[0], {0.0, 1.9}, gpu::TRACK_LOST_SHARE_FELL},
    };
    for (const Case& c : cases) {
        gpu::GpuVolume volume(context(), volumeConfig(0.03f));
        volume.integrate(*c.fusedFirst, k, orbit()[0]);
        const map::MapData before = volume.saveMap();
        const gpu::MeshBuffers mesh = volume.meshBuffers();
        gpu::FrameInput input;
        input.depth = c.depth;
        input.intrinsics = k;
        input.recordPose = [&](VkCommandBuffer cmd, const vk::Buffer& framePose) {
            tracker.recordTrackAndDecide(cmd, *c.depth, k, mesh, orbit()[0], orbit()[0], nullptr, c.lastTracked, c.recent, framePose);
        };
        volume.submitFrame(input);
        const gpu::FrameReport frame = volume.finishFrame();
        const gpu::IcpResult icp = tracker.gpuSolvedResult();
        const Pose motion = inverseRigid(c.lastTracked) * icp.gpuEstimate;
        const uint32_t host = gpu::trackingLoss(icp.finalSystem, icp.finalStep.solved, icp.finalStep.conditioning, motion, c.recent, options);
        std::printf("%-14s GPU verdict %u, host %u; conditioning GPU %.6g, host %.6g\n", c.name, icp.gpuLostReason, host, icp.gpuConditioning,
                    icp.finalStep.conditioning);
        EXPECT_EQ(icp.gpuLostReason, c.expected) << c.name;
        EXPECT_EQ(icp.gpuLostReason, host) << c.name;
        // Float against double: relative 1e-3 (measured: 2e-5 on the wall, equal to 6 digits on the room).
        EXPECT_NEAR(icp.gpuConditioning, icp.finalStep.conditioning, 1e-3 * icp.finalStep.conditioning + 1e-7) << c.name;
        EXPECT_EQ(frame.skipped, c.expected != gpu::TRACK_TRACKED) << c.name;
        if (frame.skipped) {
            EXPECT_TRUE(map::serialize(volume.saveMap()) == map::serialize(before)) << c.name << ": a lost frame changed the map";
            EXPECT_EQ(volume.framesIntegrated(), 1u) << c.name;
            continue;
        }
        // Fused at the GPU's estimate: the same TSDF as the host path's fusion at that pose, to float rounding.
        EXPECT_EQ(volume.framesIntegrated(), 2u);
        gpu::GpuVolume reference(context(), volumeConfig(0.03f));
        reference.integrate(depth0, k, orbit()[0]);
        reference.integrate(depth1, k, icp.gpuEstimate);
        std::map<std::array<int, 3>, gpu::BlockSnapshot> expected;
        for (gpu::BlockSnapshot& b : reference.downloadBlocks()) expected[{b.coord.x(), b.coord.y(), b.coord.z()}] = std::move(b);
        const std::vector<gpu::BlockSnapshot> fused = volume.downloadBlocks();
        EXPECT_EQ(fused.size(), expected.size());
        double worst = 0;
        size_t weightsDiffer = 0;
        for (const gpu::BlockSnapshot& b : fused) {
            auto it = expected.find({b.coord.x(), b.coord.y(), b.coord.z()});
            ASSERT_NE(it, expected.end()) << "block " << b.coord.transpose() << " is not in the host path's map";
            for (size_t v = 0; v < b.sdf.size(); ++v) {
                if (b.weight[v] != it->second.weight[v]) ++weightsDiffer;
                else worst = std::max(worst, double(std::abs(b.sdf[v] - it->second.sdf[v])));
            }
        }
        std::printf("fused at the GPU's estimate: TSDF within %.3g m of the host path's, %zu corner weights differ\n", worst, weightsDiffer);
        EXPECT_LT(worst, 1e-4);
        EXPECT_LT(weightsDiffer, 20u);   // a corner on the edge of a pixel or of the truncation band may flip
    }
}

}  // namespace
}  // namespace vkmesh
