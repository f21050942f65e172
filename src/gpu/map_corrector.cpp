#include "gpu/map_corrector.h"

#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "io/trajectory.h"

namespace vkmesh::gpu {

std::filesystem::path frameStorePathOf(const std::filesystem::path& mapPath) {
    std::filesystem::path p = mapPath;
    return p.replace_extension(".vkframes");
}

double poseChange(const Pose& from, const Pose& to) {
    const Eigen::Matrix3d r = from.topLeftCorner<3, 3>().transpose() * to.topLeftCorner<3, 3>();
    // The angle from its sine and cosine (atan2): acos of the cosine alone loses all precision near 0, where
    // an unchanged pose would seem to have turned by 1e-8 rad.
    const double sine = 0.5 * Eigen::Vector3d(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1)).norm();
    const double cosine = 0.5 * (r.trace() - 1.0);
    return (to.topRightCorner<3, 1>() - from.topRightCorner<3, 1>()).norm() + std::atan2(sine, cosine);
}

MapCorrector::~MapCorrector() {
    {
        std::lock_guard lock(mutex_);
        stopping_ = true;
    }
    changed_.notify_all();
    if (worker_.joinable()) worker_.join();
}

void MapCorrector::keep(uint32_t index, double timestamp, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                        const DepthImage& depth, const ColorImage* color) {
    StoredFrame frame;
    frame.index = index;
    frame.timestamp = timestamp;
    frame.intrinsics = intrinsics;
    frame.pose = cameraToWorld;
    frame.depth = depth;
    if (color) frame.color = *color;
    {
        std::unique_lock lock(mutex_);
        changed_.wait(lock, [&] { return queued_.size() < kMaxQueued || failed_; });
        if (failed_) std::rethrow_exception(std::exchange(failed_, nullptr));
        queued_.push_back(std::move(frame));
    }
    changed_.notify_all();
    if (!worker_.joinable()) worker_ = std::thread([this] { compressQueued(); });
}

void MapCorrector::compressQueued() {
    std::unique_lock lock(mutex_);
    for (;;) {
        changed_.wait(lock, [&] { return stopping_ || !queued_.empty(); });
        if (stopping_) return;
        StoredFrame frame = std::move(queued_.front());
        queued_.pop_front();
        adding_ = true;
        lock.unlock();
        // store_ is the worker's alone while adding_ (settle() waits for it), so add() runs unlocked.
        std::exception_ptr error;
        try {
            store_.add(frame);
        } catch (...) {
            error = std::current_exception();
        }
        lock.lock();
        adding_ = false;
        if (error && !failed_) failed_ = error;
        changed_.notify_all();
    }
}

void MapCorrector::settle() const {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return (queued_.empty() && !adding_) || failed_; });
    if (failed_) std::rethrow_exception(std::exchange(failed_, nullptr));
}


void MapCorrector::correct(const std::vector<uint32_t>& frames, const std::vector<Pose>& poses) {
    settle();
    if (frames.size() != poses.size())
        throw Error("correct: " + std::to_string(frames.size()) + " frame indices but " + std::to_string(poses.size()) + " poses");
    for (size_t i = 0; i < frames.size(); ++i) {
        if (!store_.contains(frames[i]))
            throw Error("correct: frame " + std::to_string(frames[i]) + " is not in the frame store (" + std::to_string(store_.size()) +
                        " frames kept; a frame tracking lost was never fused)");
        validatePose(poses[i], "correct: the new pose of frame " + std::to_string(frames[i]));
    }
    for (size_t i = 0; i < frames.size(); ++i) {
        if (poseChange(store_.pose(frames[i]), poses[i]) < 1e-9) pending_.erase(frames[i]);
        else pending_[frames[i]] = poses[i];
    }
}

CorrectionReport MapCorrector::apply(GpuVolume& volume, size_t budget, Order order) {
    CorrectionReport report;
    if (pending_.empty() || budget == 0) return report;
    settle();
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::pair<double, uint32_t>> first;   // (key, frame), smallest key first
    for (const auto& [index, pose] : pending_)
        first.emplace_back(order == Order::Newest ? -double(index) : -poseChange(store_.pose(index), pose), index);
    std::sort(first.begin(), first.end());
    first.resize(std::min(first.size(), budget));
    for (const auto& [key, index] : first) {
        const Pose newPose = pending_.at(index);
        const StoredFrame frame = store_.get(index);
        FrameInput input = FrameInput::fromHost(frame.depth, frame.color.empty() ? nullptr : &frame.color, frame.intrinsics, frame.pose);
        input.intermediate = true;
        for (bool out : {true, false}) {
            input.deintegrate = out;
            input.cameraToWorld = out ? frame.pose : newPose;
            volume.submitFrame(input);
            const FrameReport r = volume.finishFrame();
            report.blocksFreed += r.counters.blocksFreed;
            report.observationsDropped += r.counters.observationsDropped;
            report.warnings.insert(report.warnings.end(), r.warnings.begin(), r.warnings.end());
        }
        store_.setPose(index, newPose);
        pending_.erase(index);
        report.frames.push_back(index);
        ++report.framesRefused;
    }
    if (report.observationsDropped > 0)
        report.warnings.push_back(std::to_string(report.observationsDropped) +
                                  " corner updates of the re-fused frames could not be applied exactly (a corner at its observation "
                                  "limit, or a map that does not hold what the frame store says it fused)");
    report.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return report;
}

}  // namespace vkmesh::gpu
