// CPU reference of the tracking stage's compute passes (shaders_comp/track/, docs/TRACKING.md): the same
// float operations in the same order, one pixel at a time. The tests compare the GPU's pyramid maps and ICP
// sums with these. The model maps themselves come from the rasterizer; the reference takes them as input
// (the GPU's, downloaded) and checks the passes that read them.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "core/icp_solve.h"
#include "core/types.h"
#include "shared_layout.h"

namespace vkmesh::cpu {

// One pyramid level's maps, row-major, width x height.
struct TrackingLevel {
    int width = 0, height = 0;
    Intrinsics intrinsics;                   // of this level (pyramidLevelIntrinsics)
    std::vector<float> depth;                // 0 = none
    std::vector<Eigen::Vector4f> points;     // camera space, w = 1 (0 = none)
    std::vector<Eigen::Vector4f> normals;    // camera space, facing the camera, w = 1 (0 = none)
};

// The frame's pyramid (TRACK_LEVELS levels): bilateral filter, downsampling, points and normals.
std::vector<TrackingLevel> referenceTrackingPyramid(const DepthImage& depth, const Intrinsics& intrinsics,
                                                    const gpu::TrackParamsGpu& params);

// Level l + 1 of a model map pair from level l (track_downsample_model.comp).
void referenceDownsampleModel(const std::vector<Eigen::Vector4f>& positions, const std::vector<Eigen::Vector4f>& normals,
                              int width, int height, const gpu::TrackParamsGpu& params, std::vector<Eigen::Vector4f>& coarsePositions,
                              std::vector<Eigen::Vector4f>& coarseNormals);

// One ICP iteration's sums (track_icp_reduce.comp) at one level: the frame's points and normals against the
// model maps (world space, drawn at modelPose), for the frame at `estimate`, with the level's gates. Each pixel's terms are formed in
// float as on the GPU and summed in double (the GPU sums in float: compare with a tolerance). `checkerboard`:
// only the pixels with x + y even (TRACK_FLAG_CHECKERBOARD).
// The photometric term's input at one level (TrackerOptions::colorWeight): the frame's and the model's
// intensity maps (< 0: none), and its weight and Huber delta. Off when `weight` is 0.
struct PhotometricLevel {
    const std::vector<float>* frame = nullptr;
    const std::vector<float>* model = nullptr;
    float weight = 0;
    float huber = 0.1f;
};
IcpSums referenceIcpSums(const TrackingLevel& frame, const std::vector<Eigen::Vector4f>& modelPositions,
                         const std::vector<Eigen::Vector4f>& modelNormals, const Pose& estimate, const Pose& modelPose,
                         const IcpGates& gates, const PhotometricLevel& photometric = {}, bool checkerboard = false);

// The model in a view (shaders_comp/model_view/cull_view_blocks.comp): how far inside the view of a `width` x
// `height` camera with `intrinsics` at `cameraToWorld` (depths in [near, far]) the bounding sphere of the block at
// `block` (block coordinates, `blockSide` metres) reaches, in metres: >= 0 when the block is listed (any triangle of
// it may cover a pixel), < 0 when it lies wholly outside one of the view's six planes. In double: a GPU verdict
// that differs can only be a block within float rounding of 0.
double referenceBlockViewSlack(const Eigen::Vector3i& block, double blockSide, const Pose& cameraToWorld, const Intrinsics& intrinsics,
                               int width, int height, double nearDepth, double farDepth);

}  // namespace vkmesh::cpu
