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
    createMapper();
}

Reconstructor::Reconstructor(const vk::ExternalDevice& device, const ReconstructorOptions& options)
    : context_(std::make_unique<vk::Context>(device)), options_(checked(options)) {
    createMapper();
}

// The Mapper (its volume's buffers, the tracker) goes before the context (its command pool, and the device when
// owned); a frame still in flight is waited for by the volume's command recorder.
Reconstructor::~Reconstructor() { mapper_.reset(); }

void Reconstructor::createMapper() {
    MapperOptions m;
    m.volume = options_.volume;
    m.tracker = options_.tracker;
    m.correctionsPerFrame = options_.correctionsPerFrame;
    m.loopClosure = options_.loopClosure;
    mapper_ = std::make_unique<Mapper>(*context_, m);
    if (options_.keepFrames) mapper_->keepFrames(FrameStore(options_.frameStore));
}

MapperFrame Reconstructor::frameOf(const DepthImage* depth, const ColorImage* color, const Intrinsics& intrinsics,
                                   const vk::SubmitSync& sync) const {
    MapperFrame frame;
    frame.index = nextIndex();
    frame.timestamp = double(frame.index);
    frame.depth = depth;
    frame.color = color;
    frame.intrinsics = intrinsics;
    frame.source = "frame " + std::to_string(frame.index) + "'s depth image";
    frame.sync = sync;
    return frame;
}

gpu::FrameReport Reconstructor::integrate(const DepthImage& depth, const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                          const vk::SubmitSync& sync) {
    return integrate(depth, nullptr, intrinsics, cameraToWorld, sync);
}

gpu::FrameReport Reconstructor::integrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                          const Pose& cameraToWorld, const vk::SubmitSync& sync) {
    finish();   // an asynchronous frame before this one
    MapperFrame frame = frameOf(&depth, color, intrinsics, sync);
    frame.pose = cameraToWorld;
    MapperResult result = mapper_->process(frame);
    lastCorrections_ = std::move(result.corrections);
    gpu::FrameReport report;
    if (result.fused) report = std::move(*result.fused);
    else report.warnings = result.warnings;   // skipped: why
    lastDelta_ = report.delta;
    return report;
}

void Reconstructor::correct(const std::vector<uint32_t>& frames, const std::vector<Pose>& poses) {
    if (!mapper_->frameStore())
        throw Error("correct: this Reconstructor keeps no frames (ReconstructorOptions::keepFrames, Python keep_frames=True), "
                    "so it cannot take a fused frame out again");
    mapper_->correct(frames, poses);
}

size_t Reconstructor::pendingCorrections() const { return mapper_->pendingCorrections(); }

gpu::CorrectionReport Reconstructor::finishCorrections() {
    finish();
    lastCorrections_ = {};
    if (std::optional<gpu::FrameReport> published = mapper_->finishCorrections(&lastCorrections_)) lastDelta_ = published->delta;
    return lastCorrections_;
}

std::filesystem::path Reconstructor::frameStorePath(const std::filesystem::path& mapPath) { return gpu::frameStorePathOf(mapPath); }

TrackedFrame Reconstructor::integrate(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                      const vk::SubmitSync& sync) {
    finish();
    MapperResult result = mapper_->process(frameOf(&depth, color, intrinsics, sync));
    lastCorrections_ = std::move(result.corrections);
    TrackedFrame out;
    out.cameraToWorld = result.cameraToWorld;
    if (result.tracking) {
        out.tracking = std::move(*result.tracking);
    } else {   // skipped before tracking had a pose: why
        out.tracking.cameraToWorld = result.cameraToWorld;
        out.tracking.lostReason = result.warnings.empty() ? std::string("skipped") : result.warnings.front();
    }
    out.fused = std::move(result.fused);
    out.relocalised = result.relocalised;
    out.relocalisationCandidatesTried = result.relocalisationCandidatesTried;
    out.loopCorrections = result.loopCorrections;
    lastDelta_ = out.fused ? out.fused->delta : MeshDelta{};
    return out;
}

gpu::FrameReport Reconstructor::integrate(const gpu::GpuImageInput& depth, const gpu::GpuImageInput& color,
                                          const Intrinsics& intrinsics, const Pose& cameraToWorld, const vk::SubmitSync& sync) {
    finish();
    mapper_->createVolume(intrinsics.width, intrinsics.height);   // a GPU image's size is the intrinsics'
    if (mapper_->frameStore())
        throw Error("a Reconstructor that keeps frames (keepFrames) takes host images: a GPU image cannot be kept for correct()");
    mapper_->volume().submitFrame(gpuFrameInput(depth, color, intrinsics, cameraToWorld, sync));
    gpu::FrameReport report = mapper_->volume().finishFrame();
    lastDelta_ = report.delta;
    MapperFrame frame = frameOf(nullptr, nullptr, intrinsics, sync);
    frame.pose = cameraToWorld;
    mapper_->recordGiven(frame);
    return report;
}

std::optional<gpu::FrameReport> Reconstructor::finish() {
    gpu::GpuVolume* volume = mapper_->volumePtr();
    if (!volume || !volume->framePending()) return std::nullopt;
    gpu::FrameReport report = volume->finishFrame();
    lastDelta_ = report.delta;
    return report;
}

Reconstructor::AsyncFrame Reconstructor::submitAsync(const gpu::FrameInput& input) {
    AsyncFrame out;
    out.previous = finish();
    gpu::GpuVolume& volume = mapper_->volume();
    volume.submitFrame(input, ++nextReadyValue_);
    out.frame = volume.framesIntegrated() + 1;
    out.ready = volume.timeline().handle();
    out.readyValue = nextReadyValue_;
    out.mesh = volume.meshBuffers();
    return out;
}

Reconstructor::AsyncFrame Reconstructor::integrateAsync(const DepthImage& depth, const ColorImage* color, const Intrinsics& intrinsics,
                                                        const Pose& cameraToWorld, const vk::SubmitSync& sync) {
    mapper_->createVolume(depth.width, depth.height);
    gpu::FrameInput input = gpu::FrameInput::fromHost(depth, color, intrinsics, cameraToWorld);
    input.sync = sync;
    AsyncFrame out = submitAsync(input);   // checks the input first
    MapperFrame frame = frameOf(&depth, color, intrinsics, sync);
    frame.pose = cameraToWorld;
    mapper_->recordGiven(frame);   // kept for later corrections (keepFrames)
    return out;
}

Reconstructor::AsyncFrame Reconstructor::integrateAsync(const gpu::GpuImageInput& depth, const gpu::GpuImageInput& color,
                                                        const Intrinsics& intrinsics, const Pose& cameraToWorld,
                                                        const vk::SubmitSync& sync) {
    mapper_->createVolume(intrinsics.width, intrinsics.height);
    if (mapper_->frameStore()) throw Error("a Reconstructor that keeps frames (keepFrames) takes host images: a GPU image cannot be kept for correct()");
    MapperFrame frame = frameOf(nullptr, nullptr, intrinsics, sync);
    frame.pose = cameraToWorld;
    mapper_->recordGiven(frame);
    return submitAsync(gpuFrameInput(depth, color, intrinsics, cameraToWorld, sync));
}

gpu::MeshBuffers Reconstructor::meshBuffers() const { return volume() ? volume()->meshBuffers() : gpu::MeshBuffers{}; }

gpu::ExportedMesh Reconstructor::downloadMesh() {
    finish();
    return volume() ? volume()->exportMesh() : gpu::ExportedMesh{};
}

void Reconstructor::save(const std::filesystem::path& path) {
    finish();
    if (!volume()) throw Error("cannot save " + path.string() + ": no frame has been integrated yet");
    // With loop closure, the loops' corrections are re-fused first: the loop closer's state holds them as done.
    if (options_.loopClosure && pendingCorrections() > 0) finishCorrections();
    mapper_->save(path);
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
    mapper_->loadMap(m, config, path);   // and the loop closer's keyframes and graph saved beside it
    firstFrameIndex_ = m.framesIntegrated;
    if (!options_.keepFrames) return;
    const std::filesystem::path storePath = frameStorePath(path);
    if (!std::filesystem::exists(storePath))
        throw Error("keepFrames: the map " + path.string() + " has no frame store beside it (" + storePath.string() +
                    "); it was saved without kept frames, so its frames cannot be corrected");
    mapper_->keepFrames(FrameStore::load(storePath.string(), m.saveId, options_.frameStore));
    const std::vector<uint32_t> kept = mapper_->frameStore()->indices();
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
    const gpu::GpuVolume* v = volume();
    return v ? v->framesIntegrated() + (v->framePending() ? 1 : 0) : 0;
}

}  // namespace vkmesh
