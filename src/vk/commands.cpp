#include "vk/commands.h"

#include <cstring>

#include "vk/check.h"

namespace vkmesh::vk {

void memoryBarrier(VkCommandBuffer cmd) {
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                            VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                         VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT |
                             VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_HOST_BIT,
                         0, 1, &barrier, 0, nullptr, 0, nullptr);
}

CommandRecorder::CommandRecorder(const Context& context) : context_(context) {
    VkCommandBufferAllocateInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    info.commandPool = context.commandPool();
    info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    info.commandBufferCount = 1;
    check(vkAllocateCommandBuffers(context.device(), &info, &cmd_), "vkAllocateCommandBuffers");
    VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check(vkCreateFence(context.device(), &fenceInfo, nullptr, &fence_), "vkCreateFence");
}

CommandRecorder::~CommandRecorder() {
    if (pending_) vkWaitForFences(context_.device(), 1, &fence_, VK_TRUE, UINT64_MAX);
    if (fence_) vkDestroyFence(context_.device(), fence_, nullptr);
    if (cmd_) vkFreeCommandBuffers(context_.device(), context_.commandPool(), 1, &cmd_);
}

VkCommandBuffer CommandRecorder::begin() {
    wait();
    check(vkResetCommandBuffer(cmd_, 0), "vkResetCommandBuffer");
    VkCommandBufferBeginInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    info.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(vkBeginCommandBuffer(cmd_, &info), "vkBeginCommandBuffer");
    return cmd_;
}

void CommandRecorder::submit(const SubmitSync& sync) {
    check(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer");
    if (sync.wait.size() != sync.waitStages.size())
        throw Error("SubmitSync: " + std::to_string(sync.wait.size()) + " wait semaphores but " +
                    std::to_string(sync.waitStages.size()) + " wait stages");
    if ((!sync.waitValues.empty() && sync.waitValues.size() != sync.wait.size()) ||
        (!sync.signalValues.empty() && sync.signalValues.size() != sync.signal.size()))
        throw Error("SubmitSync: timeline values must be given for every wait (signal) semaphore or for none");
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    VkTimelineSemaphoreSubmitInfo timeline{VK_STRUCTURE_TYPE_TIMELINE_SEMAPHORE_SUBMIT_INFO};
    if (!sync.waitValues.empty() || !sync.signalValues.empty()) {
        timeline.waitSemaphoreValueCount = uint32_t(sync.waitValues.size());
        timeline.pWaitSemaphoreValues = sync.waitValues.data();
        timeline.signalSemaphoreValueCount = uint32_t(sync.signalValues.size());
        timeline.pSignalSemaphoreValues = sync.signalValues.data();
        submit.pNext = &timeline;
    }
    submit.waitSemaphoreCount = uint32_t(sync.wait.size());
    submit.pWaitSemaphores = sync.wait.data();
    submit.pWaitDstStageMask = sync.waitStages.data();
    submit.signalSemaphoreCount = uint32_t(sync.signal.size());
    submit.pSignalSemaphores = sync.signal.data();
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd_;
    check(vkResetFences(context_.device(), 1, &fence_), "vkResetFences");
    check(vkQueueSubmit(context_.queue(), 1, &submit, fence_), "vkQueueSubmit");
    pending_ = true;
}

void CommandRecorder::wait() {
    if (!pending_) return;
    check(vkWaitForFences(context_.device(), 1, &fence_, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    pending_ = false;
}

TimelineSemaphore::TimelineSemaphore(const Context& context, uint64_t initialValue) : context_(context) {
    VkSemaphoreTypeCreateInfo type{VK_STRUCTURE_TYPE_SEMAPHORE_TYPE_CREATE_INFO};
    type.semaphoreType = VK_SEMAPHORE_TYPE_TIMELINE;
    type.initialValue = initialValue;
    VkSemaphoreCreateInfo info{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    info.pNext = &type;
    check(vkCreateSemaphore(context.device(), &info, nullptr, &semaphore_),
          "vkCreateSemaphore (timeline; the device needs the timelineSemaphore feature enabled)");
}

TimelineSemaphore::~TimelineSemaphore() {
    if (semaphore_) vkDestroySemaphore(context_.device(), semaphore_, nullptr);
}

uint64_t TimelineSemaphore::value() const {
    uint64_t v = 0;
    check(vkGetSemaphoreCounterValue(context_.device(), semaphore_, &v), "vkGetSemaphoreCounterValue");
    return v;
}

void TimelineSemaphore::wait(uint64_t value) const {
    VkSemaphoreWaitInfo info{VK_STRUCTURE_TYPE_SEMAPHORE_WAIT_INFO};
    info.semaphoreCount = 1;
    info.pSemaphores = &semaphore_;
    info.pValues = &value;
    check(vkWaitSemaphores(context_.device(), &info, UINT64_MAX), "vkWaitSemaphores");
}

StageTimer::StageTimer(const Context& context, uint32_t maxMarks) : context_(context), capacity_(maxMarks) {
    if (!context.timestampsSupported()) return;
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = capacity_;
    check(vkCreateQueryPool(context.device(), &info, nullptr, &pool_), "vkCreateQueryPool");
}

StageTimer::~StageTimer() {
    if (pool_) vkDestroyQueryPool(context_.device(), pool_, nullptr);
}

void StageTimer::reset(VkCommandBuffer cmd) {
    names_.clear();
    isPass_.clear();
    if (pool_ && enabled_) vkCmdResetQueryPool(cmd, pool_, 0, capacity_);
}

void StageTimer::mark(VkCommandBuffer cmd, const std::string& stageThatEnded) {
    if (!pool_ || !enabled_ || names_.size() >= capacity_) return;
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_, static_cast<uint32_t>(names_.size()));
    names_.push_back(stageThatEnded);
    isPass_.push_back(false);
}

void StageTimer::markPass(VkCommandBuffer cmd, const std::string& passThatEnded) {
    if (names_.empty()) return;   // before the first stage mark (the start) there is nothing to measure from
    const size_t before = names_.size();
    mark(cmd, passThatEnded);
    if (names_.size() > before) isPass_.back() = true;   // (nothing recorded when disabled or full)
}

std::vector<uint64_t> StageTimer::ticks() const {
    std::vector<uint64_t> ticks(names_.size());
    check(vkGetQueryPoolResults(context_.device(), pool_, 0, static_cast<uint32_t>(ticks.size()),
                                ticks.size() * sizeof(uint64_t), ticks.data(), sizeof(uint64_t),
                                VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
          "vkGetQueryPoolResults");
    return ticks;
}

std::vector<std::pair<std::string, double>> StageTimer::read() const {
    std::vector<std::pair<std::string, double>> out;
    if (!pool_ || names_.size() < 2) return out;
    const std::vector<uint64_t> t = ticks();
    size_t last = 0;   // the stage mark before
    for (size_t i = 1; i < t.size(); ++i) {
        if (isPass_[i]) continue;
        out.emplace_back(names_[i], double(t[i] - t[last]) * context_.timestampPeriodNs() * 1e-6);
        last = i;
    }
    return out;
}

std::vector<std::pair<std::string, double>> StageTimer::readPasses() const {
    std::vector<std::pair<std::string, double>> out;
    if (!pool_ || names_.size() < 2) return out;
    const std::vector<uint64_t> t = ticks();
    for (size_t i = 1; i < t.size(); ++i)
        if (isPass_[i]) out.emplace_back(names_[i], double(t[i] - t[i - 1]) * context_.timestampPeriodNs() * 1e-6);
    return out;
}

void uploadToBuffer(const Context& context, const Buffer& dst, const void* data, VkDeviceSize size, VkDeviceSize offset) {
    if (offset + size > dst.size()) throw Error("upload past the end of buffer '" + dst.name() + "'");
    if (dst.mapped()) {
        std::memcpy(static_cast<char*>(dst.mapped()) + offset, data, size);
        return;
    }
    Buffer staging(context, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::Upload, dst.name() + " (staging)");
    std::memcpy(staging.mapped(), data, size);
    CommandRecorder recorder(context);
    VkCommandBuffer cmd = recorder.begin();
    VkBufferCopy region{0, offset, size};
    vkCmdCopyBuffer(cmd, staging.handle(), dst.handle(), 1, &region);
    memoryBarrier(cmd);
    recorder.submitAndWait();
}

void downloadFromBuffer(const Context& context, const Buffer& src, void* data, VkDeviceSize size, VkDeviceSize offset) {
    if (offset + size > src.size()) throw Error("download past the end of buffer '" + src.name() + "'");
    Buffer staging(context, size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::Readback, src.name() + " (readback)");
    CommandRecorder recorder(context);
    VkCommandBuffer cmd = recorder.begin();
    memoryBarrier(cmd);
    VkBufferCopy region{offset, 0, size};
    vkCmdCopyBuffer(cmd, src.handle(), staging.handle(), 1, &region);
    memoryBarrier(cmd);
    recorder.submitAndWait();
    staging.invalidate();
    std::memcpy(data, staging.mapped(), size);
}

}  // namespace vkmesh::vk
