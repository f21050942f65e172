// Asynchronous frames and GPU input (api/reconstructor.h, GpuVolume::submitFrame/finishFrame): a frame
// submitted without waiting gives the blocking frame's mesh; its published buffers hold that mesh once the
// timeline reaches the frame's value and keep it while the next frame is fused into the other set; depth and
// colour handed over in GPU buffers or images give what the host images give. Validation (with
// synchronisation validation) on: any message fails.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <tuple>
#include <string>
#include <vector>

#include "api/exported_mesh.h"
#include "api/reconstructor.h"
#include "core/mesh_analysis.h"
#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "synth/synthetic_scene.h"
#include "test_support.h"
#include "vk/buffer.h"
#include "vk/check.h"
#include "vk/commands.h"
#include "../../host/embed_example/app_device.h"

namespace vkmesh {
namespace {

constexpr int kWidth = 160, kHeight = 120;
using test::GpuTest;

gpu::GpuVolumeConfig roomConfig(bool color) {
    gpu::GpuVolumeConfig c;
    c.params.voxelSize = 0.05f;
    c.params.maxDepth = 6.0f;
    c.params.colorFusion = color ? ColorFusion::Average : ColorFusion::Off;
    c.blockCapacity = 4096;
    c.vertexCapacity = 1u << 17;
    c.chunkCapacity = 1u << 17;
    c.imageWidth = kWidth;
    c.imageHeight = kHeight;
    c.publishMesh = true;
    return c;
}

struct Frame {
    DepthImage depth;
    ColorImage color;
    Intrinsics intrinsics;
    Pose pose;
};

std::vector<Frame> roomFrames(size_t count) {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    const Intrinsics intr = synth::kinectIntrinsics(kWidth, kHeight);
    const auto poses = synth::cameraPath(24);
    std::vector<Frame> frames;
    for (size_t i = 0; i < count; ++i) {
        synth::RenderOptions noisy;
        noisy.noise = true;
        noisy.seed = uint32_t(i + 1);
        const Pose& pose = poses[i % poses.size()];
        Frame f{{}, {}, intr, pose};
        f.depth = scene.renderDepth(intr, pose, noisy, &f.color);
        frames.push_back(std::move(f));
    }
    return frames;
}

// The mesh in published buffers, read through its indirect draw command (the counts a renderer never reads).
Mesh readPublished(const vk::Context& context, const gpu::MeshBuffers& b) {
    VkDrawIndexedIndirectCommand draw{};
    const auto drawBytes = test::readDeviceBuffer(context, b.drawIndirect, b.drawIndirectOffset, sizeof(draw));
    std::memcpy(&draw, drawBytes.data(), sizeof(draw));
    gpu::ExportedMesh e;
    e.triangles.resize(draw.indexCount / 3);
    const auto indexBytes = test::readDeviceBuffer(context, b.indices, 0, VkDeviceSize(draw.indexCount) * 4);
    std::memcpy(e.triangles.data(), indexBytes.data(), indexBytes.size());
    uint32_t vertices = 0;
    for (const auto& t : e.triangles)
        for (uint32_t v : t) vertices = std::max(vertices, v + 1);
    e.vertices.resize(vertices);
    const auto vertexBytes = test::readDeviceBuffer(context, b.vertices, 0, VkDeviceSize(vertices) * sizeof(gpu::Vertex));
    std::memcpy(e.vertices.data(), vertexBytes.data(), vertexBytes.size());
    return toMesh(e);
}

size_t mismatches(const Mesh& a, const Mesh& b) { return countTriangleMismatches(canonicalTriangles(a), canonicalTriangles(b)); }

gpu::FrameInput hostInput(const Frame& f, bool withColor) {
    gpu::FrameInput in;
    in.depth = &f.depth;
    in.color = withColor ? &f.color : nullptr;
    in.intrinsics = f.intrinsics;
    in.cameraToWorld = f.pose;
    return in;
}

// The asynchronous form, frame by frame against the blocking one on the same frames: each published set
// holds its frame's mesh when the timeline reaches the frame's value, and still holds it after the next
// frame was fused into the other set; the reports (one frame late) and the final mesh are the blocking ones.
TEST_F(GpuTest, AsyncFramesPublishTheBlockingMeshIntoAlternatingSets) {
    const auto frames = roomFrames(8);
    gpu::GpuVolume blocking(context(), roomConfig(true)), async(context(), roomConfig(true));
    std::vector<Mesh> blockingMeshes;
    std::vector<gpu::FrameReport> blockingReports;
    for (const Frame& f : frames) {
        blockingReports.push_back(blocking.integrate(f.depth, &f.color, f.intrinsics, f.pose));
        blockingMeshes.push_back(readPublished(context(), blocking.meshBuffers()));
        ASSERT_GT(blockingMeshes.back().triangles.size(), 0u);
    }
    gpu::MeshBuffers previousSet{};
    for (size_t i = 0; i < frames.size(); ++i) {
        if (async.framePending()) {
            const gpu::FrameReport r = async.finishFrame();
            EXPECT_EQ(r.counters.liveTriangles, blockingReports[i - 1].counters.liveTriangles) << "frame " << i;
            EXPECT_EQ(r.counters.verticesInUse, blockingReports[i - 1].counters.verticesInUse) << "frame " << i;
        }
        async.submitFrame(hostInput(frames[i], true), i + 1);
        const gpu::MeshBuffers set = async.meshBuffers();
        EXPECT_EQ(set.readyValue, i + 1);
        EXPECT_EQ(set.triangleCount, 0u) << "counts are unknown while the frame is in flight";
        if (i > 0) {
            EXPECT_NE(set.vertices, previousSet.vertices) << "frame " << i + 1 << " writes the set frame " << i << " is drawn from";
            EXPECT_NE(set.drawIndirect, previousSet.drawIndirect);
        }
        async.timeline().wait(i + 1);
        EXPECT_EQ(mismatches(readPublished(context(), set), blockingMeshes[i]), 0u) << "frame " << i + 1 << " at its ready value";
        if (i > 0) {
            // The last frame's set is untouched by this one (read after this frame's GPU work is done).
            EXPECT_EQ(mismatches(readPublished(context(), previousSet), blockingMeshes[i - 1]), 0u) << "frame " << i;
        }
        previousSet = set;
    }
    async.finishFrame();
    EXPECT_FALSE(async.framePending());
    EXPECT_EQ(async.timeline().value(), frames.size());
    EXPECT_EQ(mismatches(toMesh(async.exportMesh()), toMesh(blocking.exportMesh())), 0u);
    EXPECT_THROW(async.finishFrame(), Error);
}

// A frame in flight must be finished before the next is submitted; a frame has one depth image.
TEST_F(GpuTest, AsyncMisuseIsAClearError) {
    const auto frames = roomFrames(1);
    gpu::GpuVolume volume(context(), roomConfig(false));
    volume.submitFrame(hostInput(frames[0], false), 1);
    const std::string twice = test::errorMessageOf([&] { volume.submitFrame(hostInput(frames[0], false), 2); });
    EXPECT_NE(twice.find("has not been finished"), std::string::npos) << twice;
    volume.finishFrame();
    gpu::FrameInput none = hostInput(frames[0], false);
    none.depth = nullptr;
    EXPECT_NE(test::errorMessageOf([&] { volume.submitFrame(none); }).find("exactly one depth image"), std::string::npos);
    gpu::FrameInput badImage = hostInput(frames[0], false);
    badImage.depth = nullptr;
    badImage.gpuDepth.image = reinterpret_cast<VkImage>(uintptr_t(1));   // never used: the format is refused first
    badImage.gpuDepth.format = VK_FORMAT_R16_UNORM;
    const std::string format = test::errorMessageOf([&] { volume.submitFrame(badImage); });
    EXPECT_NE(format.find("R32_SFLOAT or D32_SFLOAT"), std::string::npos) << format;
    EXPECT_FALSE(volume.framePending());
}

// Device-local buffers and images the "application" fills on the GPU (from staging), as a renderer or
// simulator producing depth on the GPU would hand them over.
struct AppImages {
    const vk::Context& context;
    vk::Buffer depthBuffer, colorBuffer;
    VkImage depthImage = VK_NULL_HANDLE, colorImage = VK_NULL_HANDLE;
    VkDeviceMemory memory[2] = {VK_NULL_HANDLE, VK_NULL_HANDLE};

    explicit AppImages(const vk::Context& c)
        : context(c),
          depthBuffer(c, VkDeviceSize(kWidth) * kHeight * 4 + 256, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, vk::MemoryUse::Device, "app depth"),
          colorBuffer(c, VkDeviceSize(kWidth) * kHeight * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, vk::MemoryUse::Device, "app colour") {
        depthImage = makeImage(VK_FORMAT_R32_SFLOAT, memory[0]);
        colorImage = makeImage(VK_FORMAT_R8G8B8A8_UNORM, memory[1]);
    }
    ~AppImages() {
        vkDestroyImage(context.device(), depthImage, nullptr);
        vkDestroyImage(context.device(), colorImage, nullptr);
        for (VkDeviceMemory m : memory) vkFreeMemory(context.device(), m, nullptr);
    }

    VkImage makeImage(VkFormat format, VkDeviceMemory& memoryOut) {
        VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
        info.imageType = VK_IMAGE_TYPE_2D;
        info.format = format;
        info.extent = {uint32_t(kWidth), uint32_t(kHeight), 1};
        info.mipLevels = 1;
        info.arrayLayers = 1;
        info.samples = VK_SAMPLE_COUNT_1_BIT;
        info.tiling = VK_IMAGE_TILING_OPTIMAL;
        info.usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
        VkImage image = VK_NULL_HANDLE;
        vk::check(vkCreateImage(context.device(), &info, nullptr, &image), "vkCreateImage");
        VkMemoryRequirements req;
        vkGetImageMemoryRequirements(context.device(), image, &req);
        VkPhysicalDeviceMemoryProperties props;
        vkGetPhysicalDeviceMemoryProperties(context.physicalDevice(), &props);
        uint32_t type = 0;
        while (!((req.memoryTypeBits >> type) & 1u)) ++type;
        VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        alloc.allocationSize = req.size;
        alloc.memoryTypeIndex = type;
        vk::check(vkAllocateMemory(context.device(), &alloc, nullptr, &memoryOut), "vkAllocateMemory");
        vk::check(vkBindImageMemory(context.device(), image, memoryOut, 0), "vkBindImageMemory");
        return image;
    }

    // Uploads one frame into the buffers (depth at byte offset 256, to check the offset) and the images,
    // leaving the images in TRANSFER_SRC_OPTIMAL.
    void upload(const Frame& f) {
        const VkDeviceSize pixels = VkDeviceSize(kWidth) * kHeight;
        std::vector<uint32_t> rgba(pixels);
        for (size_t i = 0; i < pixels; ++i)
            rgba[i] = uint32_t(f.color.rgb[3 * i]) | uint32_t(f.color.rgb[3 * i + 1]) << 8 | uint32_t(f.color.rgb[3 * i + 2]) << 16 |
                      0xFF000000u;
        vk::uploadToBuffer(context, depthBuffer, f.depth.meters.data(), pixels * 4, 256);
        vk::uploadToBuffer(context, colorBuffer, rgba.data(), pixels * 4);
        vk::Buffer staging(context, pixels * 8, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::Upload, "app staging");
        std::memcpy(staging.mapped(), f.depth.meters.data(), pixels * 4);
        std::memcpy(static_cast<uint8_t*>(staging.mapped()) + pixels * 4, rgba.data(), pixels * 4);
        vk::CommandRecorder recorder(context);
        VkCommandBuffer cmd = recorder.begin();
        for (int i = 0; i < 2; ++i) {
            VkImage image = i == 0 ? depthImage : colorImage;
            VkImageMemoryBarrier toDst{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
            toDst.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
            toDst.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
            toDst.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
            toDst.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
            toDst.srcQueueFamilyIndex = toDst.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
            toDst.image = image;
            toDst.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
            vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &toDst);
            VkBufferImageCopy region{};
            region.bufferOffset = i == 0 ? 0 : pixels * 4;
            region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
            region.imageExtent = {uint32_t(kWidth), uint32_t(kHeight), 1};
            vkCmdCopyBufferToImage(cmd, staging.handle(), image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
            VkImageMemoryBarrier toSrc = toDst;
            toSrc.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
            toSrc.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
            toSrc.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
            toSrc.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
            vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &toSrc);
        }
        recorder.submitAndWait();
    }
};

// Depth and colour in the application's GPU buffers, or in its images, fuse to the host images' mesh,
// colours included, blocking and asynchronously.
TEST_F(GpuTest, GpuBufferAndImageInputGiveTheHostInputsMesh) {
    const auto frames = roomFrames(5);
    gpu::GpuVolume host(context(), roomConfig(true)), fromBuffers(context(), roomConfig(true)), fromImages(context(), roomConfig(true));
    AppImages app(context());
    for (size_t i = 0; i < frames.size(); ++i) {
        const Frame& f = frames[i];
        host.integrate(f.depth, &f.color, f.intrinsics, f.pose);
        app.upload(f);
        gpu::FrameInput buffers;
        buffers.gpuDepth.buffer = app.depthBuffer.handle();
        buffers.gpuDepth.offset = 256;
        buffers.gpuColor.buffer = app.colorBuffer.handle();
        buffers.intrinsics = f.intrinsics;
        buffers.cameraToWorld = f.pose;
        fromBuffers.submitFrame(buffers);
        fromBuffers.finishFrame();
        gpu::FrameInput images = buffers;
        images.gpuDepth = {};
        images.gpuDepth.image = app.depthImage;
        images.gpuDepth.format = VK_FORMAT_R32_SFLOAT;
        images.gpuColor = {};
        images.gpuColor.image = app.colorImage;
        images.gpuColor.format = VK_FORMAT_R8G8B8A8_UNORM;
        fromImages.submitFrame(images, i + 1);   // asynchronous: the images are copied on the GPU, so the frame
        fromImages.finishFrame();                // is finished before the next upload overwrites them
    }
    const gpu::ExportedMesh expected = host.exportMesh();
    ASSERT_GT(expected.triangles.size(), 0u);
    for (gpu::GpuVolume* v : {&fromBuffers, &fromImages}) {
        const gpu::ExportedMesh got = v->exportMesh();
        ASSERT_EQ(got.vertices.size(), expected.vertices.size());
        EXPECT_EQ(mismatches(toMesh(got), toMesh(expected)), 0u);
        // Vertex order in the heap depends on thread scheduling: match vertices by their position's bits.
        auto colorsByPosition = [](const gpu::ExportedMesh& m) {
            std::map<std::tuple<float, float, float>, uint32_t> out;
            for (const gpu::Vertex& v : m.vertices) out[{v.px, v.py, v.pz}] = v.color;
            return out;
        };
        const auto want = colorsByPosition(expected);
        EXPECT_EQ(colorsByPosition(got), want) << "vertex colours";
        size_t colored = 0;
        for (const auto& [position, color] : want) colored += (color >> 24) != 0;
        EXPECT_GT(colored, want.size() / 2) << "the frames' colours reached the mesh";
    }
}

// The host's images written in place (a device with unified memory: lavapipe, integrated GPUs) or through a
// staging buffer and a copy (a discrete GPU; VKMESH_PRETEND_MISSING=unifiedMemory here) give the same mesh,
// colours included, blocking and asynchronously. The suite runs on both paths: the portability job pretends
// unified memory away.
TEST_F(GpuTest, HostImagesInPlaceOrStagedGiveTheSameMesh) {
    const bool fixtureUnified = context().unifiedMemory();
    const char* env = std::getenv("VKMESH_PRETEND_MISSING");
    const std::string saved = env ? env : "";
    if (fixtureUnified) setenv("VKMESH_PRETEND_MISSING", "unifiedMemory", 1);
    else unsetenv("VKMESH_PRETEND_MISSING");
    auto other = std::make_unique<vk::Context>(vk::ContextOptions{-1, true});
    if (env) setenv("VKMESH_PRETEND_MISSING", saved.c_str(), 1);
    else unsetenv("VKMESH_PRETEND_MISSING");
    if (!fixtureUnified && !other->unifiedMemory()) GTEST_SKIP() << "this device has no unified memory";
    ASSERT_NE(other->unifiedMemory(), fixtureUnified) << "VKMESH_PRETEND_MISSING=unifiedMemory changes the input path";
    vk::Context& inPlaceContext = fixtureUnified ? context() : *other;
    vk::Context& stagedContext = fixtureUnified ? *other : context();

    const auto frames = roomFrames(5);
    {
        gpu::GpuVolume inPlace(inPlaceContext, roomConfig(true)), staged(stagedContext, roomConfig(true));
        auto hasStaging = [](const gpu::GpuVolume& v) {
            for (const auto& pool : v.pools())
                if (pool.name == "depth staging" && pool.bytes > 0) return true;
            return false;
        };
        EXPECT_FALSE(hasStaging(inPlace));
        EXPECT_TRUE(hasStaging(staged));
        for (size_t i = 0; i < frames.size(); ++i) {
            const Frame& f = frames[i];
            staged.integrate(f.depth, &f.color, f.intrinsics, f.pose);
            // Asynchronously: the host writes the next frame's images into the buffer the last frame read.
            inPlace.submitFrame(gpu::FrameInput::fromHost(f.depth, &f.color, f.intrinsics, f.pose), i + 1);
            inPlace.finishFrame();
        }
        const gpu::ExportedMesh want = staged.exportMesh(), got = inPlace.exportMesh();
        ASSERT_GT(want.triangles.size(), 0u);
        ASSERT_EQ(got.vertices.size(), want.vertices.size());
        EXPECT_EQ(mismatches(toMesh(got), toMesh(want)), 0u);
        auto colorsByPosition = [](const gpu::ExportedMesh& m) {
            std::map<std::tuple<float, float, float>, uint32_t> out;
            for (const gpu::Vertex& v : m.vertices) out[{v.px, v.py, v.pz}] = v.color;
            return out;
        };
        EXPECT_EQ(colorsByPosition(got), colorsByPosition(want)) << "vertex colours";
    }
    const auto messages = other->takeValidationMessages();
    EXPECT_TRUE(messages.empty()) << messages.size() << " validation messages, first: " << messages.front();
}

// The Reconstructor's asynchronous form on an application's device: reports one call late, the same mesh
// as the blocking form, save() and downloadMesh() finish the frame in flight; no validation message.
TEST(Async, ReconstructorOnAnApplicationsDevice) {
    example::AppDevice app(true);
    const auto frames = roomFrames(6);
    ReconstructorOptions options;
    options.volume = roomConfig(true);
    size_t reports = 0;
    Mesh asyncMesh, blockingMesh;
    {
        Reconstructor async(app.external(), options);
        for (const Frame& f : frames) {
            Reconstructor::AsyncFrame a = async.integrateAsync(f.depth, &f.color, f.intrinsics, f.pose);
            EXPECT_EQ(a.frame, reports + 1);
            EXPECT_EQ(a.readyValue, reports + 1);
            EXPECT_NE(a.ready, VK_NULL_HANDLE);
            EXPECT_EQ(a.previous.has_value(), reports > 0);
            ++reports;
        }
        EXPECT_EQ(async.framesIntegrated(), frames.size());
        asyncMesh = toMesh(async.downloadMesh());
        EXPECT_FALSE(async.finish().has_value()) << "downloadMesh() finished the last frame";
    }
    {
        Reconstructor blocking(app.external(), options);
        for (const Frame& f : frames) blocking.integrate(f.depth, &f.color, f.intrinsics, f.pose);
        blockingMesh = toMesh(blocking.downloadMesh());
    }
    EXPECT_GT(asyncMesh.triangles.size(), 0u);
    EXPECT_EQ(mismatches(asyncMesh, blockingMesh), 0u);
    const auto messages = app.takeMessages();
    EXPECT_TRUE(messages.empty()) << messages.size() << " validation messages, first: " << messages.front();
}

}  // namespace
}  // namespace vkmesh
