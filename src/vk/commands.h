// Recording and submitting work: one command buffer per frame, a fence to wait on, GPU timestamps
// around each stage, and the one kind of barrier the compute pipeline needs.
#pragma once

#include <vulkan/vulkan.h>

#include <string>
#include <utility>
#include <vector>

#include "vk/buffer.h"
#include "vk/context.h"

namespace vkmesh::vk {

// Everything a stage wrote (shader or transfer) becomes visible to every later shader, transfer and
// indirect-argument read. The pipeline's stages depend on each other in sequence, so a full
// compute/transfer barrier between them costs nothing that a finer one would save.
void memoryBarrier(VkCommandBuffer cmd);

// Semaphores a submission waits on (each at its stage) and signals: how vkmesh's frame work is ordered
// against an application's own submissions (see api/reconstructor.h).
struct SubmitSync {
    std::vector<VkSemaphore> wait;
    std::vector<VkPipelineStageFlags> waitStages;   // one per wait semaphore
    std::vector<VkSemaphore> signal;
};

// A command buffer that is recorded, submitted, and waited for, again and again.
class CommandRecorder {
public:
    explicit CommandRecorder(const Context& context);
    ~CommandRecorder();
    CommandRecorder(const CommandRecorder&) = delete;
    CommandRecorder& operator=(const CommandRecorder&) = delete;

    VkCommandBuffer begin();
    void submitAndWait(const SubmitSync& sync = {});

private:
    const Context& context_;
    VkCommandBuffer cmd_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
};

// Timestamps written between the stages of one command buffer; read after the fence.
class StageTimer {
public:
    StageTimer(const Context& context, uint32_t maxMarks = 32);
    ~StageTimer();
    StageTimer(const StageTimer&) = delete;
    StageTimer& operator=(const StageTimer&) = delete;

    void reset(VkCommandBuffer cmd);                     // at the start of the command buffer
    void mark(VkCommandBuffer cmd, const std::string& stageThatEnded);  // after a stage; first call = start
    // (stage name, milliseconds) of the last submission; empty when the device has no timestamps.
    std::vector<std::pair<std::string, double>> read() const;

private:
    const Context& context_;
    VkQueryPool pool_ = VK_NULL_HANDLE;
    uint32_t capacity_ = 0;
    std::vector<std::string> names_;
};

// Copies host data into any buffer (through a staging buffer when it is not mapped) and back.
void uploadToBuffer(const Context& context, const Buffer& dst, const void* data, VkDeviceSize size, VkDeviceSize offset = 0);
void downloadFromBuffer(const Context& context, const Buffer& src, void* data, VkDeviceSize size, VkDeviceSize offset = 0);

}  // namespace vkmesh::vk
