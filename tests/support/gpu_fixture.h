// One Vulkan context per test program, with the Khronos validation layer on: every test fails if the
// layer reported anything while it ran.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "gpu/gpu_volume.h"
#include "vk/buffer.h"
#include "vk/commands.h"
#include "vk/context.h"

namespace vkmesh::test {

class GpuTest : public ::testing::Test {
protected:
    static vk::Context& context() {
        static std::unique_ptr<vk::Context> ctx = std::make_unique<vk::Context>(vk::ContextOptions{-1, true});
        return *ctx;
    }
    void SetUp() override { context().takeValidationMessages(); }
    void TearDown() override {
        auto messages = context().takeValidationMessages();
        EXPECT_TRUE(messages.empty()) << messages.size() << " validation messages, first: " << messages.front();
    }
};

// Reads `size` bytes at `offset` of a device buffer the way an application could: after the barrier an
// application records before reading vkmesh's mesh buffers, a copy on the device into a host-visible buffer.
inline std::vector<uint8_t> readDeviceBuffer(const vk::Context& context, VkBuffer buffer, VkDeviceSize offset, VkDeviceSize size) {
    std::vector<uint8_t> out(size_t(size), 0);
    if (size == 0) return out;
    vk::Buffer host(context, size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::Readback, "test readback");
    vk::CommandRecorder recorder(context);
    VkCommandBuffer cmd = recorder.begin();
    gpu::recordMeshReadBarrier(cmd);
    VkMemoryBarrier toTransfer{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    toTransfer.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    toTransfer.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &toTransfer, 0, nullptr, 0, nullptr);
    VkBufferCopy region{offset, 0, size};
    vkCmdCopyBuffer(cmd, buffer, host.handle(), 1, &region);
    VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    toHost.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &toHost, 0, nullptr, 0, nullptr);
    recorder.submitAndWait();
    host.invalidate();
    std::memcpy(out.data(), host.mapped(), out.size());
    return out;
}

}  // namespace vkmesh::test
