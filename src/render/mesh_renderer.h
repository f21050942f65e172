// Headless, offscreen rendering of a triangle mesh with a Vulkan graphics pipeline (classic render pass +
// framebuffer, so Vulkan 1.2 is enough): colour R8G8B8A8_UNORM + depth D32_SFLOAT, one indexed draw, the
// image copied back to the host. Used by `vkmesh render` (see renderMeshFile) and the tests. PNG writing is
// not here (the renderer links no image library): io::writePng in io/png.h.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/types.h"
#include "gpu/gpu_volume.h"
#include "io/ply.h"
#include "render/image.h"
#include "vk/commands.h"
#include "vk/context.h"

namespace vkmesh::render {

struct RenderPush;   // shaders_render/mesh_render.h

enum class ColorMode {
    Shade,   // Phong (headlight + ambient) on a light grey
    Normal,  // vertex normal mapped to RGB: n * 0.5 + 0.5
    Age,     // warm (age 0, red) to cold (oldest, blue), normalised by the mesh's largest age
    Rgb,     // the vertex colours (fused from the colour images), lightly shaded; grey without
    Auto,    // Rgb for a mesh with colours, else Shade (a host mesh; GPU mesh buffers take Shade)
};

constexpr float kVerticalFovDegrees = 60.0f;

// Looks from `eye` at `target` with `up` pointing up in the picture (world z by default).
struct Camera {
    Eigen::Vector3f eye = Eigen::Vector3f::Zero();
    Eigen::Vector3f target = Eigen::Vector3f::Zero();
    Eigen::Vector3f up = Eigen::Vector3f(0, 0, 1);
    float verticalFovDegrees = kVerticalFovDegrees;
};

// The depth sensor's own view: its position, looking along its +z axis with its -y axis up, and the
// vertical field of view of its intrinsics.
Camera sensorCamera(const Pose& cameraToWorld, const Intrinsics& intrinsics);
// Background colour (dark grey), RGBA.
constexpr uint8_t kBackground[4] = {38, 38, 38, 255};

struct RenderOptions {
    int width = 800;
    int height = 600;
    std::optional<Camera> camera;  // none: defaultCamera(mesh, width, height)
    ColorMode color = ColorMode::Shade;
};

// Parses "shade" / "normal" / "age" / "rgb" / "auto"; throws Error naming the value otherwise.
ColorMode parseColorMode(const std::string& text);
// Parses "eye_x,eye_y,eye_z,target_x,target_y,target_z" (6 finite numbers, eye != target); throws Error
// naming the value otherwise.
Camera parseCamera(const std::string& text);
// A three-quarter overview from outside the mesh's bounding box (azimuth 45 degrees, elevation about 35),
// far enough for the bounding sphere to fit the view.
Camera defaultCamera(const Mesh& mesh, int width, int height);
Camera defaultCamera(const Eigen::Vector3f& boundsMin, const Eigen::Vector3f& boundsMax, int width, int height);

// Column-major world -> Vulkan clip-space matrix of the camera (y down, depth 0..1), near/far from the
// mesh bounds as seen from the eye. Exposed for tests.
Eigen::Matrix4f viewProjection(const Camera& camera, const Eigen::Vector3f& boundsMin, const Eigen::Vector3f& boundsMax,
                               int width, int height);

// Owns the graphics pipeline (render pass, layouts, shaders); each render() creates the images of its size.
// The Context's queue must support graphics (lavapipe's and desktop GPUs' first family do).
class MeshRenderer {
public:
    explicit MeshRenderer(const vk::Context& context);
    ~MeshRenderer();
    MeshRenderer(const MeshRenderer&) = delete;
    MeshRenderer& operator=(const MeshRenderer&) = delete;

    // Throws Error for an empty mesh (no vertices or no triangles), an index out of range, inconsistent
    // normals/ages, or an image size outside 1..maxImageDimension2D; Vulkan failures via VKM_CHECK.
    Image render(const Mesh& mesh, const RenderOptions& options);

    // Draws vkmesh's mesh straight from its GPU buffers (no copy through the host): the vertex and index
    // buffers bound as they are, the draw indirect. `boundsMin/Max` bound the scene (near/far planes, and
    // the default camera when options.camera is empty). Follows the contract of api/reconstructor.h: the
    // command buffer starts with recordMeshReadBarrier; `sync` is passed to the submission. Vertex ages
    // are normalised by the number of frames integrated.
    Image render(const gpu::MeshBuffers& mesh, const Eigen::Vector3f& boundsMin, const Eigen::Vector3f& boundsMax,
                 const RenderOptions& options, const vk::SubmitSync& sync = {});

private:
    struct Geometry {
        VkBuffer vertices = VK_NULL_HANDLE, indices = VK_NULL_HANDLE;
        uint32_t indexCount = 0;                 // direct draw, or
        VkBuffer indirect = VK_NULL_HANDLE;      // an indirect one
        VkDeviceSize indirectOffset = 0;
    };
    // Records `prelude` (uploads, barriers), the draw into a new target of the options' size, and the
    // copy of the picture to the host; submits with `sync` and waits.
    Image draw(const Geometry& geometry, const RenderPush& push, int width, int height,
               const std::function<void(VkCommandBuffer)>& prelude, const vk::SubmitSync& sync);
    void release();
    const vk::Context& context_;
    VkRenderPass renderPass_ = VK_NULL_HANDLE;
    VkPipelineLayout pipelineLayout_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
};

// What `vkmesh render` does before writing the PNG (io::writePng, io/png.h, in the vkmesh_io library):
// reads the mesh (PLY) and renders it. Throws Error naming the file for a missing, unreadable or empty mesh.
Image renderMeshFile(const vk::Context& context, const std::filesystem::path& meshPath, const RenderOptions& options);

}  // namespace vkmesh::render
