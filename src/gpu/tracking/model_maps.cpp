#include "gpu/tracking/model_maps.h"

#include <cstring>
#include <map>
#include <span>
#include <string>

#include "../../../shaders_render/track_model.h"
#include "core/camera.h"
#include "vk/graphics_resources.h"
#include "vk/check.h"

namespace vkmesh::gpu {
namespace {

constexpr VkFormat kMapFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
constexpr VkFormat kIntensityFormat = VK_FORMAT_R32_SFLOAT;
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
constexpr int kDepthImage = 3;
// The attachments in order: position, normal, intensity, depth.
VkFormat imageFormat(int i) { return i == kDepthImage ? kDepthFormat : i == 2 ? kIntensityFormat : kMapFormat; }


// Where no model was drawn the position and normal maps keep their clear value: xyz far from any real
// coordinate, w = 0 ("no model").
constexpr float kNoModel = -3.0e38f;

void requireFormat(const vk::Context& context, VkFormat format, VkFormatFeatureFlags feature, const char* what) {
    VkFormatProperties props{};
    vkGetPhysicalDeviceFormatProperties(context.physicalDevice(), format, &props);
    if (!(props.optimalTilingFeatures & feature))
        throw Error("device '" + context.info().name + "' cannot render tracking's model maps: no " + what);
}

}  // namespace

ModelMapRenderer::ModelMapRenderer(const vk::Context& context, int width, int height)
    : context_(context), width_(width), height_(height) {
    uint32_t familyCount = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(context.physicalDevice(), &familyCount, nullptr);
    std::vector<VkQueueFamilyProperties> families(familyCount);
    vkGetPhysicalDeviceQueueFamilyProperties(context.physicalDevice(), &familyCount, families.data());
    if (context.queueFamily() >= familyCount || !(families[context.queueFamily()].queueFlags & VK_QUEUE_GRAPHICS_BIT))
        throw Error("device '" + context.info().name + "': vkmesh's queue does not support graphics, which tracking needs "
                    "(it draws the mesh at the predicted pose)");
    requireFormat(context, kMapFormat, VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT, "R32G32B32A32_SFLOAT colour attachment");
    requireFormat(context, kIntensityFormat, VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT, "R32_SFLOAT colour attachment");
    requireFormat(context, kDepthFormat, VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT, "D32_SFLOAT depth attachment");

    VkDevice device = context.device();
    VkShaderModule vert = VK_NULL_HANDLE, frag = VK_NULL_HANDLE;
    try {
        for (int i = 0; i < kImages; ++i) {
            const bool depth = i == kDepthImage;
            vk::createAttachmentImage(context, width, height, imageFormat(i),
                                          depth ? VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT
                                                : VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                          depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT, images_[i], memory_[i], views_[i]);
        }

        VkAttachmentDescription attachments[kImages]{};
        for (int i = 0; i < kImages; ++i) {
            const bool depth = i == kDepthImage;
            attachments[i].format = imageFormat(i);
            attachments[i].samples = VK_SAMPLE_COUNT_1_BIT;
            attachments[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
            attachments[i].storeOp = depth ? VK_ATTACHMENT_STORE_OP_DONT_CARE : VK_ATTACHMENT_STORE_OP_STORE;
            attachments[i].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
            attachments[i].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
            attachments[i].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
            attachments[i].finalLayout = depth ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        }
        VkAttachmentReference colorRefs[3] = {{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
                                              {1, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
                                              {2, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL}};
        VkAttachmentReference depthRef{kDepthImage, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
        VkSubpassDescription subpass{};
        subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
        subpass.colorAttachmentCount = 3;
        subpass.pColorAttachments = colorRefs;
        subpass.pDepthStencilAttachment = &depthRef;
        VkSubpassDependency deps[2]{};
        // Before: the clears come after the last frame's copies out of the maps (and its depth tests).
        deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
        deps[0].dstSubpass = 0;
        deps[0].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                               VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
        deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                               VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
        deps[0].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT;
        deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT |
                                VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        // After: the maps are copied into the pyramid buffers.
        deps[1].srcSubpass = 0;
        deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
        deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
        deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
        deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        VkRenderPassCreateInfo rpInfo{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
        rpInfo.attachmentCount = kImages;
        rpInfo.pAttachments = attachments;
        rpInfo.subpassCount = 1;
        rpInfo.pSubpasses = &subpass;
        rpInfo.dependencyCount = 2;
        rpInfo.pDependencies = deps;
        VKM_CHECK(vkCreateRenderPass(device, &rpInfo, nullptr, &renderPass_));

        VkFramebufferCreateInfo fbInfo{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
        fbInfo.renderPass = renderPass_;
        fbInfo.attachmentCount = kImages;
        fbInfo.pAttachments = views_;
        fbInfo.width = uint32_t(width);
        fbInfo.height = uint32_t(height);
        fbInfo.layers = 1;
        VKM_CHECK(vkCreateFramebuffer(device, &fbInfo, nullptr, &framebuffer_));

        VkPushConstantRange range{VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(ModelMapPush)};
        VkPipelineLayoutCreateInfo layoutInfo{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
        layoutInfo.pushConstantRangeCount = 1;
        layoutInfo.pPushConstantRanges = &range;
        VKM_CHECK(vkCreatePipelineLayout(device, &layoutInfo, nullptr, &pipelineLayout_));

        vert = vk::createGraphicsShaderModule(device, "track_model.vert");
        frag = vk::createGraphicsShaderModule(device, "track_model.frag");
        VkPipelineShaderStageCreateInfo stages[2]{};
        for (int i = 0; i < 2; ++i) {
            stages[i].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
            stages[i].stage = i == 0 ? VK_SHADER_STAGE_VERTEX_BIT : VK_SHADER_STAGE_FRAGMENT_BIT;
            stages[i].module = i == 0 ? vert : frag;
            stages[i].pName = "main";
        }
        VkVertexInputBindingDescription binding{0, MeshBuffers::kStride, VK_VERTEX_INPUT_RATE_VERTEX};
        VkVertexInputAttributeDescription vertexAttributes[3] = {
            {MODEL_LOC_POSITION, 0, VK_FORMAT_R32G32B32_SFLOAT, MeshBuffers::kPositionOffset},
            {MODEL_LOC_NORMAL, 0, VK_FORMAT_R32G32B32_SFLOAT, MeshBuffers::kNormalOffset},
            {MODEL_LOC_COLOR, 0, VK_FORMAT_R8G8B8A8_UNORM, MeshBuffers::kColorOffset},
        };
        VkPipelineVertexInputStateCreateInfo vertexInput{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
        vertexInput.vertexBindingDescriptionCount = 1;
        vertexInput.pVertexBindingDescriptions = &binding;
        vertexInput.vertexAttributeDescriptionCount = 3;
        vertexInput.pVertexAttributeDescriptions = vertexAttributes;
        VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
        assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
        VkPipelineViewportStateCreateInfo viewportState{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
        VkViewport viewport{0.0f, 0.0f, float(width), float(height), 0.0f, 1.0f};
        VkRect2D scissor{{0, 0}, {uint32_t(width), uint32_t(height)}};
        viewportState.viewportCount = 1;
        viewportState.pViewports = &viewport;
        viewportState.scissorCount = 1;
        viewportState.pScissors = &scissor;
        VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
        raster.polygonMode = VK_POLYGON_MODE_FILL;
        raster.cullMode = VK_CULL_MODE_BACK_BIT;   // only the sides facing free space (record())
        raster.lineWidth = 1.0f;
        VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
        multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
        // One pass, the nearest front face wins (record(): why front faces only). Two pipelines that differ only
        // in which winding is the front: a negative fx * fy mirrors the picture and so the winding.
        VkPipelineDepthStencilStateCreateInfo depthState{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
        depthState.depthTestEnable = VK_TRUE;
        depthState.depthWriteEnable = VK_TRUE;
        depthState.depthCompareOp = VK_COMPARE_OP_LESS;
        VkPipelineColorBlendAttachmentState blendAttachments[3]{};
        for (auto& b : blendAttachments)
            b.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
        VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
        blend.attachmentCount = 3;
        blend.pAttachments = blendAttachments;
        VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
        info.stageCount = 2;
        info.pStages = stages;
        info.pVertexInputState = &vertexInput;
        info.pInputAssemblyState = &assembly;
        info.pViewportState = &viewportState;
        info.pRasterizationState = &raster;
        info.pMultisampleState = &multisample;
        info.pDepthStencilState = &depthState;
        info.pColorBlendState = &blend;
        info.layout = pipelineLayout_;
        info.renderPass = renderPass_;
        info.subpass = 0;
        // The mesh's triangles are counter-clockwise seen from free space (docs/ARCHITECTURE.md); the projection
        // keeps the image's axes (x right, y down, as Vulkan's framebuffer), under which a counter-clockwise
        // triangle seen from the camera has Vulkan's positive area when fx * fy > 0.
        raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
        VKM_CHECK(vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline_));
        raster.frontFace = VK_FRONT_FACE_CLOCKWISE;
        VKM_CHECK(vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &mirroredPipeline_));
    } catch (...) {
        if (vert) vkDestroyShaderModule(device, vert, nullptr);
        if (frag) vkDestroyShaderModule(device, frag, nullptr);
        release();
        throw;
    }
    vkDestroyShaderModule(device, vert, nullptr);
    vkDestroyShaderModule(device, frag, nullptr);
}

ModelMapRenderer::~ModelMapRenderer() { release(); }

void ModelMapRenderer::release() {
    VkDevice device = context_.device();
    if (pipeline_) vkDestroyPipeline(device, pipeline_, nullptr);
    if (mirroredPipeline_) vkDestroyPipeline(device, mirroredPipeline_, nullptr);
    if (pipelineLayout_) vkDestroyPipelineLayout(device, pipelineLayout_, nullptr);
    if (framebuffer_) vkDestroyFramebuffer(device, framebuffer_, nullptr);
    if (renderPass_) vkDestroyRenderPass(device, renderPass_, nullptr);
    for (int i = 0; i < kImages; ++i) {
        if (views_[i]) vkDestroyImageView(device, views_[i], nullptr);
        if (images_[i]) vkDestroyImage(device, images_[i], nullptr);
        if (memory_[i]) vkFreeMemory(device, memory_[i], nullptr);
        views_[i] = VK_NULL_HANDLE, images_[i] = VK_NULL_HANDLE, memory_[i] = VK_NULL_HANDLE;
    }
    pipeline_ = VK_NULL_HANDLE, mirroredPipeline_ = VK_NULL_HANDLE, pipelineLayout_ = VK_NULL_HANDLE, framebuffer_ = VK_NULL_HANDLE, renderPass_ = VK_NULL_HANDLE;
}

void ModelMapRenderer::record(VkCommandBuffer cmd, const TrackingModel& model, const Pose& cameraToWorld, const Intrinsics& intrinsics,
                              float nearDepth, float farDepth, const vk::Buffer& positions, const vk::Buffer& normals,
                              const vk::Buffer& intensity) const {
    ModelMapPush push{};
    RigidRows rows = rigidRows(inverseRigid(cameraToWorld));
    std::memcpy(push.worldToCamera, rows.r, sizeof(push.worldToCamera));
    push.intrinsics[0] = intrinsics.fx, push.intrinsics[1] = intrinsics.fy;
    push.intrinsics[2] = intrinsics.cx, push.intrinsics[3] = intrinsics.cy;
    push.viewport[0] = float(width_), push.viewport[1] = float(height_);
    push.viewport[2] = nearDepth, push.viewport[3] = farDepth;

    // A volume's triangles in view, listed before the render pass (a compute pass, which ends with the barrier
    // for the draw).
    const MeshBuffers mesh = model.volume ? model.volume->recordModelView(cmd, cameraToWorld, intrinsics, width_, height_, nearDepth,
                                                                          farDepth, model.createdBefore)
                                          : model.buffers;
    const bool hasMesh = mesh.vertices && mesh.indices && mesh.drawIndirect;
    if (hasMesh && !model.volume) recordMeshReadBarrier(cmd);   // (recordModelView ends with it)
    VkClearValue clears[kImages]{};   // position and normal xyz kNoModel, w = 0 (no model); intensity -1 (none); depth 1 (far)
    for (int i = 0; i < 2; ++i)
        for (int c = 0; c < 3; ++c) clears[i].color.float32[c] = kNoModel;
    clears[2].color.float32[0] = -1.0f;
    clears[kDepthImage].depthStencil = {1.0f, 0};
    VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    begin.renderPass = renderPass_;
    begin.framebuffer = framebuffer_;
    begin.renderArea = {{0, 0}, {uint32_t(width_), uint32_t(height_)}};
    begin.clearValueCount = kImages;
    begin.pClearValues = clears;
    vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
    if (hasMesh) {
        // One draw of the faces seen from free space, the nearest kept (depth LESS). The mesh's triangle order
        // changes from run to run (its heaps are allocated by atomics), so the maps must not depend on which of
        // two triangles at exactly the same depth at a pixel centre came first. Culling back faces is what
        // makes that so: two front faces sharing an edge lie on opposite sides of it on screen, and the
        // rasterizer's fill rule gives a pixel centre on the edge to exactly one of them; the ties that two
        // passes (nearest depth, then the equal-depth triangles blended by MAX) used to resolve were folds at
        // silhouettes, a front face against a back one. It is also what a ray cast of the TSDF finds (the
        // first zero crossing from free space into the surface), and a back face's normal points away from
        // the camera, which the ICP's normal gate rejects anyway. Half the draws of the two-pass maps:
        // 47 -> 25 ms per frame on lavapipe (docs/RESULTS.md, "Tracking").
        VkDeviceSize zero = 0;
        vkCmdBindVertexBuffers(cmd, 0, 1, &mesh.vertices, &zero);
        vkCmdBindIndexBuffer(cmd, mesh.indices, 0, VK_INDEX_TYPE_UINT32);
        const bool mirrored = intrinsics.fx * intrinsics.fy < 0;
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, mirrored ? mirroredPipeline_ : pipeline_);
        vkCmdPushConstants(cmd, pipelineLayout_, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(push), &push);
        vkCmdDrawIndexedIndirect(cmd, mesh.drawIndirect, mesh.drawIndirectOffset, 1, 0);
    }
    vkCmdEndRenderPass(cmd);

    // The render pass left both maps in TRANSFER_SRC_OPTIMAL with their writes visible to transfers.
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {uint32_t(width_), uint32_t(height_), 1};
    vkCmdCopyImageToBuffer(cmd, images_[0], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, positions.handle(), 1, &region);
    vkCmdCopyImageToBuffer(cmd, images_[1], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, normals.handle(), 1, &region);
    vkCmdCopyImageToBuffer(cmd, images_[2], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, intensity.handle(), 1, &region);
    vk::memoryBarrier(cmd);
}

}  // namespace vkmesh::gpu
