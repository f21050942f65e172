// The embedding API (api/reconstructor.h): vkmesh on a device the application created and owns, the mesh
// drawn straight from vkmesh's GPU buffers (zero copy), under the validation layer with synchronisation
// validation on. The application side here is raw Vulkan, as a renderer embedding vkmesh would write it.
#include <gtest/gtest.h>

#include <cstring>
#include <mutex>
#include <string>
#include <vector>

#include "api/exported_mesh.h"
#include "api/reconstructor.h"
#include "core/mesh_analysis.h"
#include "gpu_fixture.h"
#include "render/mesh_renderer.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"
#include "vk/buffer.h"
#include "vk/check.h"
#include "vk/commands.h"
#include "../../host/embed_example/app_device.h"

namespace vkmesh {
namespace {

constexpr int kWidth = 160, kHeight = 120;
using example::AppDevice;

ReconstructorOptions smallRoomOptions() {
    ReconstructorOptions o;
    o.volume.params.voxelSize = 0.05f;
    o.volume.params.maxDepth = 6.0f;
    o.volume.blockCapacity = 4096;
    o.volume.vertexCapacity = 1u << 17;
    o.volume.chunkCapacity = 1u << 17;
    return o;
}

struct Frame {
    DepthImage depth;
    Intrinsics intrinsics;
    Pose pose;
};

std::vector<Frame> roomFrames(size_t count) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    auto poses = synth::cameraPath(24);
    std::vector<Frame> frames;
    for (size_t i = 0; i < count; ++i) frames.push_back({scene.renderDepth(intr, poses[i % poses.size()], {}), intr, poses[i % poses.size()]});
    return frames;
}

// Reads the VkDrawIndexedIndirectCommand the way an application could: a copy on the device.
VkDrawIndexedIndirectCommand readDrawCommand(const vk::Context& context, const gpu::MeshBuffers& mesh) {
    const std::vector<uint8_t> bytes = test::readDeviceBuffer(context, mesh.drawIndirect, mesh.drawIndirectOffset, sizeof(VkDrawIndexedIndirectCommand));
    VkDrawIndexedIndirectCommand out{};
    std::memcpy(&out, bytes.data(), sizeof(out));
    return out;
}

size_t differingPixels(const render::Image& a, const render::Image& b) {
    size_t n = 0;
    for (size_t i = 0; i + 3 < a.rgba.size(); i += 4)
        n += std::memcmp(&a.rgba[i], &b.rgba[i], 3) != 0;
    return n;
}

size_t coveredPixels(const render::Image& image) {
    size_t n = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const uint8_t* p = image.pixel(x, y);
            n += !(p[0] == render::kBackground[0] && p[1] == render::kBackground[1] && p[2] == render::kBackground[2]);
        }
    return n;
}

TEST(Embedding, AppOwnedDeviceDrawsTheMeshFromVkmeshBuffers) {
    if (const std::string why = test::lavapipeCannotDraw(); !why.empty()) GTEST_SKIP() << why;
    AppDevice app(true);
    {
        Reconstructor reconstructor(app.external(), smallRoomOptions());
        EXPECT_FALSE(reconstructor.context().ownsDevice());
        EXPECT_EQ(reconstructor.meshBuffers().vertices, VkBuffer(VK_NULL_HANDLE)) << "no mesh before the first frame";
        // The application's renderer, on the same device and queue family.
        vk::Context renderContext(app.external());
        render::MeshRenderer renderer(renderContext);
        render::RenderOptions view;
        view.width = 160;
        view.height = 120;

        size_t frameIndex = 0;
        uint32_t lastTriangles = 0;
        for (const Frame& f : roomFrames(8)) {
            gpu::FrameReport report = reconstructor.integrate(f.depth, f.intrinsics, f.pose);
            EXPECT_TRUE(report.warnings.empty());
            ++frameIndex;
            gpu::MeshBuffers buffers = reconstructor.meshBuffers();
            ASSERT_NE(buffers.vertices, VkBuffer(VK_NULL_HANDLE));
            EXPECT_EQ(buffers.frame, frameIndex);
            // The indirect command the GPU wrote matches the counts, and the counts match a host download.
            VkDrawIndexedIndirectCommand draw = readDrawCommand(renderContext, buffers);
            EXPECT_EQ(draw.indexCount, 3 * buffers.triangleCount);
            EXPECT_EQ(draw.instanceCount, 1u);
            EXPECT_GT(buffers.triangleCount, lastTriangles / 2) << "frame " << frameIndex;
            lastTriangles = buffers.triangleCount;

            if (frameIndex % 4 != 0) continue;
            // Zero copy: the picture drawn from vkmesh's buffers equals the one drawn from a host copy
            // uploaded by the renderer (same vertices, same order, same indices). The host copy also
            // gives the test its view (an application would know its scene's extent).
            gpu::ExportedMesh host = reconstructor.downloadMesh();
            EXPECT_EQ(host.triangles.size(), buffers.triangleCount);
            EXPECT_EQ(host.vertices.size(), buffers.vertexCount);
            Mesh hostMesh = toMesh(host);
            Eigen::Vector3f lo = hostMesh.positions[0], hi = lo;
            for (const auto& p : hostMesh.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
            view.camera = render::defaultCamera(lo, hi, view.width, view.height);
            buffers = reconstructor.meshBuffers();   // downloadMesh() may have reallocated them
            render::Image fromGpu = renderer.render(buffers, lo, hi, view);
            render::Image fromHost = renderer.render(hostMesh, view);
            EXPECT_GT(coveredPixels(fromGpu), size_t(view.width * view.height / 25)) << "frame " << frameIndex;
            EXPECT_EQ(differingPixels(fromGpu, fromHost), 0u) << "frame " << frameIndex;
        }
        EXPECT_GT(lastTriangles, 1000u);
    }
    // Everything vkmesh created is gone; the application's device is still usable and nobody complained.
    EXPECT_EQ(vkDeviceWaitIdle(app.device), VK_SUCCESS);
    auto messages = app.takeMessages();
    EXPECT_TRUE(messages.empty()) << messages.size() << " validation messages, first: " << messages.front();
}

TEST(Embedding, ExternalDeviceErrorsNameWhatIsWrong) {
    vk::ExternalDevice none;
    try {
        vk::Context context(none);
        FAIL() << "an empty ExternalDevice was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("instance, physicalDevice and device"), std::string::npos) << e.what();
    }
    AppDevice app(true);
    vk::ExternalDevice badFamily = app.external();
    badFamily.queueFamily = 99;
    try {
        Reconstructor reconstructor(badFamily);
        FAIL() << "queue family 99 was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("queue family 99"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(app.takeMessages().empty());
}

class OwnDevice : public test::GpuTest {};

TEST_F(OwnDevice, PublishedMeshEqualsTheExportAndSurvivesARebuild) {
    gpu::GpuVolumeConfig config = smallRoomOptions().volume;
    config.imageWidth = kWidth;
    config.imageHeight = kHeight;
    config.publishMesh = true;
    gpu::GpuVolume volume(context(), config);
    for (const Frame& f : roomFrames(6)) volume.integrate(f.depth, f.intrinsics, f.pose);
    gpu::MeshBuffers published = volume.meshBuffers();
    gpu::ExportedMesh exported = volume.exportMesh();
    EXPECT_EQ(published.triangleCount, exported.triangles.size());
    EXPECT_EQ(published.vertexCount, exported.vertices.size());
    auto before = canonicalTriangles(toMesh(exported));
    volume.rebuildMesh();
    gpu::MeshBuffers rebuilt = volume.meshBuffers();
    EXPECT_EQ(rebuilt.triangleCount, published.triangleCount);
    EXPECT_EQ(readDrawCommand(context(), rebuilt).indexCount, 3 * rebuilt.triangleCount);
    EXPECT_EQ(countTriangleMismatches(before, canonicalTriangles(toMesh(volume.exportMesh()))), 0u);
}

TEST_F(OwnDevice, PublishingNeedsTheIncrementalMesh) {
    gpu::GpuVolumeConfig config;
    config.meshMode = gpu::MeshMode::Baseline;
    config.publishMesh = true;
    EXPECT_THROW(gpu::GpuVolume(context(), config), Error);
}

}  // namespace
}  // namespace vkmesh
