// Shared between src/gpu/tracking/model_maps.cpp and shaders_render/track_model.*: the push constants of the
// model-map draw (the mesh seen by the depth camera, for tracking). Plain C / GLSL subset only.
#ifndef VKMESH_TRACK_MODEL_H
#define VKMESH_TRACK_MODEL_H

// Vertex input locations: vkmesh's Vertex layout (position at 0, normal at 16, colour at 32, stride 36).
#define MODEL_LOC_POSITION 0
#define MODEL_LOC_NORMAL 1
#define MODEL_LOC_COLOR 2   // R8G8B8A8_UNORM at offset 32: alpha 0 = the vertex has no colour

#ifdef __cplusplus
#include <cstdint>
namespace vkmesh::gpu {
struct ModelMapPush {
    float worldToCamera[3][4];  // rows of [R | t]
    float intrinsics[4];        // fx, fy, cx, cy (pixel centres at integer coordinates)
    float viewport[4];          // width, height, near, far (metres)
};
static_assert(sizeof(ModelMapPush) == 80, "push constant layout");
}  // namespace vkmesh::gpu
#else
layout(push_constant) uniform ModelMapPush {
    vec4 worldToCamera[3];
    vec4 intrinsics;
    vec4 viewport;
} pc;
#endif

#endif
