// Tracking's model maps: vkmesh's mesh drawn by the Vulkan rasterizer at a camera pose with the depth camera's
// own intrinsics, into a world-space position map and a unit-normal map (RGBA32F, w = 1 where the mesh is,
// 0 elsewhere, where xyz is meaningless) and an intensity map of its vertex colours (R32F, -1 where it has none),
// then copied into level 0 of the tracker's model pyramid buffers. Only the faces seen from free space are
// drawn, nearest first, in one pass. One draw replaces a raycast of the TSDF (shaders_render/track_model.*). The draw
// reads the mesh buffers as they are (an indirect indexed draw), so no mesh goes through the host: a volume's own
// mesh is drawn from its vertex heap through the list of the triangles in view (GpuVolume::recordModelView).
#pragma once

#include "core/types.h"
#include "gpu/gpu_volume.h"
#include "vk/buffer.h"
#include "vk/context.h"

namespace vkmesh::gpu {

// What tracking draws: a volume's mesh, of which only the triangles that can be in the view are drawn (listed on
// the GPU by GpuVolume::recordModelView: the cost follows the view, not the map, and no export is needed), or a
// mesh in buffers (MeshBuffers: every triangle is drawn; empty handles: no model).
struct TrackingModel {
    TrackingModel(GpuVolume& volume) : volume(&volume) {}
    TrackingModel(const MeshBuffers& buffers) : buffers(buffers) {}
    // A volume's older map: only the triangles whose three vertices frames numbered below `createdBefore` created
    // (the surface made before the recent frames, that a loop is measured against: docs/LOOP_CLOSURE.md, "Loops
    // against the older map").
    static TrackingModel olderMap(GpuVolume& volume, uint32_t createdBefore) {
        TrackingModel model(volume);
        model.createdBefore = createdBefore;
        return model;
    }
    GpuVolume* volume = nullptr;
    MeshBuffers buffers;
    uint32_t createdBefore = UINT32_MAX;   // a volume's triangles listed (GpuVolume::recordModelView): all by default
};

class ModelMapRenderer {
public:
    // Maps of width x height pixels. Throws Error when the queue has no graphics or the device cannot render
    // to R32G32B32A32_SFLOAT / D32_SFLOAT.
    ModelMapRenderer(const vk::Context& context, int width, int height);
    ~ModelMapRenderer();
    ModelMapRenderer(const ModelMapRenderer&) = delete;
    ModelMapRenderer& operator=(const ModelMapRenderer&) = delete;

    // Records the draw of `model` seen from `cameraToWorld` (depth range [near, far] metres) and the copies of
    // the maps to the start of `positions` and `normals` (width x height vec4 each) and `intensity` (float),
    // followed by a barrier that makes them visible to compute shaders. An empty mesh (no buffers yet, or a volume
    // without triangles) clears the maps (no model anywhere).
    void record(VkCommandBuffer cmd, const TrackingModel& model, const Pose& cameraToWorld, const Intrinsics& intrinsics,
                float nearDepth, float farDepth, const vk::Buffer& positions, const vk::Buffer& normals,
                const vk::Buffer& intensity) const;
private:
    void release();
    const vk::Context& context_;
    int width_, height_;
    static constexpr int kImages = 4;   // position, normal, intensity, depth
    VkImage images_[kImages]{};
    VkDeviceMemory memory_[kImages]{};
    VkImageView views_[kImages]{};
    VkRenderPass renderPass_ = VK_NULL_HANDLE;
    VkFramebuffer framebuffer_ = VK_NULL_HANDLE;
    VkPipelineLayout pipelineLayout_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;           // front faces counter-clockwise (fx * fy > 0)
    VkPipeline mirroredPipeline_ = VK_NULL_HANDLE;   // clockwise (a negative fx * fy mirrors the picture)
};

}  // namespace vkmesh::gpu
