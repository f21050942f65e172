// Shared between src/render/mesh_renderer.cpp and the shaders of shaders_render/: the push constants of
// the mesh renderer and its colour modes. Plain C / GLSL subset only.
#ifndef VKMESH_MESH_RENDER_H
#define VKMESH_MESH_RENDER_H

#define RENDER_COLOR_SHADE 0u
#define RENDER_COLOR_NORMAL 1u
#define RENDER_COLOR_AGE 2u

// Vertex input locations (one interleaved binding: position, normal, normalised age).
#define RENDER_LOC_POSITION 0
#define RENDER_LOC_NORMAL 1
#define RENDER_LOC_AGE 2

#ifdef __cplusplus
#include <cstdint>
namespace vkmesh::render {
struct RenderPush {
    float viewProj[16];   // column-major, world -> Vulkan clip space
    float eye[4];         // xyz: camera position (headlight), w unused
    uint32_t colorMode;   // RENDER_COLOR_*
    uint32_t pad[3];
};
static_assert(sizeof(RenderPush) == 96, "push constant layout");
}  // namespace vkmesh::render
#else
layout(push_constant) uniform RenderPush {
    mat4 viewProj;
    vec4 eye;
    uint colorMode;
} pc;
#endif

#endif
