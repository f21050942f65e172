// `vkmesh fuse --track --loop-closure` (docs/LOOP_CLOSURE.md): what the fuse loop does with a loop closer.
// Relocalises lost frames, hands every fused frame to the loop closer, queues the poses an accepted loop moved
// for the map's correction (re-fused a budget per frame, the rest after the last frame), moves the tracker with
// the corrected current pose, and reports it all for --stats.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <vector>

#include "gpu/map_corrector.h"
#include "gpu/tracking/pose_tracker.h"
#include "slam/loop_closer.h"

namespace vkmesh::cli {

class FuseLoopClosure {
public:
    FuseLoopClosure(const slam::LoopClosureOptions& options, size_t correctionsPerFrame) : closer_(options), budget_(correctionsPerFrame) {}

    // Before frame `index` is tracked: up to the budget of queued corrections re-fused.
    void beforeFrame(gpu::GpuVolume& volume, gpu::MapCorrector& corrector);
    // A frame tracking lost: tracked again from the keyframes that look alike; the fusion when one worked.
    std::optional<gpu::TrackedFusion> relocalise(uint32_t index, gpu::GpuVolume& volume, gpu::PoseTracker& tracker, const DepthImage& depth,
                                                 const ColorImage* trackingColor, const ColorImage* fusedColor, const Intrinsics& intrinsics,
                                                 const Pose& predicted);
    // Frame `index` was fused at `pose` (and kept by `corrector`): a loop that closes queues its corrections.
    void frameFused(uint32_t index, const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics, const Pose& pose,
                    gpu::MapCorrector& corrector, gpu::PoseTracker& tracker);
    // After the last frame: every queued correction re-fused and the mesh published.
    void finish(gpu::GpuVolume& volume, gpu::MapCorrector& corrector);
    // The latest pose of a fused frame (false: not fused).
    bool latestPose(uint32_t index, Pose& pose) const { return closer_.latestPose(index, pose); }
    nlohmann::json stats() const;
    // Beside a saved map (api/loop_closure.h, loopClosurePathOf), so that a run continued with --load finds its places.
    void save(const std::filesystem::path& path, uint64_t mapId) const { closer_.save(path, mapId); }
    void load(const std::filesystem::path& path, uint64_t mapId) { closer_.load(path, mapId); }

private:
    slam::LoopCloser closer_;
    size_t budget_;
    gpu::CorrectionReport applied_;
    std::vector<nlohmann::json> relocalised_;   // per lost frame: relocalised or not, candidates tried
};

}  // namespace vkmesh::cli
