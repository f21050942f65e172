#version 450
// Model maps for tracking, vertex stage: the mesh projected by the depth camera's own pinhole model, so that
// pixel (x, y) of the maps is pixel (x, y) of a depth image taken at that pose. The intrinsics put pixel
// centres at integer coordinates, Vulkan's framebuffer at +0.5; both count rows downwards (no flip; a negative
// fy, as ICL-NUIM's, mirrors the picture and the winding, so nothing is culled). Depth: [near, far] -> [0, 1].
#extension GL_GOOGLE_include_directive : require
#include "track_model.h"

layout(location = MODEL_LOC_POSITION) in vec3 inPosition;
layout(location = MODEL_LOC_NORMAL) in vec3 inNormal;
layout(location = MODEL_LOC_COLOR) in vec4 inColor;

layout(location = 0) out vec3 worldPos;
layout(location = 1) out vec3 worldNormal;
// The vertex colour's intensity (Rec. 601 luma, as the frame's), -1 without colour. A triangle with one
// uncoloured vertex interpolates to below 0 somewhere: the fragment stage then writes "none".
layout(location = 2) out float intensity;

void main() {
    worldPos = inPosition;
    worldNormal = inNormal;
    intensity = inColor.a > 0.0 ? dot(inColor.rgb, vec3(0.299, 0.587, 0.114)) : -4.0;
    // `precise`: the position is computed the same way wherever this shader is compiled (no contraction into
    // fused multiply-adds that one compiler makes and another does not).
    precise vec3 c;
    c.x = dot(pc.worldToCamera[0].xyz, inPosition) + pc.worldToCamera[0].w;
    c.y = dot(pc.worldToCamera[1].xyz, inPosition) + pc.worldToCamera[1].w;
    c.z = dot(pc.worldToCamera[2].xyz, inPosition) + pc.worldToCamera[2].w;
    float width = pc.viewport.x, height = pc.viewport.y, near = pc.viewport.z, far = pc.viewport.w;
    // clip x / w = 2 (u + 0.5) / width - 1 with u = fx x / z + cx, w = z (so the rasterizer divides).
    precise float x = 2.0 * (pc.intrinsics.x * c.x + (pc.intrinsics.z + 0.5) * c.z) / width - c.z;
    precise float y = 2.0 * (pc.intrinsics.y * c.y + (pc.intrinsics.w + 0.5) * c.z) / height - c.z;
    precise float z = far * (c.z - near) / (far - near);
    gl_Position = vec4(x, y, z, c.z);
}
