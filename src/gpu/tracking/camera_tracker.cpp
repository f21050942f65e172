#include "gpu/tracking/camera_tracker.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>

#include "core/camera.h"

namespace vkmesh::gpu {
namespace {

constexpr VkBufferUsageFlags kStorage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
// The per-pixel maps the ICP pass reads as texel buffers too.
constexpr VkBufferUsageFlags kMap = kStorage | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT;

uint32_t levelWidth(int width, int level) { return uint32_t(width) >> level; }
uint32_t levelHeight(int height, int level) { return uint32_t(height) >> level; }
uint32_t groupsFor(uint32_t n, uint32_t size) { return (n + size - 1) / size; }
// Pixels per invocation of track_icp_reduce (TrackParamsGpu::pixelsPerInvocation): a CPU device pays per
// workgroup, a GPU wants many of them.
uint32_t pixelsPerInvocationFor(const vk::Context& context, const TrackerOptions& options) {
    if (options.pixelsPerInvocation > TRACK_MAX_PIXELS_PER_INVOCATION)
        throw Error("tracking: " + std::to_string(options.pixelsPerInvocation) + " pixels per invocation is above " +
                    std::to_string(TRACK_MAX_PIXELS_PER_INVOCATION));
    if (options.pixelsPerInvocation > 0) return options.pixelsPerInvocation;
    return context.info().type == "CPU" ? TRACK_MAX_PIXELS_PER_INVOCATION : 16u;
}

}  // namespace

// The options with the iterations resolved for frames `width` pixels wide.
static TrackerOptions withIterations(TrackerOptions options, int width) {
    options.iterations = trackingIterations(options, width);
    return options;
}

std::array<int, TRACK_LEVELS> trackingIterations(const TrackerOptions& options, int width) {
    if (options.iterations != std::array<int, TRACK_LEVELS>{}) return options.iterations;
    // Measured (docs/RESULTS.md, "Tracking"): at 320 x 240, 3 / 4 / 4 tracks TUM fr1/rpy, ICL-NUIM and the
    // synthetic room as well as 10 / 5 / 4 in 0.6x the iterations; at 160 x 120 it triples the error.
    return width >= 320 ? std::array<int, TRACK_LEVELS>{3, 4, 4} : std::array<int, TRACK_LEVELS>{10, 5, 4};
}

TrackParamsGpu trackParamsFor(const TrackerOptions& o) {
    if (o.filterRadius > 4) throw Error("tracking: filter radius " + std::to_string(o.filterRadius) + " is above 4 pixels");
    for (int n : o.iterations)
        if (n < 0 || n > 100) throw Error("tracking: " + std::to_string(n) + " iterations per level is outside 0..100");
    // The finest level's last system is what the loss checks read (inliers, conditioning); all 0 is "by size".
    if (o.iterations[0] < 1 && o.iterations != std::array<int, TRACK_LEVELS>{})
        throw Error("tracking: the finest level needs at least 1 iteration (got 0)");
    for (uint32_t l = 0; l < TRACK_LEVELS; ++l)
        if (!(o.distanceGates[l] > 0) || !(o.huberDeltas[l] > 0) || !(o.normalGateDegrees[l] > 0 && o.normalGateDegrees[l] <= 180))
            throw Error("tracking: level " + std::to_string(l) + "'s distance gate and Huber delta must be positive, its normal gate in "
                        "(0, 180] degrees");
    if (!(o.filterSpatialSigma > 0) || !(o.filterDepthSigma > 0) || !(o.edgeJumpFraction > 0) || !(o.modelMergeDistance > 0))
        throw Error("tracking: filter sigmas, the edge jump fraction and the model merge distance must be positive");
    TrackParamsGpu p{};
    p.filterSpatialSigma = o.filterSpatialSigma;
    p.filterDepthSigma = o.filterDepthSigma;
    p.filterRadius = o.filterRadius;
    p.minDepth = o.minDepth;
    p.maxDepth = o.maxDepth;
    p.edgeJumpFraction = o.edgeJumpFraction;
    p.modelMergeDistance = o.modelMergeDistance;
    if (!(o.colorWeight >= 0) || !(o.colorHuber > 0)) throw Error("tracking: the colour weight must be >= 0 and its Huber delta > 0");
    p.colorWeight = o.colorWeight;
    p.colorHuber = o.colorHuber;
    p.stopRotation = float(o.stopRotation);
    p.stopTranslation = float(o.stopTranslation);
    p.minInliers = float(o.minInliers);
    p.minInlierFraction = float(o.minInlierFraction);
    p.minConditioning = float(o.minConditioning);
    p.maxJumpMetres = float(o.maxJumpMetres);
    p.maxJumpDegrees = float(o.maxJumpDegrees);
    p.maxErrorRise = float(o.maxErrorRise);
    p.minErrorForRise = float(o.minErrorForRise);
    p.minShareOfRecent = float(o.minShareOfRecent);
    return p;
}

IcpGates icpGatesFor(const TrackerOptions& o, int level) {
    IcpGates g;
    g.distance = o.distanceGates[level];
    g.normalCos = float(std::cos(double(o.normalGateDegrees[level]) * std::numbers::pi / 180.0));
    g.huber = o.huberDeltas[level];
    return g;
}

namespace {

void copyRows(float (&dst)[3][4], const Pose& pose) {
    RigidRows rows = rigidRows(pose);
    std::memcpy(dst, rows.r, sizeof(dst));
}

}  // namespace

uint32_t CameraTracker::reduceGroups(uint32_t pixels) const { return groupsFor(pixels, WG_TRACK_REDUCE * pixelsPerInvocation_); }

Intrinsics CameraTracker::levelIntrinsics(const Intrinsics& k, int level) { return pyramidLevelIntrinsics(k, level); }

static uint32_t pyramidSize(int width, int height, std::array<uint32_t, TRACK_LEVELS>& offsets) {
    if (width < int(1u << (TRACK_LEVELS - 1)) * 2 || height < int(1u << (TRACK_LEVELS - 1)) * 2 || width > 16384 || height > 16384)
        throw Error("tracking: image size " + std::to_string(width) + "x" + std::to_string(height) + " is outside 8x8..16384x16384");
    uint32_t total = 0;
    for (int l = 0; l < int(TRACK_LEVELS); ++l) {
        offsets[l] = total;
        total += levelWidth(width, l) * levelHeight(height, l);
    }
    return total;
}

CameraTracker::CameraTracker(const vk::Context& context, int width, int height, const TrackerOptions& options)
    : context_(context), width_(width), height_(height), options_(withIterations(options, width)),
      pyramidPixels_(pyramidSize(width, height, offsets_)),
      pixelsPerInvocation_(pixelsPerInvocationFor(context, options)),
      texelReads_(options.texelReads && pyramidPixels_ <= context.properties().limits.maxTexelBufferElements),
      checkerboard_(options.checkerboard && width >= 320 && width % 2 == 0),
      table_(context, sizeof(TrackPush)),
      params_(context, sizeof(TrackParamsGpu), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, vk::MemoryUse::Upload, "tracking params"),
      rawDepth_(context, VkDeviceSize(width) * height * sizeof(float), kStorage, vk::MemoryUse::Upload, "tracking depth input"),
      rawIntensity_(context, VkDeviceSize(width) * height * sizeof(float), kStorage, vk::MemoryUse::Upload, "tracking intensity input"),
      depth_(context, VkDeviceSize(pyramidPixels_) * sizeof(float), kStorage, vk::MemoryUse::Device, "tracking depth pyramid"),
      points_(context, VkDeviceSize(pyramidPixels_) * 16, kMap, vk::MemoryUse::Device, "tracking point pyramid"),
      normals_(context, VkDeviceSize(pyramidPixels_) * 16, kMap, vk::MemoryUse::Device, "tracking normal pyramid"),
      modelPositions_(context, VkDeviceSize(pyramidPixels_) * 16, kMap, vk::MemoryUse::Device, "tracking model positions"),
      modelNormals_(context, VkDeviceSize(pyramidPixels_) * 16, kMap, vk::MemoryUse::Device, "tracking model normals"),
      partials_(context, VkDeviceSize(std::max(1u, reduceGroups(uint32_t(width) * height))) * TRACK_SUM_COUNT * sizeof(float), kStorage,
                vk::MemoryUse::Device, "tracking partial sums"),
      sums_(context, TRACK_SUM_COUNT * sizeof(float), kStorage, vk::MemoryUse::Readback, "tracking sums"),
      intensity_(context, VkDeviceSize(pyramidPixels_) * sizeof(float), kMap, vk::MemoryUse::Device, "tracking intensity pyramid"),
      modelIntensity_(context, VkDeviceSize(pyramidPixels_) * sizeof(float), kMap, vk::MemoryUse::Device, "tracking model intensity"),
      state_(context, sizeof(TrackStateGpu), kStorage, vk::MemoryUse::Readback, "tracking state"),
      filter_(context, table_, "track_filter_depth"),
      downsampleDepth_(context, table_, "track_downsample_depth"),
      vertexNormals_(context, table_, "track_vertex_normals"),
      downsampleModel_(context, table_, "track_downsample_model"),
      reduce_(context, table_, texelReads_ ? "track_icp_reduce" : "track_icp_reduce_buffers"),
      sum_(context, table_, "track_icp_sum"),
      solve_(context, table_, "track_icp_solve"),
      decide_(context, table_, "track_decide"),
      modelMaps_(context, width, height),
      recorder_(context),
      timer_(context, 16) {
    if (reduceGroups(uint32_t(width) * height) > TRACK_MAX_PARTIALS) throw Error("tracking: image too large for the ICP sums");
    paramValues_ = trackParamsFor(options);
    paramValues_.pixelsPerInvocation = pixelsPerInvocation_;
    std::memcpy(params_.mapped(), &paramValues_, sizeof(paramValues_));
    table_.bind(TRACK_BINDING_PARAMS, params_);
    table_.bind(TRACK_BINDING_RAW_DEPTH, rawDepth_);
    table_.bind(TRACK_BINDING_DEPTH, depth_);
    table_.bind(TRACK_BINDING_VERTICES, points_);
    table_.bind(TRACK_BINDING_NORMALS, normals_);
    table_.bind(TRACK_BINDING_MODEL_POSITIONS, modelPositions_);
    table_.bind(TRACK_BINDING_MODEL_NORMALS, modelNormals_);
    table_.bind(TRACK_BINDING_PARTIALS, partials_);
    table_.bind(TRACK_BINDING_SUMS, sums_);
    table_.bind(TRACK_BINDING_INTENSITY, intensity_);
    table_.bind(TRACK_BINDING_MODEL_INTENSITY, modelIntensity_);
    table_.bind(TRACK_BINDING_STATE, state_);
    if (texelReads_) {
        table_.bindTexels(TRACK_BINDING_VERTEX_TEXELS, points_, VK_FORMAT_R32G32B32A32_SFLOAT, 16);
        table_.bindTexels(TRACK_BINDING_NORMAL_TEXELS, normals_, VK_FORMAT_R32G32B32A32_SFLOAT, 16);
        table_.bindTexels(TRACK_BINDING_MODEL_POSITION_TEXELS, modelPositions_, VK_FORMAT_R32G32B32A32_SFLOAT, 16);
        table_.bindTexels(TRACK_BINDING_MODEL_NORMAL_TEXELS, modelNormals_, VK_FORMAT_R32G32B32A32_SFLOAT, 16);
        table_.bindTexels(TRACK_BINDING_INTENSITY_TEXELS, intensity_, VK_FORMAT_R32_SFLOAT, 4);
        table_.bindTexels(TRACK_BINDING_MODEL_INTENSITY_TEXELS, modelIntensity_, VK_FORMAT_R32_SFLOAT, 4);
    }
}

CameraTracker::~CameraTracker() { recorder_.wait(); }

TrackPush CameraTracker::levelPush(int level, const Pose& estimate) const {
    TrackPush push{};
    copyRows(push.cameraToWorld, estimate);
    const IcpGates gates = icpGatesFor(options_, level);
    push.distanceGate = gates.distance;
    push.normalGateCos = gates.normalCos;
    push.huberDelta = gates.huber;
    const Intrinsics k = levelIntrinsics(intrinsics_, level);
    push.intrinsics[0] = k.fx, push.intrinsics[1] = k.fy, push.intrinsics[2] = k.cx, push.intrinsics[3] = k.cy;
    push.size = levelWidth(width_, level) | levelHeight(height_, level) << 16;
    push.offset = offsets_[level];
    if (level > 0) {
        push.finerOffset = offsets_[level - 1];
        push.finerWidth = levelWidth(width_, level - 1);
    }
    return push;
}

void CameraTracker::checkFrame(const DepthImage& depth, const ColorImage* color) const {
    if (depth.width != width_ || depth.height != height_ || depth.meters.size() != size_t(width_) * size_t(height_))
        throw Error("tracking: a " + std::to_string(depth.width) + "x" + std::to_string(depth.height) + " depth image for a tracker of " +
                    std::to_string(width_) + "x" + std::to_string(height_));
    if (options_.colorWeight > 0 && color && !color->empty() &&
        (color->width != width_ || color->height != height_ || color->rgb.size() != size_t(width_) * size_t(height_) * 3))
        throw Error("tracking: a " + std::to_string(color->width) + "x" + std::to_string(color->height) + " colour image for a tracker of " +
                    std::to_string(width_) + "x" + std::to_string(height_));
}

void CameraTracker::prepare(const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model, const Pose& modelPose,
                            const ColorImage* color) {
    checkFrame(depth, color);
    // A paged map brings back what the model's view reaches before the draw is recorded (docs/PAGING.md).
    if (model.volume && model.volume->paging()) (void)model.volume->pageInView(modelPose, intrinsics);
    VkCommandBuffer cmd = recorder_.begin();   // waits for the last submission: the input buffer is free
    recordPrepare(cmd, depth, intrinsics, model, modelPose, color);
    recorder_.submitAndWait();
    stageMs_.clear();
    addStageTimes();
}

void CameraTracker::addStageTimes() {
    for (const auto& stage : timer_.read()) {   // (not a structured binding: clang 14 cannot capture one)
        auto same = std::find_if(stageMs_.begin(), stageMs_.end(), [&](const auto& s) { return s.first == stage.first; });
        if (same == stageMs_.end())
            stageMs_.push_back(stage);
        else
            same->second += stage.second;
    }
}

double CameraTracker::gpuMilliseconds() const {
    double total = 0;
    for (const auto& [name, ms] : stageMs_) total += ms;
    return total;
}

void CameraTracker::recordPrepare(VkCommandBuffer cmd, const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model,
                                  const Pose& modelPose, const ColorImage* color) {
    checkFrame(depth, color);
    intrinsics_ = intrinsics;
    intrinsics_.width = width_, intrinsics_.height = height_;
    const bool drawModel = !(keepModelMaps_ && modelDrawn_);
    if (drawModel) {
        modelPose_ = modelPose;
        copyRows(paramValues_.modelWorldToCamera, inverseRigid(modelPose));
    }
    std::memcpy(rawDepth_.mapped(), depth.meters.data(), depth.meters.size() * sizeof(float));
    const bool withColor = options_.colorWeight > 0 && color && !color->empty();
    if (withColor) {
        // Rec. 601 luma in [0, 1], as the model map's (shaders_render/track_model.vert).
        float* out = static_cast<float*>(rawIntensity_.mapped());
        for (size_t i = 0; i < size_t(width_) * size_t(height_); ++i)
            out[i] = (0.299f * color->rgb[3 * i] + 0.587f * color->rgb[3 * i + 1] + 0.114f * color->rgb[3 * i + 2]) / 255.0f;
    }
    paramValues_.frameHasColor = withColor ? 1u : 0u;
    std::memcpy(params_.mapped(), &paramValues_, sizeof(paramValues_));
    timer_.reset(cmd);
    timer_.mark(cmd, "start");
    const Pose none = Pose::Identity();
    auto pixelGroups = [&](const vk::ComputePipeline& pipeline, int level) {
        TrackPush push = levelPush(level, none);
        pipeline.dispatch(cmd, &push, groupsFor(levelWidth(width_, level), WG_TRACK_PIXELS_X),
                          groupsFor(levelHeight(height_, level), WG_TRACK_PIXELS_Y));
    };
    pixelGroups(filter_, 0);
    if (withColor) {
        VkBufferCopy region{0, 0, VkDeviceSize(width_) * height_ * sizeof(float)};
        vkCmdCopyBuffer(cmd, rawIntensity_.handle(), intensity_.handle(), 1, &region);
    }
    vk::memoryBarrier(cmd);
    for (int l = 1; l < int(TRACK_LEVELS); ++l) {
        pixelGroups(downsampleDepth_, l);
        vk::memoryBarrier(cmd);
    }
    for (int l = 0; l < int(TRACK_LEVELS); ++l) pixelGroups(vertexNormals_, l);
    vk::memoryBarrier(cmd);
    timer_.mark(cmd, "track_pyramid");
    if (drawModel) {
        // The far plane at the frame's farthest measurement plus twice the widest association gate: a model point
        // further away can be associated with no pixel, and it hides nothing (it is the farthest). Triangles
        // beyond it are clipped, which costs the rasterizer less than drawing and depth-testing them behind the
        // walls of the view: with the plane at twice the maximum depth, other rooms of the soak were drawn
        // (docs/RESULTS.md, "Tracking").
        const float nearDepth = std::max(0.01f, options_.minDepth * 0.5f);
        float farDepth = options_.maxDepth > 0 ? options_.maxDepth * 2.0f : 100.0f;
        float farthest = 0;
        for (float d : depth.meters)
            if (d > farthest && std::isfinite(d) && (options_.maxDepth <= 0 || d <= options_.maxDepth)) farthest = d;
        const float widestGate = *std::max_element(options_.distanceGates.begin(), options_.distanceGates.end());
        if (farthest > 0) farDepth = std::max(nearDepth + 0.1f, std::min(farthest + 2.0f * widestGate, farDepth));
        modelMaps_.record(cmd, model, modelPose, intrinsics_, nearDepth, farDepth, modelPositions_, modelNormals_, modelIntensity_);
        for (int l = 1; l < int(TRACK_LEVELS); ++l) {
            pixelGroups(downsampleModel_, l);
            vk::memoryBarrier(cmd);
        }
        modelDrawn_ = true;
    }
    timer_.mark(cmd, "track_model");
}

void CameraTracker::recordIcpIteration(VkCommandBuffer cmd, int level, const Pose& estimate, bool solveOnGpu) {
    const bool checkerboard = checkerboard_ && level == 0;
    const uint32_t pixels = levelWidth(width_, level) * levelHeight(height_, level);
    const uint32_t groups = reduceGroups(checkerboard ? pixels / 2 : pixels);
    TrackPush push = levelPush(level, estimate);
    if (solveOnGpu) push.flags = TRACK_FLAG_STATE | uint32_t(level) << TRACK_FLAG_LEVEL_SHIFT;
    if (checkerboard) push.flags |= TRACK_FLAG_CHECKERBOARD;
    reduce_.dispatch(cmd, &push, groups);
    vk::memoryBarrier(cmd);
    TrackPush sumPush{};
    sumPush.size = groups;
    sumPush.flags = push.flags;
    sum_.dispatch(cmd, &sumPush, 1);
    vk::memoryBarrier(cmd);
    if (!solveOnGpu) return;
    solve_.dispatch(cmd, &sumPush, 1);
    vk::memoryBarrier(cmd);
}

IcpSums CameraTracker::sums(int level, const Pose& estimate) {
    if (level < 0 || level >= int(TRACK_LEVELS)) throw Error("tracking: no pyramid level " + std::to_string(level));
    VkCommandBuffer cmd = recorder_.begin();
    timer_.reset(cmd);
    timer_.mark(cmd, "start");
    recordIcpIteration(cmd, level, estimate, /*solveOnGpu=*/false);
    timer_.mark(cmd, "track_icp");
    recorder_.submitAndWait();
    addStageTimes();
    sums_.invalidate();
    float values[TRACK_SUM_COUNT];
    std::memcpy(values, sums_.mapped(), sizeof(values));
    IcpSums out{};
    for (uint32_t k = 0; k < TRACK_SUM_COUNT; ++k) out[k] = values[k];
    return out;
}

void CameraTracker::recordGpuSolvedTracking(VkCommandBuffer cmd, const DepthImage& depth, const Intrinsics& intrinsics,
                                            const TrackingModel& model, const Pose& modelPose, const Pose& initial, const ColorImage* color) {
    recordPrepare(cmd, depth, intrinsics, model, modelPose, color);
    TrackStateGpu start{};
    copyRows(start.cameraToWorld, initial);
    vkCmdUpdateBuffer(cmd, state_.handle(), 0, sizeof(start), &start);
    vk::memoryBarrier(cmd);
    // Every iteration's passes are recorded; those of a level that has stopped return at once (the state
    // says so), which is how a level still stops early without the host.
    for (int level = int(TRACK_LEVELS) - 1; level >= 0; --level)
        for (int it = 0; it < options_.iterations[level]; ++it) recordIcpIteration(cmd, level, initial, /*solveOnGpu=*/true);
}

IcpResult CameraTracker::trackInOneSubmission(const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model,
                                              const Pose& modelPose, const Pose& initial, const ColorImage* color) {
    if (model.volume && model.volume->paging()) (void)model.volume->pageInView(modelPose, intrinsics);
    VkCommandBuffer cmd = recorder_.begin();
    recordGpuSolvedTracking(cmd, depth, intrinsics, model, modelPose, initial, color);
    timer_.mark(cmd, "track_icp");
    recorder_.submitAndWait();
    return gpuSolvedResult();
}

void CameraTracker::recordTrackAndDecide(VkCommandBuffer cmd, const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model,
                                         const Pose& modelPose, const Pose& initial, const ColorImage* color, const Pose& lastTracked,
                                         const RecentFrames& recent, const vk::Buffer& framePose) {
    // Bound before anything is recorded (a binding changes decide_'s descriptor set at once).
    if (boundFramePose_ != framePose.handle()) {
        table_.bind(TRACK_BINDING_FRAME_POSE, framePose);
        boundFramePose_ = framePose.handle();
    }
    copyRows(paramValues_.lastTrackedCameraToWorld, lastTracked);
    paramValues_.recentRmse = float(recent.rmse);   // recordPrepare uploads the parameters
    paramValues_.recentInlierShare = float(recent.inlierShare);
    recordGpuSolvedTracking(cmd, depth, intrinsics, model, modelPose, initial, color);
    TrackPush push{};
    decide_.dispatch(cmd, &push, 1);
    vk::memoryBarrier(cmd);
    timer_.mark(cmd, "track_icp");
}

IcpResult CameraTracker::gpuSolvedResult() {
    stageMs_.clear();
    addStageTimes();
    state_.invalidate();
    TrackStateGpu end;
    std::memcpy(&end, state_.mapped(), sizeof(end));
    IcpResult result;
    result.submissions = 1;
    result.iterations = int(end.iterations);
    result.solved = end.unsolvedLevels == 0;
    Pose pose = Pose::Identity();
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) pose(r, c) = end.cameraToWorld[r][c];
    result.gpuEstimate = pose;
    result.gpuLostReason = end.lostReason;
    result.gpuConditioning = end.conditioning;
    // The GPU kept the rotation orthonormal in float; make it so in double, as applyTwist does.
    result.cameraToWorld = applyTwist(Twist::Zero(), pose);
    IcpSums finalSums{};
    for (uint32_t k = 0; k < TRACK_SUM_COUNT; ++k) finalSums[k] = end.finalSums[k];
    result.finalSystem = icpSystem(finalSums);
    // For the loss checks (conditioning, solvable): the same analysis of level 0's last system as the host mode's.
    result.finalStep = solveIcpStep(result.finalSystem);
    if (end.unsolvedLevels & 1u) result.finalStep.solved = false;
    return result;
}

IcpResult CameraTracker::align(const Pose& initial) {
    IcpResult result;
    result.cameraToWorld = initial;
    result.submissions = 1;   // prepare()
    result.solved = true;
    for (int level = int(TRACK_LEVELS) - 1; level >= 0; --level) {
        for (int it = 0; it < options_.iterations[level]; ++it) {
            IcpSystem system = icpSystem(sums(level, result.cameraToWorld));
            ++result.iterations;
            ++result.submissions;
            IcpStep step = solveIcpStep(system);
            if (level == 0) result.finalSystem = system, result.finalStep = step;
            if (!step.solved) {
                result.solved = false;
                break;
            }
            result.cameraToWorld = applyTwist(step.twist, result.cameraToWorld);
            if (step.twist.head<3>().norm() < options_.stopRotation && step.twist.tail<3>().norm() < options_.stopTranslation) break;
        }
    }
    return result;
}

CameraTracker::Maps CameraTracker::downloadMaps() const {
    Maps maps;
    maps.depth.resize(pyramidPixels_);
    vk::downloadFromBuffer(context_, depth_, maps.depth.data(), maps.depth.size() * sizeof(float));
    for (auto [buffer, out] : {std::pair{&points_, &maps.points}, {&normals_, &maps.normals}, {&modelPositions_, &maps.modelPositions},
                               {&modelNormals_, &maps.modelNormals}}) {
        out->resize(pyramidPixels_);
        vk::downloadFromBuffer(context_, *buffer, out->data(), out->size() * sizeof(Eigen::Vector4f));
    }
    for (auto [buffer, out] : {std::pair{&intensity_, &maps.intensity}, {&modelIntensity_, &maps.modelIntensity}}) {
        out->resize(pyramidPixels_);
        vk::downloadFromBuffer(context_, *buffer, out->data(), out->size() * sizeof(float));
    }
    return maps;
}

}  // namespace vkmesh::gpu
