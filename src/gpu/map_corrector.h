// Component: the map corrector (docs/CORRECTION.md). Keeps what every fused frame fused (a FrameStore: depth,
// colour, the pose it was fused at) and re-fuses the frames whose poses changed: each is de-integrated at its
// old pose (exactly: shared_layout.h "A TSDF corner") and integrated at its new one, largest pose change first,
// a budget of frames per call, so that a live run keeps its frame rate while the map converges. The volume's
// incremental mesh follows through its usual passes, and its deltas report every change.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/frame_store.h"
#include "core/types.h"
#include "gpu/gpu_volume.h"

namespace vkmesh::gpu {

// What applying corrections did.
struct CorrectionReport {
    uint32_t framesRefused = 0;        // frames de-integrated at their old pose and integrated at the new one
    uint32_t blocksFreed = 0;          // blocks left with no observation, freed with their mesh
    uint32_t observationsDropped = 0;  // corner updates that could not be applied exactly (0 for a consistent map)
    double milliseconds = 0;           // wall time
    std::vector<uint32_t> frames;      // the frames re-fused, in the order they were
    std::vector<std::string> warnings; // capacity problems of the re-fusion frames, dropped observations
};

// How far a pose moved, for ranking corrections: the translation in metres plus the geodesic rotation angle
// in radians (a point 1 m in front of the camera moves about that far). A geodesic angle, not Euler angles,
// which wrap near +-pi (../shared/docs/global-consistency.md).
double poseChange(const Pose& from, const Pose& to);

// Where a map's frame store is saved: beside the map, with the extension .vkframes (map.vkmap -> map.vkframes).
std::filesystem::path frameStorePathOf(const std::filesystem::path& mapPath);

// Keeping a frame costs its compression (zstd: about 20 ms of a CPU core for a 640 x 480 frame with colour), so
// keep() only copies the frame and a worker thread of the corrector compresses it into the store while the caller
// goes on with its next frame (beside the GPU's work). Whatever reads the store (correct, apply, store()) first
// waits for the frames kept before it, so it sees every one of them; an error of the store's add() (e.g. past its
// budget without a spill folder) is thrown by the next call. One caller thread at a time, as before.
class MapCorrector {
public:
    explicit MapCorrector(FrameStore store) : store_(std::move(store)) {}
    ~MapCorrector();   // frames still queued are dropped with the store
    MapCorrector(const MapCorrector&) = delete;
    MapCorrector& operator=(const MapCorrector&) = delete;

    // Records a frame just fused at `cameraToWorld` (its index: the position in the caller's sequence): copied now,
    // compressed into the store by the worker. Waits while kMaxQueued frames are still being compressed.
    void keep(uint32_t index, double timestamp, const Intrinsics& intrinsics, const Pose& cameraToWorld, const DepthImage& depth,
              const ColorImage* color);
    static constexpr size_t kMaxQueued = 4;

    // Queues new poses for frames already kept (a later pose for the same frame replaces a queued one). Every
    // pose is checked first: an unknown frame, a non-finite or non-rigid pose throws Error naming it, and then
    // nothing is queued (validatePose's rules, io/trajectory.h). A frame whose pose did not move (poseChange
    // below 1e-9) is not queued.
    void correct(const std::vector<uint32_t>& frames, const std::vector<Pose>& poses);
    size_t pending() const { return pending_.size(); }

    // Which queued frames apply() re-fuses first: those whose pose changed most (they put the most surface in the
    // wrong place), or the newest (the surface a moving camera sees next: after a loop closed).
    enum class Order { LargestChange, Newest };
    // Re-fuses up to `budget` queued frames into `volume` (in `order`) as intermediate frames: the caller's next
    // frame, or GpuVolume::publishMesh(), exports the mesh and takes the deltas.
    CorrectionReport apply(GpuVolume& volume, size_t budget, Order order = Order::LargestChange);

    // Every frame kept so far is in it (the call waits for the worker).
    const FrameStore& store() const {
        settle();
        return store_;
    }
    FrameStore& store() {
        settle();
        return store_;
    }

private:
    void compressQueued();   // the worker thread: adds the queued frames to store_ in order
    void settle() const;     // waits until the queue is empty and the worker idle; rethrows the worker's error

    FrameStore store_;
    std::map<uint32_t, Pose> pending_;
    mutable std::mutex mutex_;                  // guards the members below it
    mutable std::condition_variable changed_;   // a frame queued or added, or the worker told to stop
    std::deque<StoredFrame> queued_;
    bool adding_ = false, stopping_ = false;    // the worker holds a frame popped from queued_; it is to stop
    mutable std::exception_ptr failed_;         // store_.add()'s error on the worker, thrown by the next call
    std::thread worker_;                        // started by the first keep()
};

}  // namespace vkmesh::gpu
