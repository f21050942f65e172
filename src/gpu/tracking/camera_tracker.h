// Stage: camera tracking (docs/TRACKING.md; shaders_comp/track/, shaders_render/track_model.*). Aligns a depth
// frame to vkmesh's own mesh by point-to-plane ICP, frame to model:
//   prepare()  one submission: the frame's depth -> bilateral filter -> TRACK_LEVELS-level pyramid -> point and
//              normal maps per level; the mesh drawn at the model pose (ModelMapRenderer) -> model position and
//              normal maps, downsampled alike (or, after keepModelMaps(true), the last frame's maps kept).
//   sums()     one submission per ICP iteration (the maps read as texel buffers where the device allows; the
//              finest level on a checkerboard): projective association with distance and normal gates, Huber
//              weights, the 6x6 system's terms summed per workgroup by a fixed tree and the partials added in
//              a fixed order (the same frames give the same poses, bit for bit); the host solves in double
//              (core/icp_solve.h).
//   align()    coarse to fine from an initial pose, TrackerOptions::iterations per level, stopping a level
//              early when the step is tiny.
//   trackInOneSubmission()  prepare() and align() in one submission: every iteration's 6x6 system solved on
//              the GPU in float (track_icp_solve), the estimate kept in GPU memory; one host wait per frame
//              instead of one per iteration (TrackerOptions::solveOnGpu).
// The loss policy (too few inliers, a jump, an ill-conditioned system, a rising error) and the prediction are
// PoseTracker's (pose_tracker.h). CPU reference: src/cpu/reference_tracking.h.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/icp_solve.h"
#include "core/types.h"
#include "gpu/gpu_volume.h"
#include "gpu/layout.h"
#include "gpu/tracking/model_maps.h"
#include "vk/buffer.h"
#include "vk/commands.h"
#include "vk/context.h"
#include "vk/pipeline.h"

namespace vkmesh::gpu {

struct TrackerOptions {
    // ICP iterations per pyramid level, finest (level 0) first; the coarsest level runs first. All 0 (the
    // default): by the finest tracked level's width (trackingIterations()): 3, 4, 4 from 320 pixels wide (VGA frames
    // tracked at 320 x 240, or 320 x 240 frames), 10, 5, 4 below, where the coarse levels are tiny (40 x 30) and
    // the finest level does the work (docs/RESULTS.md, "Tracking").
    std::array<int, TRACK_LEVELS> iterations{0, 0, 0};
    // A level stops early once a step rotates less than this (radians) and moves less than this (metres).
    double stopRotation = 1e-4;
    double stopTranslation = 1e-4;
    // Bilateral filter of the depth before tracking (fusion takes the raw depth).
    float filterSpatialSigma = 4.5f;   // pixels
    float filterDepthSigma = 0.03f;    // metres
    uint32_t filterRadius = 2;         // window half-size in pixels, at most 4
    // Neighbours further apart in depth than this fraction of the depth: a depth edge, no normal.
    float edgeJumpFraction = 0.05f;
    // Association gates and robust weight per level, finest first: wider at the coarse levels, which must
    // catch the motion the prediction missed (a fast turn moves a point at 2 m by 10-20 cm).
    std::array<float, TRACK_LEVELS> distanceGates{0.10f, 0.20f, 0.30f};   // metres
    std::array<float, TRACK_LEVELS> normalGateDegrees{20.0f, 25.0f, 30.0f};
    std::array<float, TRACK_LEVELS> huberDeltas{0.01f, 0.02f, 0.04f};     // metres
    // Model maps' downsampling: fine pixels further than this from the first are not averaged (metres).
    float modelMergeDistance = 0.05f;
    // The photometric term: the frame's intensity against the mesh's vertex colours drawn at the model pose,
    // for frames with colour (and a mesh with colours), added to the geometric system with this weight per
    // pixel (0: geometry only). Intensities are in [0, 1], point-to-plane residuals in metres. On TUM fr1/rpy
    // (fast rotation) it halves the trajectory error (docs/RESULTS.md, "Tracking").
    float colorWeight = 0.1f;
    float colorHuber = 0.1f;
    // Depth samples outside [minDepth, maxDepth] are ignored (maxDepth 0: no limit).
    float minDepth = 0.1f;
    float maxDepth = 0.0f;
    // Loss (PoseTracker): a frame is lost when, after ICP,
    double minInlierFraction = 0.10;   //  fewer than this share of its valid pixels are inliers (level 0),
    double minInliers = 100;           //  or fewer than this many;
    double minConditioning = 1e-6;     //  the system's smallest / largest eigenvalue is below this (a direction
                                       //  of motion unconstrained, e.g. one plane);
    double maxJumpMetres = 0.30;       //  the pose moved further than this from the last tracked one,
    double maxJumpDegrees = 30.0;      //  or turned further;
    double maxErrorRise = 3.0;         //  its inlier RMSE exceeds this many times the recent tracked frames'
    double minErrorForRise = 0.005;    //  (and this many metres: a tiny error may triple harmlessly);
    double minShareOfRecent = 0.5;     //  its inlier share is below this fraction of the recent tracked frames'
                                       //  (a jump that ICP settles next to the old pose: on real data the share
                                       //  falls to 0.4 of the recent frames', where tracked frames stay above 0.73;
                                       //  docs/TRACKING.md).
    // Where the 6x6 systems are solved: false, on the host in double after each iteration (one submission per
    // iteration); true, on the GPU in float, the whole frame's ICP in one submission with prepare()
    // (CameraTracker::trackInOneSubmission; docs/TRACKING.md, "One submission").
    bool solveOnGpu = false;
    // Pixels each invocation of the ICP reduction sums (1..TRACK_MAX_PIXELS_PER_INVOCATION); 0: by device, 64
    // on a CPU device (lavapipe: each workgroup costs) and 16 on a GPU (which wants many workgroups).
    uint32_t pixelsPerInvocation = 0;
    // The ICP pass reads the per-pixel maps as texel buffers (texelFetch) where the device's
    // maxTexelBufferElements holds the pyramid, else as storage buffers (false: always). On lavapipe a texel
    // fetch is a vector gather and an SSBO load at per-lane addresses a loop over the lanes (docs/TRACKING.md).
    bool texelReads = true;
    // The finest level's ICP visits half its pixels, a checkerboard (x + y even), when that level is at least
    // 320 pixels wide (and of even width); below, every pixel (checkerboardUsed()). On TUM fr1/rpy at 320 x 240:
    // 0.88x the tracking time, the same trajectory errors on the three shared sequences (docs/RESULTS.md).
    bool checkerboard = true;
    // Track on the frames downsampled by this factor (1, 2 or 4; PoseTracker): the pyramid's finest level is
    // width / downsample by height / downsample, with intrinsics to match; fusion still takes the full frame.
    // 0 (the default): 2 for frames at least 640 pixels wide, else 1 (trackingDownsample()); at 640 x 480 that is a
    // quarter of the finest level's work at the same accuracy (docs/TRACKING.md, docs/RESULTS.md "Tracking").
    int downsample = 0;
    // Reuse of the model maps (PoseTracker; InfiniTAM's idea): a frame whose predicted pose lies within
    // modelReuseMetres and modelReuseDegrees of the pose the maps were last drawn at is associated with those
    // maps (at that pose) instead of a new draw of the mesh, for at most modelReuseFrames frames in a row
    // (0: the mesh is drawn for every frame). The surface fused meanwhile is missing from reused maps. The
    // defaults draw half the frames' maps on ICL-NUIM and the synthetic room and 70 % on TUM fr1/rpy, with the
    // same trajectory errors (docs/RESULTS.md, "Tracking"): on lavapipe the draw is the largest part of tracking.
    int modelReuseFrames = 2;
    double modelReuseMetres = 0.04;
    double modelReuseDegrees = 4.0;
};

// The recent tracked frames' means that the loss policy compares a frame with (0: none yet; PoseTracker keeps them).
struct RecentFrames {
    double rmse = 0;          // inlier RMSE (metres)
    double inlierShare = 0;   // inliers / valid pixels
};

// The factor frames `width` pixels wide are tracked downsampled by (TrackerOptions::downsample, 0 resolved).
int trackingDownsample(const TrackerOptions& options, int width);
// The iterations per level (TrackerOptions::iterations, all 0 resolved) for a finest tracked level `width` wide.
std::array<int, TRACK_LEVELS> trackingIterations(const TrackerOptions& options, int width);
// The options as the shaders read them (TrackParamsGpu, without the model pose); throws Error naming a value
// out of range.
TrackParamsGpu trackParamsFor(const TrackerOptions& options);
// The association gates of pyramid level `level`.
IcpGates icpGatesFor(const TrackerOptions& options, int level);

// What align() found.
struct IcpResult {
    Pose cameraToWorld = Pose::Identity();
    IcpSystem finalSystem;          // the last iteration's sums at level 0 (before its step)
    IcpStep finalStep;
    int iterations = 0;             // over all levels
    uint32_t submissions = 0;       // GPU submissions waited for (one per iteration, plus prepare)
    bool solved = false;            // every level's last system could be solved
    // GPU-solved: the estimate exactly as the GPU holds it (float; cameraToWorld is it re-orthonormalised in
    // double), and, after track_decide, its verdict (TRACK_LOST_*, TRACK_TRACKED) and float conditioning.
    Pose gpuEstimate = Pose::Identity();
    uint32_t gpuLostReason = TRACK_TRACKED;
    double gpuConditioning = 0;
};

class CameraTracker {
public:
    // Frames of width x height pixels (the pyramid: width >> l by height >> l).
    CameraTracker(const vk::Context& context, int width, int height, const TrackerOptions& options = {});
    ~CameraTracker();
    CameraTracker(const CameraTracker&) = delete;
    CameraTracker& operator=(const CameraTracker&) = delete;

    // The frame's pyramid and the model maps of `model` drawn at `modelPose` (one submission). The model may be
    // empty (no model: every pixel unassociated). The depth (and the colour, when given and not empty) must be
    // width x height; colour is used only with options.colorWeight > 0.
    void prepare(const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model, const Pose& modelPose,
                 const ColorImage* color = nullptr);
    // Whether the next prepare() (or trackInOneSubmission / recordTrackAndDecide) keeps the model maps of the last
    // one, drawn at modelPose(), instead of drawing `model` at its `modelPose` (ignored until maps were drawn).
    void keepModelMaps(bool keep) { keepModelMaps_ = keep; }
    // The pose the current model maps were drawn at, and whether any were.
    const Pose& modelPose() const { return modelPose_; }
    bool hasModelMaps() const { return modelDrawn_; }
    // One ICP iteration's sums at `level` for the frame at `estimate` (after prepare; one submission).
    IcpSums sums(int level, const Pose& estimate);
    // ICP from `initial`, coarse to fine (after prepare).
    IcpResult align(const Pose& initial);
    // prepare() and ICP from `initial` in one submission, every system solved on the GPU (float Cholesky of
    // the equilibrated system; the same steps, stopping rule and level-0 final system as align()).
    IcpResult trackInOneSubmission(const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model, const Pose& modelPose,
                                   const Pose& initial, const ColorImage* color = nullptr);
    // trackInOneSubmission()'s passes recorded into `cmd`, the start of a volume's frame (FrameInput::recordPose),
    // followed by track_decide: the loss policy (trackingLoss, pose_tracker.h) decided on the GPU against
    // `lastTracked` and `recent` (the recent tracked frames' means, 0: none), and the frame's pose written
    // into the volume's `framePose` (FramePoseGpu; skip when lost). After the submission: gpuSolvedResult().
    void recordTrackAndDecide(VkCommandBuffer cmd, const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model,
                              const Pose& modelPose, const Pose& initial, const ColorImage* color, const Pose& lastTracked,
                              const RecentFrames& recent, const vk::Buffer& framePose);
    // Throws Error unless the frame's depth is width x height and its colour (used when options.colorWeight > 0) is
    // registered to it; what recordTrackAndDecide's caller checks before it records anything.
    void checkFrame(const DepthImage& depth, const ColorImage* color) const;
    // What the last GPU-solved tracking found (trackInOneSubmission, or after recordTrackAndDecide's submission).
    IcpResult gpuSolvedResult();

    // Milliseconds the GPU spent in the last prepare() and in the ICP passes since (timestamps; 0 without), in
    // all and per stage: track_pyramid (filter, pyramids), track_model (the mesh drawn, its maps), track_icp.
    double gpuMilliseconds() const;
    const std::vector<std::pair<std::string, double>>& gpuStageMilliseconds() const { return stageMs_; }
    bool readsTexels() const { return texelReads_; }   // which ICP pass this device and these options got
    bool checkerboardUsed() const { return checkerboard_; }   // TrackerOptions::checkerboard at this size
    int width() const { return width_; }
    int height() const { return height_; }
    const TrackerOptions& options() const { return options_; }
    // The intrinsics of pyramid level `level` (core/icp_solve.h, pyramidLevelIntrinsics).
    static Intrinsics levelIntrinsics(const Intrinsics& intrinsics, int level);

    // The maps of the last prepare(), for the tests and the CPU reference: every level, concatenated as on the
    // GPU (level l starts at pixelOffset(l)).
    struct Maps {
        std::vector<float> depth;
        std::vector<Eigen::Vector4f> points, normals, modelPositions, modelNormals;
        std::vector<float> intensity, modelIntensity;   // < 0: none
    };
    Maps downloadMaps() const;
    uint32_t pixelOffset(int level) const { return offsets_[level]; }

private:
    TrackPush levelPush(int level, const Pose& estimate) const;
    uint32_t reduceGroups(uint32_t pixels) const;   // track_icp_reduce's workgroups over `pixels` pixels
    // One ICP iteration at `level`: the reduction and the fixed-order sum, and with `solveOnGpu` the solve that
    // moves the state's estimate (the passes then read the estimate from the state, not from `estimate`).
    void recordIcpIteration(VkCommandBuffer cmd, int level, const Pose& estimate, bool solveOnGpu);
    void addStageTimes();   // the timer's stages of the last submission, added to stageMs_
    // prepare()'s passes, recorded into `cmd` (the caller submits).
    void recordPrepare(VkCommandBuffer cmd, const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model,
                       const Pose& modelPose, const ColorImage* color);
    // recordPrepare() and every ICP iteration solved on the GPU, recorded into `cmd`.
    void recordGpuSolvedTracking(VkCommandBuffer cmd, const DepthImage& depth, const Intrinsics& intrinsics, const TrackingModel& model,
                                 const Pose& modelPose, const Pose& initial, const ColorImage* color);
    const vk::Context& context_;
    int width_, height_;
    TrackerOptions options_;
    std::array<uint32_t, TRACK_LEVELS> offsets_{};
    uint32_t pyramidPixels_ = 0;
    uint32_t pixelsPerInvocation_ = 16;   // TrackParamsGpu::pixelsPerInvocation for this device
    bool texelReads_ = false;             // the ICP reads the maps as texel buffers (TrackerOptions::texelReads)
    bool checkerboard_ = false;           // the finest level's ICP visits a checkerboard (TrackerOptions::checkerboard)
    Intrinsics intrinsics_;
    Pose modelPose_ = Pose::Identity();
    bool keepModelMaps_ = false;   // keepModelMaps()
    bool modelDrawn_ = false;      // the model buffers hold maps drawn at modelPose_
    vk::BindingTable table_;
    TrackParamsGpu paramValues_{};   // what params_ holds (the model pose changes every prepare())
    vk::Buffer params_, rawDepth_, rawIntensity_, depth_, points_, normals_, modelPositions_, modelNormals_, partials_, sums_;
    vk::Buffer intensity_, modelIntensity_, state_;
    vk::ComputePipeline filter_, downsampleDepth_, vertexNormals_, downsampleModel_, reduce_, sum_, solve_, decide_;
    VkBuffer boundFramePose_ = VK_NULL_HANDLE;   // the volume pose buffer decide_ writes (bound on first use)
    ModelMapRenderer modelMaps_;
    vk::CommandRecorder recorder_;
    vk::StageTimer timer_;
    std::vector<std::pair<std::string, double>> stageMs_;
};

}  // namespace vkmesh::gpu
