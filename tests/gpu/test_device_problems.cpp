// Device problems (issue 5): no Vulkan driver, a device without what vkmesh needs, capacities that do not
// fit the device's buffers or memory. Each gives a message saying what is missing and what to change,
// before anything is allocated, never a crash.
#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <string>

#include "gpu/gpu_volume.h"
#include "gpu_fixture.h"
#include "test_support.h"

namespace vkmesh {
namespace {

constexpr uint64_t kMiB = 1ull << 20;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(DeviceProblems, BufferLargerThanOneBindingNamesTheSettingAndItsLimit) {
    gpu::GpuVolumeConfig config;
    config.blockCapacity = 300000;   // 586 MiB of TSDF per array
    std::string m = test::errorMessageOf([&] { gpu::checkCapacities(config, 128 * kMiB, 16384 * kMiB, "Test GPU"); });
    EXPECT_TRUE(contains(m, "voxel sdf")) << m;
    EXPECT_TRUE(contains(m, "--blocks")) << m;
    EXPECT_TRUE(contains(m, "at most 65536")) << m;   // 128 MiB / (512 corners x 4 bytes)
    EXPECT_TRUE(contains(m, "Test GPU")) << m;

    gpu::GpuVolumeConfig vertices;
    vertices.vertexCapacity = 30000000;
    m = test::errorMessageOf([&] { gpu::checkCapacities(vertices, 128 * kMiB, 16384 * kMiB, "Test GPU"); });
    // 128 MiB / sizeof(Vertex) (36 bytes) = 3728270.
    EXPECT_TRUE(contains(m, "vertex heap") && contains(m, "--vertices") && contains(m, std::to_string(128 * kMiB / sizeof(gpu::Vertex)))) << m;
}

TEST(DeviceProblems, CapacitiesBeyondTheDeviceMemoryAreRefusedUpFront) {
    gpu::GpuVolumeConfig config;   // defaults: about 0.5 GiB
    std::string m = test::errorMessageOf([&] { gpu::checkCapacities(config, 128 * kMiB, 256 * kMiB, "Small GPU"); });
    EXPECT_TRUE(contains(m, "device memory")) << m;
    EXPECT_TRUE(contains(m, "Small GPU has 256 MiB")) << m;
    EXPECT_TRUE(contains(m, "--blocks") || contains(m, "--vertices") || contains(m, "--chunks")) << m;
    // The same configuration fits a device with enough memory.
    EXPECT_NO_THROW(gpu::checkCapacities(config, 128 * kMiB, 4096 * kMiB, "Big GPU"));
}

class DeviceProblemsOnDevice : public test::GpuTest {};

TEST_F(DeviceProblemsOnDevice, TheVolumeChecksBeforeAllocating) {
    gpu::GpuVolumeConfig config;
    config.blockCapacity = 1u << 30;   // 2 TiB of TSDF: must be refused, not attempted
    std::string m = test::errorMessageOf([&] { gpu::GpuVolume volume(context(), config); });
    EXPECT_TRUE(contains(m, "--blocks")) << m;
    EXPECT_TRUE(contains(m, context().info().name)) << m;
}

TEST(DeviceProblems, NoVulkanDriverSaysWhatToInstall) {
    // The Vulkan loader finds no driver when pointed at a missing ICD manifest.
    test::CliRun r = test::runCli("devices");
    ASSERT_EQ(r.exitCode, 0) << "the normal case must work first: " << r.err;
    setenv("VK_ICD_FILENAMES", "/nonexistent/vkmesh_no_driver.json", 1);
    setenv("VK_DRIVER_FILES", "/nonexistent/vkmesh_no_driver.json", 1);
    r = test::runCli("devices");
    unsetenv("VK_ICD_FILENAMES");
    unsetenv("VK_DRIVER_FILES");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_TRUE(contains(r.err, "mesa-vulkan-drivers")) << r.err;
}

TEST(DeviceProblems, MissingDeviceIndexIsExplained) {
    test::CliRun dev = test::runCli("devices");
    auto list = vk::Context::listDevices();
    ASSERT_FALSE(list.empty());
    try {
        vk::Context context(vk::ContextOptions{int(list.size()) + 3, false});
        FAIL() << "a device index past the end was accepted";
    } catch (const Error& e) {
        EXPECT_TRUE(contains(e.what(), "does not exist") && contains(e.what(), "vkmesh devices")) << e.what();
    }
    // `vkmesh devices` lists every device by name, with what it lacks when vkmesh cannot use it.
    EXPECT_TRUE(contains(dev.out, list.front().name)) << dev.out;
}

}  // namespace
}  // namespace vkmesh
