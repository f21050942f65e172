#include "api/reconstructor.h"

#include <algorithm>

namespace vkmesh {

namespace {
ReconstructorOptions checked(ReconstructorOptions options) {
    if (options.volume.meshMode != gpu::MeshMode::Incremental)
        throw Error("Reconstructor keeps the incremental mesh: options.volume.meshMode must be Incremental");
    options.volume.publishMesh = true;
    options.volume.trackDeltas = options.trackDeltas;
    if (options.loopClosure && !options.keepFrames)
        throw Error("loop closure re-fuses the frames a loop moves: it needs keepFrames (Python keep_frames=True)");
    return options;
}

gpu::FrameInput gpuFrameInput(const gpu::GpuImageInput& depth, const gpu::GpuImageInput& color, const Intrinsics& intrinsics,
                              const Pose& cameraToWorld, const vk::SubmitSync& sync) {
    gpu::FrameInput input;
    input.gpuDepth = depth;
    input.gpuColor = color;
    input.intrinsics = intrinsics;
    input.cameraToWorld = cameraToWorld;
    input.sync = sync;
    return input;
}
}  // namespace

Reconstructor::Reconstructor(const ReconstructorOptions& options)
    : context_(std::make_unique<vk::Context>(options.device)), options_(checked(options)) {
    if (options_.keepFrames) corrector_.emplace(FrameStore(options_.frameStore));
}

Reconstructor::Reconstructor(const vk::ExternalDevice& device, const ReconstructorOptions& options)
    : context_(std::make_unique<vk::Context>(device)), options_(checked(options)) {
    if (options_.keepFrames) corrector_.emplace(FrameStore(options_.frameStore));
}

// The volume (its buffers) goes before the context (its command pool, and the device when owned); a frame
// still in flight is waited for by the volume's command recorder.
Reconstructor::~Reconstructor() {
    tracker_.reset();
    volume_.reset();
}

gpu::FrameReport Reconstructor::integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                          const vk::SubmitSync& sync) {
    return integrate(depth, nullptr, intrinsics, cameraToWorld, sync);
}

void Reconstructor::createVolume(int width, int height) {
    if (volume_) return;
    if (width <= 0 || height <= 0) throw Error("the first depth image is empty");
    gpu::GpuVolumeConfig config = options_.volume;
    config.imageWidth = width;
    config.imageHeight = height;
    volume_ = std::make_unique<gpu::GpuVolume>(*context_, config);
}

void Reconstructor::given(const Pose& cameraToWorld) {
    trajectory_.push_back(cameraToWorld);
    if (tracker_) tracker_->start(cameraToWorld);
}

gpu::FrameReport Reconstructor::integrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                          const Pose& cameraToWorld, const vk::SubmitSync& sync) {
    finish();   // an asynchronous frame before this one
    createVolume(depth.width, depth.height);
    applyCorrections(options_.correctionsPerFrame);
    gpu::FrameReport report = volume_->integrate(depth, color, intrinsics, cameraToWorld, sync);
    lastDelta_ = report.delta;
    keepFrame(depth, color, intrinsics, cameraToWorld);
    given(cameraToWorld);
    return report;
}

void Reconstructor::keepFrame(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics, const Pose& cameraToWorld) {
    if (!corrector_) return;
    const uint32_t index = firstFrameIndex_ + uint32_t(trajectory_.size());
    // What fusion used: colour only when the volume fuses it.
    corrector_->keep(index, double(index), intrinsics, cameraToWorld, depth, volume_->fusesColor() ? color : nullptr);
}

void Reconstructor::applyCorrections(size_t budget) {
    lastCorrections_ = {};
    if (!corrector_ || corrector_->pending() == 0) return;
    lastCorrections_ = corrector_->apply(*volume_, budget);
    for (uint32_t index : lastCorrections_.frames)
        if (index >= firstFrameIndex_ && index - firstFrameIndex_ < trajectory_.size())
            trajectory_[index - firstFrameIndex_] = corrector_->store().pose(index);
}

void Reconstructor::correct(const std::vector<uint32_t>& frames, const std::vector<Pose>& poses) {
    if (!corrector_)
        throw Error("correct: this Reconstructor keeps no frames (ReconstructorOptions::keepFrames, Python keep_frames=True), "
                    "so it cannot take a fused frame out again");
    corrector_->correct(frames, poses);
}

size_t Reconstructor::pendingCorrections() const { return corrector_ ? corrector_->pending() : 0; }

gpu::CorrectionReport Reconstructor::finishCorrections() {
    finish();
    if (!volume_ || pendingCorrections() == 0) {
        lastCorrections_ = {};
        return lastCorrections_;
    }
    applyCorrections(corrector_->pending());
    lastDelta_ = volume_->publishMesh().delta;
    return lastCorrections_;
}

std::filesystem::path Reconstructor::frameStorePath(const std::filesystem::path& mapPath) { return gpu::frameStorePathOf(mapPath); }

TrackedFrame Reconstructor::integrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                      const vk::SubmitSync& sync) {
    finish();
    createVolume(depth.width, depth.height);
    if (!tracker_) {
        tracker_ = std::make_unique<gpu::PoseTracker>(*context_, options_.tracker);
        tracker_->start(trajectory_.empty() ? Pose::Identity() : trajectory_.back());
    }
    TrackedFrame out;
    const uint32_t index = firstFrameIndex_ + uint32_t(trajectory_.size());
    LoopClosure* loops = options_.loopClosure.get();
    if (volume_->framesIntegrated() == 0) {
        // Nothing fused yet (a new reconstruction): the frame starts the map where the tracker stands.
        out.tracking = tracker_->start(tracker_->prediction());
        out.fused = volume_->integrate(depth, color, intrinsics, out.tracking.cameraToWorld, sync);
    } else {
        applyCorrections(options_.correctionsPerFrame);
        gpu::TrackedFusion f = tracker_->trackAndFuse(*volume_, depth, intrinsics, color, color, sync);
        if (!f.tracking.tracked && loops) {
            // Relocalisation: tracked again from the poses of the keyframes that look like this frame.
            const Pose predicted = f.tracking.cameraToWorld;
            for (const Pose& candidate : loops->relocalisationCandidates({index, &depth, color, intrinsics, predicted})) {
                ++out.relocalisationCandidatesTried;
                gpu::TrackedFusion g = tracker_->relocalise(*volume_, candidate, depth, intrinsics, color, color);
                if (g.tracking.tracked) {
                    f = std::move(g);
                    out.relocalised = true;
                    break;
                }
            }
            loops->relocalisationResult(index, out.relocalised, out.relocalisationCandidatesTried);
            if (!out.relocalised) f.tracking.cameraToWorld = predicted;
        }
        out.tracking = std::move(f.tracking);
        out.fused = std::move(f.fused);
    }
    out.cameraToWorld = out.tracking.cameraToWorld;
    if (out.fused) keepFrame(depth, color, intrinsics, out.cameraToWorld);
    trajectory_.push_back(out.cameraToWorld);
    lastDelta_ = out.fused ? out.fused->delta : MeshDelta{};
    if (out.fused && loops) {
        const PoseCorrections moved = loops->frameFused({index, &depth, color, intrinsics, out.cameraToWorld});
        if (!moved.empty()) {
            corrector_->correct(moved.frames, moved.poses);
            out.loopCorrections = uint32_t(moved.frames.size());
            // Tracking goes on from this frame's corrected pose (the next frame is predicted in the corrected map).
            if (Pose corrected; loops->latestPose(index, corrected)) tracker_->correctLastPose(corrected);
        }
    }
    return out;
}

gpu::FrameReport Reconstructor::integrate(const gpu::GpuImageInput& depth, const gpu::GpuImageInput& color,
                                          const Intrinsics& intrinsics, const Pose& cameraToWorld, const vk::SubmitSync& sync) {
    finish();
    createVolume(intrinsics.width, intrinsics.height);   // a GPU image's size is the intrinsics'
    if (corrector_)
        throw Error("a Reconstructor that keeps frames (keepFrames) takes host images: a GPU image cannot be kept for correct()");
    volume_->submitFrame(gpuFrameInput(depth, color, intrinsics, cameraToWorld, sync));
    gpu::FrameReport report = volume_->finishFrame();
    lastDelta_ = report.delta;
    given(cameraToWorld);
    return report;
}

std::optional<gpu::FrameReport> Reconstructor::finish() {
    if (!volume_ || !volume_->framePending()) return std::nullopt;
    gpu::FrameReport report = volume_->finishFrame();
    lastDelta_ = report.delta;
    return report;
}

Reconstructor::AsyncFrame Reconstructor::submitAsync(const gpu::FrameInput& input) {
    AsyncFrame out;
    out.previous = finish();
    volume_->submitFrame(input, ++nextReadyValue_);
    out.frame = volume_->framesIntegrated() + 1;
    out.ready = volume_->timeline().handle();
    out.readyValue = nextReadyValue_;
    out.mesh = volume_->meshBuffers();
    return out;
}

Reconstructor::AsyncFrame Reconstructor::integrateAsync(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                                        const Pose& cameraToWorld, const vk::SubmitSync& sync) {
    createVolume(depth.width, depth.height);
    gpu::FrameInput input = gpu::FrameInput::fromHost(depth, color, intrinsics, cameraToWorld);
    input.sync = sync;
    AsyncFrame out = submitAsync(input);   // checks the input first
    keepFrame(depth, color, intrinsics, cameraToWorld);
    given(cameraToWorld);
    return out;
}

Reconstructor::AsyncFrame Reconstructor::integrateAsync(const gpu::GpuImageInput& depth, const gpu::GpuImageInput& color,
                                                        const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                                        const vk::SubmitSync& sync) {
    createVolume(intrinsics.width, intrinsics.height);
    if (corrector_) throw Error("a Reconstructor that keeps frames (keepFrames) takes host images: a GPU image cannot be kept for correct()");
    given(cameraToWorld);
    return submitAsync(gpuFrameInput(depth, color, intrinsics, cameraToWorld, sync));
}

gpu::MeshBuffers Reconstructor::meshBuffers() const { return volume_ ? volume_->meshBuffers() : gpu::MeshBuffers{}; }

gpu::ExportedMesh Reconstructor::downloadMesh() {
    finish();
    return volume_ ? volume_->exportMesh() : gpu::ExportedMesh{};
}

void Reconstructor::save(const std::filesystem::path& path) {
    finish();
    if (!volume_) throw Error("cannot save " + path.string() + ": no frame has been integrated yet");
    // With loop closure, the loops' corrections are re-fused first: the loop closer's state holds them as done.
    if (options_.loopClosure && corrector_ && corrector_->pending() > 0) finishCorrections();
    const uint64_t saveId = volume_->save(path);
    // Queued corrections are not saved: the store holds the poses the map was fused at.
    if (corrector_) corrector_->store().save(frameStorePath(path).string(), saveId);
    if (options_.loopClosure) options_.loopClosure->save(loopClosurePathOf(path), saveId);
}

void Reconstructor::loadMap(const map::MapData& m, const std::filesystem::path& path) {
    gpu::GpuVolumeConfig config = gpu::GpuVolume::mapConfig(m);
    const gpu::GpuVolumeConfig& want = options_.volume;
    config.blockCapacity = want.blockCapacity;   // GpuVolume::load takes the larger of these and the map's
    config.hashCapacity = want.hashCapacity;
    config.vertexCapacity = want.vertexCapacity;
    config.chunkCapacity = want.chunkCapacity;
    config.retypeCapacity = want.retypeCapacity;
    config.publishMesh = true;
    config.trackDeltas = options_.trackDeltas;
    volume_ = gpu::GpuVolume::load(*context_, m, config, path.string());
    firstFrameIndex_ = m.framesIntegrated;
    // The loop closer's keyframes and graph saved with the map (absent: it starts empty).
    if (options_.loopClosure && std::filesystem::exists(loopClosurePathOf(path))) options_.loopClosure->load(loopClosurePathOf(path), m.saveId);
    if (!corrector_) return;
    const std::filesystem::path storePath = frameStorePath(path);
    if (!std::filesystem::exists(storePath))
        throw Error("keepFrames: the map " + path.string() + " has no frame store beside it (" + storePath.string() +
                    "); it was saved without kept frames, so its frames cannot be corrected");
    corrector_.emplace(FrameStore::load(storePath.string(), m.saveId, options_.frameStore));
    const std::vector<uint32_t> kept = corrector_->store().indices();
    if (!kept.empty()) firstFrameIndex_ = std::max(firstFrameIndex_, kept.back() + 1);
}

std::unique_ptr<Reconstructor> Reconstructor::load(const std::filesystem::path& path, const ReconstructorOptions& options) {
    const map::MapData m = map::readFile(path);   // parsed and checked before a device is created
    auto r = std::make_unique<Reconstructor>(options);
    r->loadMap(m, path);
    return r;
}

std::unique_ptr<Reconstructor> Reconstructor::load(const std::filesystem::path& path, const vk::ExternalDevice& device,
                                                   const ReconstructorOptions& options) {
    const map::MapData m = map::readFile(path);
    auto r = std::make_unique<Reconstructor>(device, options);
    r->loadMap(m, path);
    return r;
}

uint32_t Reconstructor::framesIntegrated() const {
    return volume_ ? volume_->framesIntegrated() + (volume_->framePending() ? 1 : 0) : 0;
}

}  // namespace vkmesh
