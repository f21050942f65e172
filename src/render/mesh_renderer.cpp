#include "render/mesh_renderer.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <span>
#include <numbers>
#include <sstream>

#include "../../shaders_render/mesh_render.h"
#include "core/types.h"
#include "vk/buffer.h"
#include "vk/graphics_resources.h"
#include "vk/check.h"
#include "vk/commands.h"

namespace vkmesh::render {
namespace {

constexpr VkFormat kColorFormat = VK_FORMAT_R8G8B8A8_UNORM;
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;

using gpu::Vertex;   // the vertex layout the shaders read (RENDER_LOC_*), vkmesh's own

std::string trim(const std::string& s) {
    size_t a = s.find_first_not_of(" \t");
    size_t b = s.find_last_not_of(" \t");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}


// Per-render Vulkan objects, destroyed in reverse order whatever happens.
struct Target {
    VkDevice device = VK_NULL_HANDLE;
    VkImage color = VK_NULL_HANDLE, depth = VK_NULL_HANDLE;
    VkDeviceMemory colorMemory = VK_NULL_HANDLE, depthMemory = VK_NULL_HANDLE;
    VkImageView colorView = VK_NULL_HANDLE, depthView = VK_NULL_HANDLE;
    VkFramebuffer framebuffer = VK_NULL_HANDLE;
    explicit Target(VkDevice d) : device(d) {}
    Target(const Target&) = delete;
    Target& operator=(const Target&) = delete;
    ~Target() {
        if (framebuffer) vkDestroyFramebuffer(device, framebuffer, nullptr);
        if (depthView) vkDestroyImageView(device, depthView, nullptr);
        if (colorView) vkDestroyImageView(device, colorView, nullptr);
        if (depth) vkDestroyImage(device, depth, nullptr);
        if (color) vkDestroyImage(device, color, nullptr);
        if (depthMemory) vkFreeMemory(device, depthMemory, nullptr);
        if (colorMemory) vkFreeMemory(device, colorMemory, nullptr);
    }
};

void bounds(const Mesh& mesh, Eigen::Vector3f& lo, Eigen::Vector3f& hi) {
    lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    hi = Eigen::Vector3f::Constant(-std::numeric_limits<float>::max());
    for (const auto& p : mesh.positions) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
}

void checkMesh(const Mesh& mesh) {
    const size_t n = mesh.positions.size();
    if (n == 0 || mesh.triangles.empty())
        throw Error("the mesh is empty (" + std::to_string(n) + " vertices, " + std::to_string(mesh.triangles.size()) +
                    " triangles): nothing to render");
    if (!mesh.normals.empty() && mesh.normals.size() != n)
        throw Error("the mesh has " + std::to_string(mesh.normals.size()) + " normals for " + std::to_string(n) + " vertices");
    if (!mesh.vertexAge.empty() && mesh.vertexAge.size() != n)
        throw Error("the mesh has " + std::to_string(mesh.vertexAge.size()) + " ages for " + std::to_string(n) + " vertices");
    if (!mesh.colors.empty() && mesh.colors.size() != n)
        throw Error("the mesh has " + std::to_string(mesh.colors.size()) + " colours for " + std::to_string(n) + " vertices");
    for (const auto& t : mesh.triangles)
        for (uint32_t i : t)
            if (i >= n) throw Error("triangle index " + std::to_string(i) + " out of range (" + std::to_string(n) + " vertices)");
    for (const auto& p : mesh.positions)
        if (!p.allFinite()) throw Error("the mesh has a vertex position that is not finite");
}

// Packs a host mesh into vkmesh's Vertex layout; ages become creation frames counted back from the
// largest age (*newestFrame).
std::vector<Vertex> vertexData(const Mesh& mesh, uint32_t* newestFrame) {
    const size_t n = mesh.positions.size();
    std::vector<Eigen::Vector3f> normals = mesh.normals;
    if (normals.empty()) {  // area-weighted face normals
        normals.assign(n, Eigen::Vector3f::Zero());
        for (const auto& t : mesh.triangles) {
            Eigen::Vector3f fn = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
            for (uint32_t i : t) normals[i] += fn;
        }
        for (auto& v : normals)
            if (v.norm() > 0) v.normalize();
    }
    uint32_t maxAge = 0;
    for (uint32_t a : mesh.vertexAge) maxAge = std::max(maxAge, a);
    *newestFrame = maxAge;
    std::vector<Vertex> out(n);
    for (size_t i = 0; i < n; ++i) {
        const Eigen::Vector3f& p = mesh.positions[i];
        Eigen::Vector3f nn = normals[i].allFinite() ? normals[i] : Eigen::Vector3f::Zero();
        uint32_t color = 0;   // alpha 0: no colour
        if (!mesh.colors.empty()) color = mesh.colors[i][0] | mesh.colors[i][1] << 8 | mesh.colors[i][2] << 16 | 0xFF000000u;
        out[i] = Vertex{p.x(), p.y(), p.z(), 0u, nn.x(), nn.y(), nn.z(), mesh.vertexAge.empty() ? maxAge : maxAge - mesh.vertexAge[i], color};
    }
    return out;
}

RenderPush makePush(const Camera& camera, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, int width, int height,
                    ColorMode color, uint32_t newestFrame, uint32_t largestAge) {
    RenderPush push{};
    Eigen::Matrix4f vp = viewProjection(camera, lo, hi, width, height);
    std::memcpy(push.viewProj, vp.data(), sizeof(push.viewProj));  // Eigen is column-major, like GLSL
    push.eye[0] = camera.eye.x();
    push.eye[1] = camera.eye.y();
    push.eye[2] = camera.eye.z();
    push.colorMode = color == ColorMode::Normal ? RENDER_COLOR_NORMAL
                     : color == ColorMode::Age  ? RENDER_COLOR_AGE
                     : color == ColorMode::Rgb  ? RENDER_COLOR_RGB
                                                : RENDER_COLOR_SHADE;
    push.newestFrame = newestFrame;
    push.ageScale = largestAge ? 1.0f / float(largestAge) : 0.0f;
    return push;
}

void checkImageSize(const vk::Context& context, int width, int height) {
    const uint32_t maxDim = context.properties().limits.maxImageDimension2D;
    if (width < 1 || height < 1 || uint32_t(width) > maxDim || uint32_t(height) > maxDim)
        throw Error("image size " + std::to_string(width) + "x" + std::to_string(height) + " is outside 1.." + std::to_string(maxDim));
}

}  // namespace

ColorMode parseColorMode(const std::string& text) {
    if (text == "shade") return ColorMode::Shade;
    if (text == "normal") return ColorMode::Normal;
    if (text == "age") return ColorMode::Age;
    if (text == "rgb") return ColorMode::Rgb;
    if (text == "auto") return ColorMode::Auto;
    throw Error("unknown colour mode '" + text + "' (expected shade, normal, age, rgb or auto)");
}

Camera parseCamera(const std::string& text) {
    std::vector<float> values;
    std::stringstream stream(text);
    std::string item;
    while (std::getline(stream, item, ',')) {
        std::string s = trim(item);
        size_t used = 0;
        float v = 0;
        try {
            v = std::stof(s, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (s.empty() || used != s.size() || !std::isfinite(v))
            throw Error("bad --camera '" + text + "': '" + item + "' is not a number (expected eye_x,eye_y,eye_z,target_x,target_y,target_z)");
        values.push_back(v);
    }
    if (!text.empty() && text.back() == ',') values.push_back(0), values.push_back(0);  // forces the count error below
    if (values.size() != 6)
        throw Error("bad --camera '" + text + "': expected 6 numbers eye_x,eye_y,eye_z,target_x,target_y,target_z, got " +
                    std::to_string(values.size()));
    Camera c;
    c.eye = {values[0], values[1], values[2]};
    c.target = {values[3], values[4], values[5]};
    if ((c.target - c.eye).norm() < 1e-9f) throw Error("bad --camera '" + text + "': eye and target are the same point");
    return c;
}

Camera defaultCamera(const Mesh& mesh, int width, int height) {
    if (mesh.positions.empty()) throw Error("the mesh is empty: no default camera");
    Eigen::Vector3f lo, hi;
    bounds(mesh, lo, hi);
    return defaultCamera(lo, hi, width, height);
}

Camera sensorCamera(const Pose& cameraToWorld, const Intrinsics& intrinsics) {
    Eigen::Matrix3f r = cameraToWorld.block<3, 3>(0, 0).cast<float>();
    Camera c;
    c.eye = cameraToWorld.block<3, 1>(0, 3).cast<float>();
    c.target = c.eye + r.col(2);
    c.up = -r.col(1);
    if (intrinsics.height > 0 && intrinsics.fy != 0)
        c.verticalFovDegrees = 2.0f * std::atan(0.5f * float(intrinsics.height) / std::abs(intrinsics.fy)) * 180.0f / std::numbers::pi_v<float>;
    return c;
}

Camera defaultCamera(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, int width, int height) {
    Eigen::Vector3f center = 0.5f * (lo + hi);
    float radius = std::max(0.5f * (hi - lo).norm(), 1e-3f);
    const float halfV = kVerticalFovDegrees * 0.5f * std::numbers::pi_v<float> / 180.0f;
    const float aspect = float(width) / float(std::max(height, 1));
    const float halfH = std::atan(std::tan(halfV) * aspect);
    const float distance = 1.05f * radius / std::sin(std::min(halfV, halfH));  // > radius: outside the box
    Camera c;
    c.target = center;
    c.eye = center + distance * Eigen::Vector3f(1.0f, -1.0f, 1.0f).normalized();
    return c;
}

Eigen::Matrix4f viewProjection(const Camera& camera, const Eigen::Vector3f& boundsMin, const Eigen::Vector3f& boundsMax,
                               int width, int height) {
    Eigen::Vector3f f = camera.target - camera.eye;
    if (f.norm() <= 0) throw Error("camera eye and target are the same point");
    f.normalize();
    Eigen::Vector3f up = camera.up.norm() > 0 ? camera.up.normalized() : Eigen::Vector3f(0, 0, 1);
    if (f.cross(up).norm() < 1e-4f) up = std::abs(f.y()) < 0.9f ? Eigen::Vector3f(0, 1, 0) : Eigen::Vector3f(1, 0, 0);  // up along the view
    Eigen::Vector3f s = f.cross(up).normalized();
    Eigen::Vector3f u = s.cross(f);
    Eigen::Matrix4f view = Eigen::Matrix4f::Identity();
    view.block<1, 3>(0, 0) = s.transpose();
    view.block<1, 3>(1, 0) = u.transpose();
    view.block<1, 3>(2, 0) = -f.transpose();
    view(0, 3) = -s.dot(camera.eye);
    view(1, 3) = -u.dot(camera.eye);
    view(2, 3) = f.dot(camera.eye);

    // Near and far: the range of depths of the bounding box's corners along the view direction.
    float dMin = std::numeric_limits<float>::max(), dMax = -std::numeric_limits<float>::max();
    for (int i = 0; i < 8; ++i) {
        Eigen::Vector3f corner((i & 1) ? boundsMax.x() : boundsMin.x(), (i & 2) ? boundsMax.y() : boundsMin.y(),
                               (i & 4) ? boundsMax.z() : boundsMin.z());
        float d = f.dot(corner - camera.eye);
        dMin = std::min(dMin, d);
        dMax = std::max(dMax, d);
    }
    float farZ = dMax > 0 ? dMax * 1.01f + 1e-4f : 1.0f;
    float nearZ = std::max(dMin * 0.99f, farZ * 1e-4f);

    if (!(camera.verticalFovDegrees > 0.0f && camera.verticalFovDegrees < 180.0f))
        throw Error("camera field of view " + std::to_string(camera.verticalFovDegrees) + " degrees is outside (0, 180)");
    const float t = std::tan(camera.verticalFovDegrees * 0.5f * std::numbers::pi_v<float> / 180.0f);
    const float aspect = float(width) / float(height);
    Eigen::Matrix4f proj = Eigen::Matrix4f::Zero();
    proj(0, 0) = 1.0f / (t * aspect);
    proj(1, 1) = -1.0f / t;  // Vulkan: framebuffer y points down
    proj(2, 2) = farZ / (nearZ - farZ);
    proj(2, 3) = nearZ * farZ / (nearZ - farZ);
    proj(3, 2) = -1.0f;
    return proj * view;
}

MeshRenderer::MeshRenderer(const vk::Context& context) : context_(context) {
    uint32_t familyCount = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(context.physicalDevice(), &familyCount, nullptr);
    std::vector<VkQueueFamilyProperties> families(familyCount);
    vkGetPhysicalDeviceQueueFamilyProperties(context.physicalDevice(), &familyCount, families.data());
    if (context.queueFamily() >= familyCount || !(families[context.queueFamily()].queueFlags & VK_QUEUE_GRAPHICS_BIT))
        throw Error("device '" + context.info().name + "': vkmesh's queue does not support graphics, cannot render");
    VkFormatProperties depthProps{};
    vkGetPhysicalDeviceFormatProperties(context.physicalDevice(), kDepthFormat, &depthProps);
    if (!(depthProps.optimalTilingFeatures & VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT))
        throw Error("device '" + context.info().name + "' cannot use D32_SFLOAT as a depth attachment");

    VkDevice device = context.device();
    VkShaderModule vert = VK_NULL_HANDLE, frag = VK_NULL_HANDLE;
    try {
        VkAttachmentDescription attachments[2]{};
        attachments[0].format = kColorFormat;
        attachments[0].samples = VK_SAMPLE_COUNT_1_BIT;
        attachments[0].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        attachments[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        attachments[0].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        attachments[0].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        attachments[0].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        attachments[0].finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        attachments[1].format = kDepthFormat;
        attachments[1].samples = VK_SAMPLE_COUNT_1_BIT;
        attachments[1].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        attachments[1].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        attachments[1].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        attachments[1].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        attachments[1].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        attachments[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
        VkAttachmentReference colorRef{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
        VkAttachmentReference depthRef{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
        VkSubpassDescription subpass{};
        subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
        subpass.colorAttachmentCount = 1;
        subpass.pColorAttachments = &colorRef;
        subpass.pDepthStencilAttachment = &depthRef;
        VkSubpassDependency deps[2]{};
        // Before: the attachments' layout transitions and clears come after whatever used them last.
        deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
        deps[0].dstSubpass = 0;
        deps[0].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                               VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
        deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                               VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
        deps[0].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                                VK_ACCESS_TRANSFER_READ_BIT;
        deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT |
                                VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        // After: the colour image is copied to the host buffer.
        deps[1].srcSubpass = 0;
        deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
        deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
        deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
        deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        VkRenderPassCreateInfo rpInfo{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
        rpInfo.attachmentCount = 2;
        rpInfo.pAttachments = attachments;
        rpInfo.subpassCount = 1;
        rpInfo.pSubpasses = &subpass;
        rpInfo.dependencyCount = 2;
        rpInfo.pDependencies = deps;
        VKM_CHECK(vkCreateRenderPass(device, &rpInfo, nullptr, &renderPass_));

        VkPushConstantRange range{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(RenderPush)};
        VkPipelineLayoutCreateInfo layoutInfo{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
        layoutInfo.pushConstantRangeCount = 1;
        layoutInfo.pPushConstantRanges = &range;
        VKM_CHECK(vkCreatePipelineLayout(device, &layoutInfo, nullptr, &pipelineLayout_));

        vert = vk::createGraphicsShaderModule(device, "mesh.vert");
        frag = vk::createGraphicsShaderModule(device, "mesh.frag");
        VkPipelineShaderStageCreateInfo stages[2]{};
        stages[0].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
        stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
        stages[0].module = vert;
        stages[0].pName = "main";
        stages[1].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
        stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
        stages[1].module = frag;
        stages[1].pName = "main";

        VkVertexInputBindingDescription binding{0, sizeof(Vertex), VK_VERTEX_INPUT_RATE_VERTEX};
        VkVertexInputAttributeDescription attributes[4] = {
            {RENDER_LOC_POSITION, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, px)},
            {RENDER_LOC_NORMAL, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, nx)},
            {RENDER_LOC_CREATED, 0, VK_FORMAT_R32_UINT, offsetof(Vertex, createdFrame)},
            {RENDER_LOC_COLOR, 0, VK_FORMAT_R8G8B8A8_UNORM, offsetof(Vertex, color)},
        };
        static_assert(offsetof(Vertex, px) == gpu::MeshBuffers::kPositionOffset && offsetof(Vertex, nx) == gpu::MeshBuffers::kNormalOffset &&
                      offsetof(Vertex, createdFrame) == gpu::MeshBuffers::kCreatedFrameOffset &&
                      offsetof(Vertex, color) == gpu::MeshBuffers::kColorOffset);
        VkPipelineVertexInputStateCreateInfo vertexInput{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
        vertexInput.vertexBindingDescriptionCount = 1;
        vertexInput.pVertexBindingDescriptions = &binding;
        vertexInput.vertexAttributeDescriptionCount = 4;
        vertexInput.pVertexAttributeDescriptions = attributes;
        VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
        assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
        VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
        viewport.viewportCount = 1;
        viewport.scissorCount = 1;
        VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
        raster.polygonMode = VK_POLYGON_MODE_FILL;
        raster.cullMode = VK_CULL_MODE_NONE;  // open meshes: back faces drawn (darker, see mesh.frag)
        // Triangles are counter-clockwise seen from outside; with the y flip in the projection that is
        // VK_FRONT_FACE_COUNTER_CLOCKWISE in Vulkan's framebuffer coordinates.
        raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
        raster.lineWidth = 1.0f;
        VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
        multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
        VkPipelineDepthStencilStateCreateInfo depthState{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
        depthState.depthTestEnable = VK_TRUE;
        depthState.depthWriteEnable = VK_TRUE;
        depthState.depthCompareOp = VK_COMPARE_OP_LESS;
        VkPipelineColorBlendAttachmentState blendAttachment{};
        blendAttachment.colorWriteMask =
            VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
        VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
        blend.attachmentCount = 1;
        blend.pAttachments = &blendAttachment;
        VkDynamicState dynamicStates[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
        VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
        dynamic.dynamicStateCount = 2;
        dynamic.pDynamicStates = dynamicStates;

        VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
        info.stageCount = 2;
        info.pStages = stages;
        info.pVertexInputState = &vertexInput;
        info.pInputAssemblyState = &assembly;
        info.pViewportState = &viewport;
        info.pRasterizationState = &raster;
        info.pMultisampleState = &multisample;
        info.pDepthStencilState = &depthState;
        info.pColorBlendState = &blend;
        info.pDynamicState = &dynamic;
        info.layout = pipelineLayout_;
        info.renderPass = renderPass_;
        info.subpass = 0;
        VKM_CHECK(vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline_));
    } catch (...) {
        if (vert) vkDestroyShaderModule(device, vert, nullptr);
        if (frag) vkDestroyShaderModule(device, frag, nullptr);
        release();
        throw;
    }
    vkDestroyShaderModule(device, vert, nullptr);
    vkDestroyShaderModule(device, frag, nullptr);
}

MeshRenderer::~MeshRenderer() { release(); }

void MeshRenderer::release() {
    VkDevice device = context_.device();
    if (pipeline_) vkDestroyPipeline(device, pipeline_, nullptr);
    if (pipelineLayout_) vkDestroyPipelineLayout(device, pipelineLayout_, nullptr);
    if (renderPass_) vkDestroyRenderPass(device, renderPass_, nullptr);
    pipeline_ = VK_NULL_HANDLE;
    pipelineLayout_ = VK_NULL_HANDLE;
    renderPass_ = VK_NULL_HANDLE;
}

Image MeshRenderer::render(const Mesh& mesh, const RenderOptions& options) {
    checkMesh(mesh);
    checkImageSize(context_, options.width, options.height);
    const int width = options.width, height = options.height;
    const Camera camera = options.camera ? *options.camera : defaultCamera(mesh, width, height);
    Eigen::Vector3f lo, hi;
    bounds(mesh, lo, hi);
    uint32_t newestFrame = 0;
    std::vector<Vertex> vertices = vertexData(mesh, &newestFrame);
    const ColorMode color = options.color != ColorMode::Auto ? options.color : mesh.colors.empty() ? ColorMode::Shade : ColorMode::Rgb;
    RenderPush push = makePush(camera, lo, hi, width, height, color, newestFrame, newestFrame);

    // Geometry: staged and copied to device-local buffers in the same command buffer as the draw.
    const VkDeviceSize vertexBytes = vertices.size() * sizeof(Vertex);
    const VkDeviceSize indexBytes = mesh.triangles.size() * 3 * sizeof(uint32_t);
    vk::Buffer vertexStaging(context_, vertexBytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::Upload, "render vertices (staging)");
    vk::Buffer indexStaging(context_, indexBytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, vk::MemoryUse::Upload, "render indices (staging)");
    std::memcpy(vertexStaging.mapped(), vertices.data(), vertexBytes);
    std::memcpy(indexStaging.mapped(), mesh.triangles.data(), indexBytes);
    vk::Buffer vertexBuffer(context_, vertexBytes, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                            vk::MemoryUse::Device, "render vertices");
    vk::Buffer indexBuffer(context_, indexBytes, VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                           vk::MemoryUse::Device, "render indices");
    Geometry geometry;
    geometry.vertices = vertexBuffer.handle();
    geometry.indices = indexBuffer.handle();
    geometry.indexCount = uint32_t(mesh.triangles.size() * 3);
    auto upload = [&](VkCommandBuffer cmd) {
        VkBufferCopy vertexCopy{0, 0, vertexBytes}, indexCopy{0, 0, indexBytes};
        vkCmdCopyBuffer(cmd, vertexStaging.handle(), vertexBuffer.handle(), 1, &vertexCopy);
        vkCmdCopyBuffer(cmd, indexStaging.handle(), indexBuffer.handle(), 1, &indexCopy);
        VkMemoryBarrier toVertexInput{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        toVertexInput.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        toVertexInput.dstAccessMask = VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_INDEX_READ_BIT;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_VERTEX_INPUT_BIT, 0, 1, &toVertexInput, 0,
                             nullptr, 0, nullptr);
    };
    return draw(geometry, push, width, height, upload, {});
}

Image MeshRenderer::render(const gpu::MeshBuffers& mesh, const Eigen::Vector3f& boundsMin, const Eigen::Vector3f& boundsMax,
                           const RenderOptions& options, const vk::SubmitSync& sync) {
    if (!mesh.vertices || !mesh.indices || !mesh.drawIndirect)
        throw Error("no mesh buffers to render: nothing has been integrated and published yet");
    if (!boundsMin.allFinite() || !boundsMax.allFinite() || (boundsMax - boundsMin).minCoeff() < 0.0f)
        throw Error("render: the scene bounds are empty or not finite");
    checkImageSize(context_, options.width, options.height);
    const int width = options.width, height = options.height;
    const Camera camera = options.camera ? *options.camera : defaultCamera(boundsMin, boundsMax, width, height);
    RenderPush push = makePush(camera, boundsMin, boundsMax, width, height, options.color, mesh.frame, std::max(mesh.frame, 2u) - 1);
    Geometry geometry;
    geometry.vertices = mesh.vertices;
    geometry.indices = mesh.indices;
    geometry.indirect = mesh.drawIndirect;
    geometry.indirectOffset = mesh.drawIndirectOffset;
    return draw(geometry, push, width, height, [](VkCommandBuffer cmd) { gpu::recordMeshReadBarrier(cmd); }, sync);
}

Image MeshRenderer::draw(const Geometry& geometry, const RenderPush& push, int width, int height,
                         const std::function<void(VkCommandBuffer)>& prelude, const vk::SubmitSync& sync) {
    const VkDeviceSize imageBytes = VkDeviceSize(width) * VkDeviceSize(height) * 4;
    vk::Buffer readback(context_, imageBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::Readback, "render image (readback)");

    Target target(context_.device());
    vk::createAttachmentImage(context_, width, height, kColorFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                VK_IMAGE_ASPECT_COLOR_BIT, target.color, target.colorMemory, target.colorView);
    vk::createAttachmentImage(context_, width, height, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT,
                target.depth, target.depthMemory, target.depthView);
    VkImageView views[2] = {target.colorView, target.depthView};
    VkFramebufferCreateInfo fbInfo{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fbInfo.renderPass = renderPass_;
    fbInfo.attachmentCount = 2;
    fbInfo.pAttachments = views;
    fbInfo.width = uint32_t(width);
    fbInfo.height = uint32_t(height);
    fbInfo.layers = 1;
    VKM_CHECK(vkCreateFramebuffer(context_.device(), &fbInfo, nullptr, &target.framebuffer));

    vk::CommandRecorder recorder(context_);
    VkCommandBuffer cmd = recorder.begin();
    prelude(cmd);

    VkClearValue clears[2]{};
    for (int k = 0; k < 4; ++k) clears[0].color.float32[k] = float(kBackground[k]) / 255.0f;
    clears[1].depthStencil = {1.0f, 0};
    VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    begin.renderPass = renderPass_;
    begin.framebuffer = target.framebuffer;
    begin.renderArea = {{0, 0}, {uint32_t(width), uint32_t(height)}};
    begin.clearValueCount = 2;
    begin.pClearValues = clears;
    vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_);
    VkViewport vpState{0.0f, 0.0f, float(width), float(height), 0.0f, 1.0f};
    VkRect2D scissor{{0, 0}, {uint32_t(width), uint32_t(height)}};
    vkCmdSetViewport(cmd, 0, 1, &vpState);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
    vkCmdPushConstants(cmd, pipelineLayout_, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(push), &push);
    VkDeviceSize zero = 0;
    vkCmdBindVertexBuffers(cmd, 0, 1, &geometry.vertices, &zero);
    vkCmdBindIndexBuffer(cmd, geometry.indices, 0, VK_INDEX_TYPE_UINT32);
    if (geometry.indirect)
        vkCmdDrawIndexedIndirect(cmd, geometry.indirect, geometry.indirectOffset, 1, 0);
    else
        vkCmdDrawIndexed(cmd, geometry.indexCount, 1, 0, 0, 0);
    vkCmdEndRenderPass(cmd);

    // The render pass left the colour image in TRANSFER_SRC_OPTIMAL, its writes visible to transfers.
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {uint32_t(width), uint32_t(height), 1};
    vkCmdCopyImageToBuffer(cmd, target.color, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback.handle(), 1, &region);
    VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    toHost.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &toHost, 0, nullptr, 0, nullptr);
    recorder.submitAndWait(sync);

    readback.invalidate();
    Image image;
    image.width = width;
    image.height = height;
    image.rgba.resize(imageBytes);
    std::memcpy(image.rgba.data(), readback.mapped(), imageBytes);
    return image;
}

Image renderMeshFile(const vk::Context& context, const std::filesystem::path& meshPath, const RenderOptions& options) {
    if (!std::filesystem::exists(meshPath)) throw Error("mesh file " + meshPath.string() + " does not exist");
    Mesh mesh = readPly(meshPath);  // throws Error naming the file when it is unreadable
    if (mesh.positions.empty() || mesh.triangles.empty())
        throw Error("mesh file " + meshPath.string() + " is empty (" + std::to_string(mesh.positions.size()) + " vertices, " +
                    std::to_string(mesh.triangles.size()) + " triangles): nothing to render");
    MeshRenderer renderer(context);
    return renderer.render(mesh, options);
}

}  // namespace vkmesh::render
