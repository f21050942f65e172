// Shared between src/render/mesh_renderer.cpp and the shaders of shaders_render/: the push constants of
// the mesh renderer and its colour modes. Plain C / GLSL subset only.
#ifndef VKMESH_MESH_RENDER_H
#define VKMESH_MESH_RENDER_H

#define RENDER_COLOR_SHADE 0u
#define RENDER_COLOR_NORMAL 1u
#define RENDER_COLOR_AGE 2u
#define RENDER_COLOR_RGB 3u   // the vertex colour (fused from the colour images), lightly shaded

// Vertex input locations. One interleaved binding in vkmesh's own Vertex layout (shaders_comp/
// shared_layout.h: position at 0, normal at 16, createdFrame at 28, colour at 32, stride 36), so the renderer draws the
// GPU mesh buffers as they are and host meshes are packed the same way.
#define RENDER_LOC_POSITION 0
#define RENDER_LOC_NORMAL 1
#define RENDER_LOC_CREATED 2
#define RENDER_LOC_COLOR 3

#ifdef __cplusplus
#include <cstdint>
namespace vkmesh::render {
struct RenderPush {
    float viewProj[16];   // column-major, world -> Vulkan clip space
    float eye[4];         // xyz: camera position (headlight), w unused
    uint32_t colorMode;   // RENDER_COLOR_*
    uint32_t newestFrame; // age of a vertex = newestFrame - createdFrame (0 if created later)
    float ageScale;       // normalised age = age * ageScale (1 / the largest age shown)
    uint32_t pad;
};
static_assert(sizeof(RenderPush) == 96, "push constant layout");
}  // namespace vkmesh::render
#else
layout(push_constant) uniform RenderPush {
    mat4 viewProj;
    vec4 eye;
    uint colorMode;
    uint newestFrame;
    float ageScale;
} pc;
#endif

#endif
