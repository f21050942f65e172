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
    // Values for timeline semaphores, one per entry of `wait` / `signal` (ignored for a binary semaphore
    // among them); empty when all are binary.
    std::vector<uint64_t> waitValues;
    std::vector<uint64_t> signalValues;
};

// A timeline semaphore (Vulkan 1.2 core; the device must have enabled the timelineSemaphore feature, which
// Context::enableRequiredFeatures does): a counter the GPU raises as submissions finish, that the host or
// another submission waits on for a given value.
class TimelineSemaphore {
public:
    explicit TimelineSemaphore(const Context& context, uint64_t initialValue = 0);
    ~TimelineSemaphore();
    TimelineSemaphore(const TimelineSemaphore&) = delete;
    TimelineSemaphore& operator=(const TimelineSemaphore&) = delete;

    VkSemaphore handle() const { return semaphore_; }
    uint64_t value() const;           // what the GPU has reached
    void wait(uint64_t value) const;  // on the host, until the GPU reaches `value`

private:
    const Context& context_;
    VkSemaphore semaphore_ = VK_NULL_HANDLE;
};

// A command buffer that is recorded, submitted, and waited for, again and again. begin() waits for the
// last submission first (the command buffer cannot be re-recorded while the GPU runs it).
class CommandRecorder {
public:
    explicit CommandRecorder(const Context& context);
    ~CommandRecorder();
    CommandRecorder(const CommandRecorder&) = delete;
    CommandRecorder& operator=(const CommandRecorder&) = delete;

    VkCommandBuffer begin();
    void submit(const SubmitSync& sync = {});   // returns at once; wait() before reading what it wrote
    void wait();                               // for the last submission; no-op when none is pending
    bool pending() const { return pending_; }
    void submitAndWait(const SubmitSync& sync = {}) {
        submit(sync);
        wait();
    }

private:
    const Context& context_;
    VkCommandBuffer cmd_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    bool pending_ = false;
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
    // After one pass (a dispatch) inside a stage: read() does not see it (a stage still spans from the stage mark
    // before it), readPasses() gives its time since the mark before it, whichever kind.
    void markPass(VkCommandBuffer cmd, const std::string& passThatEnded);
    // Off: reset and mark record nothing and read() is empty (a timestamp costs ~50 µs on lavapipe).
    void setEnabled(bool enabled) { enabled_ = enabled; }
    // (stage name, milliseconds) of the last submission; empty when the device has no timestamps.
    std::vector<std::pair<std::string, double>> read() const;
    // (pass name, milliseconds) of the last submission's markPass() calls, in order (a pass may repeat).
    std::vector<std::pair<std::string, double>> readPasses() const;

private:
    const Context& context_;
    VkQueryPool pool_ = VK_NULL_HANDLE;
    uint32_t capacity_ = 0;
    bool enabled_ = true;
    std::vector<std::string> names_;
    std::vector<bool> isPass_;   // per mark: markPass() rather than mark()
    std::vector<uint64_t> ticks() const;
};

// Copies host data into any buffer (through a staging buffer when it is not mapped) and back.
void uploadToBuffer(const Context& context, const Buffer& dst, const void* data, VkDeviceSize size, VkDeviceSize offset = 0);
void downloadFromBuffer(const Context& context, const Buffer& src, void* data, VkDeviceSize size, VkDeviceSize offset = 0);

}  // namespace vkmesh::vk
